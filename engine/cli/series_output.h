#pragma once
/// The command line's visitor of a described series (engine/common/series.h): `simulate`'s and
/// `land`'s series as CSV (a header of the keys, then one line per sample) and as a JSON object of
/// arrays under the keys. A choice quantity (a landing's phase) is written as its name.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "engine/cli/json_util.h"
#include "engine/common/series.h"

namespace gesweep::cli {

namespace series_detail {

// The cell of `field` at sample i: its number through `format`, or a choice's name.
template <class Field, class Data, class Format>
std::string Cell(const Field& field, const Data& data, std::size_t i, const Format& format) {
  if constexpr (requires { SeriesText(field, data, i); }) {
    return std::string(SeriesText(field, data, i));
  } else {
    return format(field.Number(data, i));
  }
}

}  // namespace series_detail

/// The series as a JSON object (nlohmann's json or ordered_json): key → array (NaN as null, a
/// choice's names as texts).
template <class Json, class Data>
Json SeriesJson(const Data& data, const SeriesContents& contents) {
  Json out = Json::object();
  const std::size_t n = SeriesLength(data);
  ForEachSeriesField<Data>(contents, [&](const auto& field) {
    Json values = Json::array();
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (requires { SeriesText(field, data, i); }) {
        values.push_back(std::string(SeriesText(field, data, i)));
      } else {
        values.push_back(Json(JsonNumber(field.Number(data, i))));
      }
    }
    out[std::string(field.attributes().key)] = std::move(values);
  });
  return out;
}

/// The series as CSV: the keys, then a line per sample, each number through `format`.
template <class Data, class Format>
std::string SeriesCsv(const Data& data, const SeriesContents& contents, const Format& format) {
  std::string out;
  ForEachSeriesField<Data>(contents, [&](const auto& field) {
    out += (out.empty() ? "" : ",") + std::string(field.attributes().key);
  });
  out += "\n";
  const std::size_t n = SeriesLength(data);
  for (std::size_t i = 0; i < n; ++i) {
    bool first = true;
    ForEachSeriesField<Data>(contents, [&](const auto& field) {
      out += (first ? "" : ",") + series_detail::Cell(field, data, i, format);
      first = false;
    });
    out += "\n";
  }
  return out;
}

}  // namespace gesweep::cli
