#pragma once
/// What the front ends' visitors of a described struct (describe.h) share: which fields a person sets,
/// and the output fields' values by kind, in the key's unit. The command line's JSON
/// (engine/cli/described_output.h) and the Python module's dicts (engine/python/module.cc) are sinks of
/// VisitOutputs; its flags (engine/cli/described_flags.h) and keyword arguments read SettingValue fields.

#include <concepts>
#include <string>
#include <vector>

#include "engine/common/describe.h"

namespace gesweep {

/// A field a person sets (a flag, a keyword argument): a bool, a named enum, an integer (a seed) or a
/// number; never a result's array or text.
template <class U>
concept SettingValue = std::same_as<U, bool> || NamedEnum<U> || IntegerValue<U> || std::floating_point<U>;

namespace describe_detail {

template <class Sink>
struct OutputVisitor {
  Sink* sink;
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (!a.in_output) return;
    const std::string key(a.key);
    const U& v = *field.value();
    if constexpr (std::same_as<U, bool> || IntegerValue<U> || std::same_as<U, std::string>) {
      sink->Plain(key, v);
    } else if constexpr (NamedEnum<U>) {
      sink->Plain(key, std::string(ToString(v)));
    } else if constexpr (std::floating_point<U>) {
      sink->Number(key, v / a.scale);
    } else {
      static_assert(DoubleArray<U>);
      const int size = static_cast<int>(v.size());
      std::vector<double> values;
      values.reserve(static_cast<std::size_t>(size));
      for (int c = 0; c < size; ++c) values.push_back(v[c] / a.scale);
      std::vector<std::string> names;
      names.reserve(a.components.size());
      for (const FieldComponent& component : a.components) names.emplace_back(component.name);
      if (a.named_components) {
        sink->NamedNumbers(key, names, values);  // a setting's array: keyed by component
      } else {
        sink->Array(key, values, names);
      }
    }
  }
};

}  // namespace describe_detail

/// Calls, for each output field of `object` (in_output) in order, with the field's key:
/// - `sink.Plain(key, value)`: a bool, an integer or a text as it is, an enum as its name (std::string);
/// - `sink.Number(key, value)`: a number in the key's unit (struct value / scale);
/// - `sink.Array(key, values, names)`: a result's array: its values and its components' names;
/// - `sink.NamedNumbers(key, names, values)`: a setting's array (named_components), keyed by name.
template <class T, class Sink>
void VisitOutputs(const T& object, Sink& sink) {
  describe_detail::OutputVisitor<Sink> visitor{&sink};
  DescribeConst(object, visitor);
}

}  // namespace gesweep
