#pragma once
/// Typed, validating access to a parsed TOML document. Every failure throws InputError naming the
/// file, the dotted key, the value, what was expected, and the line toml++ knows.

#include <toml++/toml.h>

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/errors.h"

namespace gesweep {

/// The name in `candidates` closest to `key` by edit distance, when close enough to be a likely
/// misspelling (distance ≤ max(2, |key|/3)); empty otherwise.
std::string NearestName(std::string_view key, const std::vector<std::string>& candidates);

/// Reads a whole text file; throws InputError (source = path) when it cannot be read.
std::string ReadTextFile(const std::filesystem::path& path, std::string_view what);

/// Whether a number's text is past a double's range: "" when it is not (or is no number), else why
/// ("is past the largest magnitude a double can hold (about 1.8e308)").
std::string MagnitudeProblem(const std::string& token);

/// Parses TOML text; a syntax error becomes an InputError with its line (a number past a double's
/// magnitude is named as such).
toml::table ParseToml(std::string_view text, const std::string& source);

/// A view on one TOML table with its dotted prefix, for error messages.
class TomlSection {
 public:
  TomlSection(const toml::table& table, std::string source, std::string prefix)
      : table_(&table), source_(std::move(source)), prefix_(std::move(prefix)) {}

  /// Dotted key of a child, e.g. "geometry.wingspan_m".
  std::string KeyOf(std::string_view key) const;
  /// Line of a child node, or of this table when the child is missing; 0 when unknown.
  int LineOf(std::string_view key) const;
  const std::string& source() const { return source_; }
  const toml::table& table() const { return *table_; }
  bool Has(std::string_view key) const { return table_->contains(key); }

  /// Throws for any key not in `allowed`, suggesting the nearest allowed one.
  void RejectUnknownKeys(const std::vector<std::string>& allowed) const;

  /// A required sub-table.
  TomlSection Section(std::string_view key) const;
  std::optional<TomlSection> OptionalSection(std::string_view key) const;

  /// A required finite number (integers are accepted).
  double Number(std::string_view key) const;
  /// A required finite number > 0.
  double PositiveNumber(std::string_view key) const;
  std::optional<double> OptionalNumber(std::string_view key) const;
  /// An optional number within the entry `limit_name` of the limits table (input_limits.h).
  std::optional<double> OptionalLimitedNumber(std::string_view key, std::string_view limit_name) const;
  std::string String(std::string_view key) const;
  std::optional<std::string> OptionalString(std::string_view key) const;
  std::optional<bool> OptionalBool(std::string_view key) const;
  std::optional<long long> OptionalInteger(std::string_view key) const;
  /// A required array of finite numbers.
  std::vector<double> NumberArray(std::string_view key) const;

  /// Throws InputError for `key` with the given value text and expectation.
  [[noreturn]] void Fail(std::string_view key, std::string value, std::string expected) const;

 private:
  const toml::node* Node(std::string_view key) const;
  const toml::table* table_;
  std::string source_;
  std::string prefix_;
};

/// Renders a TOML node briefly for an error message (e.g. `"abc"`, `-1`, `[...]`).
std::string DescribeNode(const toml::node& node);

}  // namespace gesweep
