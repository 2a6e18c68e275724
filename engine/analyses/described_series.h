#pragma once
/// The archive visitor of a described series (engine/common/series.h): the time axis
/// series/<analysis>/time_s on the grid t = k·dt, one column series/<analysis>/<key> per stored
/// quantity on it, and the filling of one run's columns from its samples.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "engine/analyses/analysis.h"
#include "engine/common/series.h"

namespace gesweep {

/// Data: the series as the simulation returns it (OpenLoopSeries, std::vector<LandingSample>).
template <class Data>
class DescribedSeries {
 public:
  /// A sample is on the grid when its time is within this of k·dt.
  static constexpr double kGridTolerance_s = 1e-9;

  /// Adds the axis (samples at k·dt_s up to duration_s) and the stored quantities: the air motion
  /// always (0 in still air, so that every run of a sweep has the same columns), q_g when the study's
  /// runs have the pitch-rate gust. Returns the number of samples.
  int Declare(OutputSchema& schema, const std::string& analysis, const std::string& axis_description,
              double duration_s, double dt_s, bool pitch_rate_gust) {
    const std::string base = "series/" + analysis + "/";
    dt_s_ = dt_s;
    contents_ = SeriesContents{.disturbance = true, .pitch_rate_gust = pitch_rate_gust};
    samples_ = static_cast<int>(std::floor(duration_s / dt_s + kGridTolerance_s)) + 1;
    TimeAxis axis;
    axis.description = axis_description;
    for (int k = 0; k < samples_; ++k) axis.times_s.push_back(k * dt_s);
    columns_.clear();
    ForEachSeriesField<Data>(contents_, [&](const auto& field) {
      const SeriesAttributes& a = field.attributes();
      if (a.axis) axis.path = base + std::string(a.key);
    });
    GESWEEP_DEMAND(!axis.path.empty());
    schema.AddAxis(axis);
    ForEachSeriesField<Data>(contents_, [&](const auto& field) {
      const SeriesAttributes& a = field.attributes();
      if (!a.stored) return;
      columns_.push_back(schema.Add(OutputColumn::Series(base + std::string(a.key), std::string(a.unit),
                                                         std::string(a.doc), axis.path, samples_)));
    });
    return samples_;
  }

  /// Stores the samples of `data` that lie on the grid into `row`; returns whether some lay past the
  /// stored duration (they are left out).
  bool Store(const Data& data, OutputRow& row) const {
    bool truncated = false;
    const std::size_t n = SeriesLength(data);
    for (std::size_t i = 0; i < n; ++i) {
      const double position = TimeOf(data, i) / dt_s_;
      const double k = std::round(position);
      if (std::abs(position - k) * dt_s_ > kGridTolerance_s || k < 0) continue;
      if (k >= samples_) {
        truncated = true;
        continue;
      }
      std::size_t c = 0;
      ForEachSeriesField<Data>(contents_, [&](const auto& field) {
        if (field.attributes().stored) row.Slot(columns_[c++])[static_cast<int>(k)] = field.Number(data, i);
      });
    }
    return truncated;
  }

 private:
  double TimeOf(const Data& data, std::size_t i) const {
    double time_s = 0;
    ForEachSeriesField<Data>(contents_, [&](const auto& field) {
      if (field.attributes().axis) time_s = field.Number(data, i);
    });
    return time_s;
  }

  std::vector<int> columns_;
  SeriesContents contents_;
  int samples_ = 0;
  double dt_s_ = 0;
};

}  // namespace gesweep
