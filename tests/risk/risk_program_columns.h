#pragma once
/// What the programs of tests/risk (risk_importance, risk_roughness) share: finding a result column
/// among the values of an evaluation.

#include <string>
#include <string_view>
#include <vector>

#include "engine/risk/landing_risk.h"
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

}  // namespace gesweep::risk::programs
