#pragma once
/// What the programs of tests/risk (risk_importance, risk_roughness, risk_splitting,
/// risk_proxy_subset, risk_touchdown_memory, risk_restart) share: finding a column, a plan whose series lie
/// on the noise's sample grid, and the summary of independent repetitions.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/risk/landing_risk.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep::risk::programs {

/// The position, in an Evaluation's values (RiskColumns order), of the column whose path ends in
/// "/" + `leaf` ("final_time_s"); -1 when there is none.
inline int EvaluationColumn(const SweepPlan& plan, std::string_view leaf) {
  const std::vector<int> columns = RiskColumns(plan);
  std::string suffix(1, '/');
  suffix += leaf;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (plan.schema().columns[static_cast<std::size_t>(columns[i])].path.ends_with(suffix)) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

/// The position of the schema column `path` ("series/landing/height_m") in a run's results; throws
/// std::runtime_error when the plan has none.
inline int SchemaColumn(const SweepPlan& plan, const std::string& path) {
  const auto& columns = plan.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c].path == path) return static_cast<int>(c);
  }
  throw std::runtime_error("the study has no column " + path);
}

/// The plan of the study at `path` with its time series stored at the noise's sample interval (so
/// that series sample i is the state at t = i dt, which depends on the noise samples 0 .. i - 1
/// only), after `edit` (if any) has changed the loaded study.
inline SweepPlan SeriesPlanOnNoiseGrid(const std::filesystem::path& path,
                                       const std::function<void(Study&)>& edit = {}) {
  double interval = 0;
  {
    const SweepPlan probe(LoadStudy(path), ShardSpec{});
    interval = CellSampleInterval(probe, 0);
  }
  Study study = LoadStudy(path);
  if (edit) edit(study);
  study.storage.time_series = true;
  study.storage.output_dt_s = interval;
  return SweepPlan(std::move(study), ShardSpec{});
}

/// Independent repetitions' estimates: their mean, one run's measured CoV and the CoV of the mean.
class RepetitionTally {
 public:
  void Add(double estimate, long long landings) {
    sum_ += estimate;
    sum2_ += estimate * estimate;
    landings_ += landings;
    ++count_;
  }
  /// "# mean ..., one run's measured CoV ..., CoV of the mean ..., N landings" (nothing for one run).
  void Print() const {
    if (count_ < 2) return;
    const double mean = sum_ / count_;
    const double sd = std::sqrt(std::max(0.0, (sum2_ - count_ * mean * mean) / (count_ - 1)));
    std::printf("# mean %.4g, one run's measured CoV %.3f, CoV of the mean %.3f, %lld landings\n", mean,
                sd / mean, sd / mean / std::sqrt(static_cast<double>(count_)), landings_);
  }

 private:
  double sum_ = 0, sum2_ = 0;
  long long landings_ = 0;
  int count_ = 0;
};

}  // namespace gesweep::risk::programs
