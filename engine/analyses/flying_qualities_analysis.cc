// Adapter: the `flying_qualities` analysis. The short period and the phugoid of Eq. (1) at the run's
// height and speed rated against MIL-F-8785C Category C (docs/model.md §11), by
// RateFlyingQualities(AnalyzeModes(model.StateMatrix(H, u0))). It re-runs the eigen-analysis rather
// than reading the `modes` columns, so it stands alone in a study.
#include <sstream>

#include "engine/analyses/analysis.h"
#include "engine/modal/flying_qualities.h"

namespace gesweep {
namespace {

// One 5×5 eigen-analysis (the `modes` analysis measures about 8 µs with its bookkeeping) and a rating.
constexpr double kFlyingQualitiesCost_us = 8.0;

class FlyingQualitiesAnalysis final : public Analysis {
 public:
  std::string_view name() const override { return "flying_qualities"; }
  std::vector<ParameterId> parameters_used() const override { return {height_, speed_}; }
  double nominal_run_cost_us() const override { return kFlyingQualitiesCost_us; }

  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    std::vector<std::string> levels;
    for (auto level : {FlyingQualitiesLevel::kLevel1, FlyingQualitiesLevel::kLevel2,
                       FlyingQualitiesLevel::kLevel3, FlyingQualitiesLevel::kWorseThanLevel3}) {
      levels.emplace_back(ToString(level));
    }
    auto level_column = [&](const std::string& leaf, const std::string& what) {
      return schema.Add(
          OutputColumn::Integer(ColumnType::kInt8, "results/flying_qualities/" + leaf, "1",
                                "MIL-F-8785C Category C level of " + what + " (docs/model.md §11)", levels));
    };
    short_period_level_ = level_column("short_period_level", "the short period (3.2.2.1.2)");
    phugoid_level_ = level_column("phugoid_level", "the phugoid (3.2.1.2)");
    level_ = level_column("level", "the airplane: the worse of short period and phugoid");
    short_period_damping_ = schema.Add(OutputColumn::Real(
        "results/flying_qualities/short_period_damping_ratio", "1",
        "Short-period damping ratio rated: of the pair, or -(l1+l2)/(2 sqrt(l1 l2)) of a split pair; "
        "NaN when its real roots have opposite signs"));
    phugoid_damping_ = schema.Add(OutputColumn::Real(
        "results/flying_qualities/phugoid_damping_ratio", "1",
        "Phugoid damping ratio rated: of the pair, or -(l1+l2)/(2 sqrt(l1 l2)) of a split pair; NaN "
        "when its real roots have opposite signs"));
    phugoid_time_to_double_ = schema.Add(OutputColumn::Real(
        "results/flying_qualities/phugoid_time_to_double_s", "s",
        "Phugoid time to double amplitude ln 2/max Re(lambda); inf when it does not diverge"));
  }

  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    const double height_m = context.value(height_);
    const double speed_mps = context.value(speed_);
    const ModalAnalysis modal = AnalyzeModes(context.model->StateMatrix(height_m, speed_mps));
    if (!modal.finite) {
      std::ostringstream message;
      message << "state matrix not finite at H = " << height_m << " m, u0 = " << speed_mps << " m/s";
      return AnalysisOutcome::Failed(message.str());
    }
    const FlyingQualities rated = RateFlyingQualities(modal);
    // Level n is stored as code n - 1 of the levels attribute.
    auto code = [](FlyingQualitiesLevel level) { return static_cast<double>(static_cast<int>(level) - 1); };
    row.Set(short_period_level_, code(rated.short_period.level));
    row.Set(phugoid_level_, code(rated.phugoid.level));
    row.Set(level_, code(rated.worst));
    row.Set(short_period_damping_, rated.short_period.damping_ratio);
    row.Set(phugoid_damping_, rated.phugoid.damping_ratio);
    row.Set(phugoid_time_to_double_, rated.phugoid.time_to_double_s);
    return AnalysisOutcome::Ok();
  }

 private:
  ParameterId height_ = RequireParameter("height_m");
  ParameterId speed_ = RequireParameter("speed_mps");
  int short_period_level_ = 0, phugoid_level_ = 0, level_ = 0;
  int short_period_damping_ = 0, phugoid_damping_ = 0, phugoid_time_to_double_ = 0;
};

std::unique_ptr<Analysis> MakeFlyingQualitiesAnalysis(const TomlSection& settings, const Aircraft*) {
  settings.RejectUnknownKeys({});
  return std::make_unique<FlyingQualitiesAnalysis>();
}

}  // namespace

const AnalysisRegistrar kRegistrar{
    {"flying_qualities",
     "MIL-F-8785C Category C levels of the short period (3.2.2.1.2) and the phugoid (3.2.1.2) at the run's "
     "height_m and speed_mps, and the worse of the two (docs/model.md section 11).",
     true, &MakeFlyingQualitiesAnalysis, 200}};

}  // namespace gesweep
