#pragma once
/// The output visitors of a described struct (engine/common/describe.h) for `simulate` and `land`:
/// a JSON object and a CSV header and row, each field under its key, numbers in the key's unit.
/// Fields marked NotInOutput are left out; text fields are left out of CSV (they may hold commas);
/// an array field is a JSON array with a "<key>_names" array beside it, and one CSV column per
/// component (prefix + component name).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/cli/json_util.h"
#include "engine/cli/record_json.h"
#include "engine/common/describe.h"
#include "engine/common/described_values.h"

namespace gesweep::cli {

namespace describe_detail {

struct CsvHeaderWriter {
  std::string out;
  void Add(std::string_view name) { out += (out.empty() ? "" : ",") + std::string(name); }
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (!a.in_output || std::same_as<U, std::string>) return;
    if constexpr (DoubleArray<U>) {
      for (const FieldComponent& c : a.components) Add(std::string(a.component_prefix) + std::string(c.name));
    } else {
      Add(a.key);
    }
  }
};

template <class Format>
struct CsvRowWriter {
  Format* number;
  std::string out;
  bool first = true;
  void Add(const std::string& text) {
    out += (first ? "" : ",") + text;
    first = false;
  }
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (!a.in_output) return;
    const U& v = *field.value();
    if constexpr (std::same_as<U, bool>) {
      Add(v ? "true" : "false");
    } else if constexpr (IntegerValue<U>) {
      Add(std::to_string(v));
    } else if constexpr (NamedEnum<U>) {
      Add(std::string(ToString(v)));
    } else if constexpr (std::floating_point<U>) {
      Add((*number)(v / a.scale));
    } else if constexpr (DoubleArray<U>) {
      for (int c = 0; c < static_cast<int>(v.size()); ++c) Add((*number)(v[c]));
    }
  }
};

}  // namespace describe_detail

/// Every output field of `object`: {key: value}. Non-finite numbers are null. `Json` may be
/// nlohmann::ordered_json, which keeps the fields' order.
template <class T, class Json = nlohmann::json>
Json FieldsJson(const T& object) {
  Json out = Json::object();
  JsonRecordSink<Json> sink{&out};  // engine/cli/record_json.h: VisitOutputs' sink too
  VisitOutputs(object, sink);
  return out;
}

/// The CSV header of `T`'s output fields (no line end).
template <class T>
std::string CsvHeader(const T& object) {
  describe_detail::CsvHeaderWriter header;
  DescribeConst(object, header);
  return header.out;
}

/// The CSV row of `object` (no line end); `number` formats a double.
template <class T, class Format>
std::string CsvRow(const T& object, Format number) {
  describe_detail::CsvRowWriter<Format> row{&number, {}, true};
  DescribeConst(object, row);
  return row.out;
}

}  // namespace gesweep::cli
