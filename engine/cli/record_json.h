#pragma once
/// The command line's sink of the records of engine/analyses/records.h: a JSON object (nlohmann's
/// json or ordered_json), NaN as null, a complex number as [re, im], a range as [low, high]. The
/// Python module renders the same records as dicts (engine/python/support.h, DictRecordSink).

#include <complex>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "engine/cli/json_util.h"

namespace gesweep::cli {

template <class Json>
struct JsonRecordSink {
  Json* out;

  static Json Num(double value) { return Json(JsonNumber(value)); }

  template <class X>
  void Plain(const std::string& key, const X& value) {
    (*out)[key] = value;
  }
  void Number(const std::string& key, double value) { (*out)[key] = Num(value); }
  void Array(const std::string& key, const std::vector<double>& values,
             const std::vector<std::string>& names) {
    Numbers(key, values);
    (*out)[key + "_names"] = names;
  }
  void Null(const std::string& key) { (*out)[key] = nullptr; }
  static Json ComplexJson(std::complex<double> z) {
    Json pair = Json::array();
    pair.push_back(Num(z.real()));
    pair.push_back(Num(z.imag()));
    return pair;
  }
  void Complex(const std::string& key, std::complex<double> z) { (*out)[key] = ComplexJson(z); }
  void Complexes(const std::string& key, const std::vector<std::complex<double>>& values) {
    Json list = Json::array();
    for (const auto z : values) list.push_back(ComplexJson(z));
    (*out)[key] = std::move(list);
  }
  void Numbers(const std::string& key, std::span<const double> values) {
    Json list = Json::array();
    for (const double v : values) list.push_back(Num(v));
    (*out)[key] = std::move(list);
  }
  void Texts(const std::string& key, const std::vector<std::string>& values) { (*out)[key] = values; }
  void Range(const std::string& key, double low, double high) {
    Json pair = Json::array();
    pair.push_back(Num(low));
    pair.push_back(Num(high));
    (*out)[key] = std::move(pair);
  }
  template <class Names, class Values>
  void NamedNumbers(const std::string& key, const Names& names, const Values& values) {
    Json object = Json::object();
    for (std::size_t i = 0; i < names.size(); ++i) object[std::string(names[i])] = Num(values[i]);
    (*out)[key] = std::move(object);
  }
  template <class Fill>
  void Records(const std::string& key, std::size_t count, const Fill& fill) {
    Json list = Json::array();
    for (std::size_t i = 0; i < count; ++i) {
      Json record = Json::object();
      JsonRecordSink sink{&record};
      fill(i, sink);
      list.push_back(std::move(record));
    }
    (*out)[key] = std::move(list);
  }
};

/// A record of engine/analyses/records.h as a JSON object: `RecordJson<Json>([&](auto& s) {
/// DesignRecord(design, s); })`.
template <class Json, class Describe>
Json RecordJson(const Describe& describe) {
  Json out = Json::object();
  JsonRecordSink<Json> sink{&out};
  describe(sink);
  return out;
}

}  // namespace gesweep::cli
