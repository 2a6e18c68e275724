#pragma once
/// The study-file visitor of a described struct (describe.h): reads the [analyses.<name>] table into
/// it. Every key of the table must be a field's key (or in `extra_keys`); each value is checked
/// against its field's kind and limits-table range, with the file, key, value, expectation and line.

#include <string>
#include <vector>

#include "engine/common/describe.h"
#include "engine/common/toml_reader.h"

namespace gesweep {

/// The study keys of `object`'s fields (scope kEverywhere or kStudyOnly), in field order.
template <class T>
std::vector<std::string> StudyKeys(const T& object) {
  std::vector<std::string> keys;
  for (const FieldRecord& r : ListFields(object)) {
    if (InScope(r.attributes, true) && r.kind != FieldKind::kArray) keys.emplace_back(r.attributes.key);
  }
  return keys;
}

namespace describe_detail {

struct TomlReader {
  const TomlSection* settings;
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (!InScope(a, true)) return;
    const std::string_view key = a.key;
    U& value = *field.value();
    if constexpr (std::same_as<U, bool>) {
      if (const auto b = settings->OptionalBool(key)) value = *b;
    } else if constexpr (NamedEnum<U>) {
      if (const auto text = settings->OptionalString(key)) {
        const auto parsed = ParseEnum<U>(*text);
        if (!parsed) settings->Fail(key, "\"" + *text + "\"", "expected " + EnumChoices<U>());
        value = *parsed;
      }
    } else if constexpr (IntegerValue<U>) {
      if (const auto i = settings->OptionalInteger(key)) value = static_cast<U>(*i);
    } else if constexpr (std::floating_point<U>) {
      const auto number =
          a.limit.empty() ? settings->OptionalNumber(key) : settings->OptionalLimitedNumber(key, a.limit);
      if (number) value = *number * a.scale;
    } else if constexpr (std::same_as<U, std::string>) {
      if (const auto text = settings->OptionalString(key)) value = *text;
    }  // an array field is a result, never a setting
  }
};

}  // namespace describe_detail

/// Reads every study field of `object` present in `settings` (absent ones keep their value, the
/// default). Throws InputError for an unknown key (neither a field nor in `extra_keys`), a value of
/// the wrong kind, a number outside its range or a name not among an enum's.
template <class T>
void ReadFields(const TomlSection& settings, T& object, const std::vector<std::string>& extra_keys = {}) {
  std::vector<std::string> allowed = StudyKeys(object);
  allowed.insert(allowed.end(), extra_keys.begin(), extra_keys.end());
  settings.RejectUnknownKeys(allowed);
  describe_detail::TomlReader reader{&settings};
  object.Describe(reader);
}

}  // namespace gesweep
