#pragma once
/// One table of names per enum, from which come its printing, its parsing and the list of choices an
/// error message offers (docs/architecture.md, "Describe once").
///
/// An enum opts in by declaring its table next to its declaration, in one statement:
///
///     enum class IntegratorKind { kRk4, kDopri5 };
///     GESWEEP_ENUM_NAMES(IntegratorKind, {kRk4, "rk4"}, {kDopri5, "dopri5"});
///
/// (the specialization `EnumNames<IntegratorKind>` with `kTable`; the enumerators are in scope), and
/// then `ToString(kind)`, `ParseEnum<IntegratorKind>("rk4")` and `EnumChoices<IntegratorKind>()`
/// ("rk4 or dopri5") all read that one table.

#include <concepts>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/errors.h"

namespace gesweep {

/// One value of an enum and its name in study files, CLI flags and archives.
template <class E>
struct EnumName {
  E value;
  std::string_view name;
};

/// Specialize with `static constexpr EnumName<E> kTable[] = {...}` listing every value once.
template <class E>
struct EnumNames;

/// Declares the names table of enum `E` (at namespace scope, in E's namespace): the specialization
/// `EnumNames<E>` whose `kTable` lists the `{value, "name"}` pairs given, with E's enumerators in scope
/// (`{kRk4, "rk4"}` for `{IntegratorKind::kRk4, "rk4"}`).
#define GESWEEP_ENUM_NAMES(E, ...)                         \
  template <>                                              \
  struct EnumNames<E> {                                    \
    using enum E;                                          \
    static constexpr EnumName<E> kTable[] = {__VA_ARGS__}; \
  }

/// An enum with a names table.
template <class E>
concept NamedEnum = std::is_enum_v<E> && requires {
  EnumNames<E>::kTable;
};

/// The name of `value`. Every value is in the table (GESWEEP_UNREACHABLE otherwise: a broken table).
template <NamedEnum E>
constexpr std::string_view ToString(E value) {
  for (const auto& entry : EnumNames<E>::kTable) {
    if (entry.value == value) return entry.name;
  }
  GESWEEP_UNREACHABLE();
}

/// The value named `text` exactly; nullopt for any other text.
template <NamedEnum E>
constexpr std::optional<E> ParseEnum(std::string_view text) {
  for (const auto& entry : EnumNames<E>::kTable) {
    if (entry.name == text) return entry.value;
  }
  return std::nullopt;
}

/// The names in table order for a message: "a", "a or b", "a, b or c".
template <NamedEnum E>
std::string EnumChoices() {
  std::string out;
  const auto& table = EnumNames<E>::kTable;
  const std::size_t n = std::size(table);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) out += (i + 1 == n) ? " or " : ", ";
    out += table[i].name;
  }
  return out;
}

/// The names of an enum's codes 0, 1, ... (the levels of its archive column, of a choice parameter
/// in the catalogue): every value in the table, ordered by its underlying value, which must run
/// 0..n-1.
template <NamedEnum E>
std::vector<std::string> EnumLevels() {
  const auto& table = EnumNames<E>::kTable;
  std::vector<std::string> levels(std::size(table));
  for (const auto& entry : table) {
    const auto code = static_cast<std::size_t>(entry.value);
    GESWEEP_DEMAND(code < levels.size() && levels[code].empty());
    levels[code] = std::string(entry.name);
  }
  return levels;
}

/// The value whose code (underlying value, the index in EnumLevels) is `code`: a choice parameter's
/// level code as the enum. `code` is one of the levels' (GESWEEP_DEMAND otherwise: the study parser
/// checks codes against the levels).
template <NamedEnum E>
E EnumAt(double code) {
  GESWEEP_DEMAND(code >= 0 && code < static_cast<double>(std::size(EnumNames<E>::kTable)) &&
                 code == static_cast<double>(static_cast<std::size_t>(code)));
  return static_cast<E>(static_cast<std::size_t>(code));
}

}  // namespace gesweep
