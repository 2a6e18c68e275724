#pragma once
/// The Python module's visitor of a described series (engine/common/series.h): gesweep.simulate's
/// and gesweep.land's series as a dict of key → NumPy array, a choice quantity (a landing's phase) as
/// a list of its names; the same keys, in the same order, as the command line's CSV and JSON.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <string>

#include "engine/common/series.h"

namespace gesweep::python {

namespace py = pybind11;

template <class Data>
py::dict SeriesDict(const Data& data, const SeriesContents& contents) {
  py::dict out;
  const std::size_t n = SeriesLength(data);
  ForEachSeriesField<Data>(contents, [&](const auto& field) {
    const py::str key(std::string(field.attributes().key));
    if constexpr (requires { SeriesText(field, data, n); }) {
      py::list names;
      for (std::size_t i = 0; i < n; ++i) names.append(std::string(SeriesText(field, data, i)));
      out[key] = names;
    } else {
      py::array_t<double> values(static_cast<py::ssize_t>(n));
      double* cells = values.mutable_data();
      for (std::size_t i = 0; i < n; ++i) cells[i] = field.Number(data, i);
      out[key] = values;
    }
  });
  return out;
}

}  // namespace gesweep::python
