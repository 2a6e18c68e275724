// Adapter: the `boundary` analysis. The stability boundary H*(u0) of the run's own model at the
// run's speed (docs/model.md §6), by FindBoundary: the certified Hurwitz finder by default (every
// crossing of the imaginary axis, issue 16), or the former sampled search with method = "sampled".
// Makes H* a sweepable scalar (issue 7: Sobol indices of H*).
#include <cmath>
#include <limits>

#include "engine/analyses/analysis.h"
#include "engine/modal/boundary.h"

namespace gesweep {
namespace {

// Measured (docs/performance.md, "Boundary"): the Hurwitz finder about 40 µs, the sampled search
// (about 300 eigen-analyses) about 1 ms; the estimate keeps a margin for slower machines.
constexpr double kHurwitzBoundaryCost_us = 100.0;
constexpr double kSampledBoundaryCost_us = 5000.0;
constexpr int kMaximumSamplesPerSegment = 10000;

class BoundaryAnalysis final : public Analysis {
 public:
  BoundaryAnalysis(const Aircraft& aircraft, BoundaryOptions options)
      : wingspan_m_(aircraft.wingspan_m), options_(options) {}

  std::string_view name() const override { return "boundary"; }
  std::vector<ParameterId> parameters_used() const override { return {speed_}; }
  double nominal_run_cost_us() const override {
    return options_.method == BoundaryMethod::kHurwitz ? kHurwitzBoundaryCost_us : kSampledBoundaryCost_us;
  }

  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    height_ = schema.Add(OutputColumn::Real(
        "results/boundary/height_m", "m",
        "Boundary height H*: the highest height where sigma changes sign, unstable below and "
        "stable above (docs/model.md §6); NaN when there is none in the scanned range"));
    height_over_span_ = schema.Add(
        OutputColumn::Real("results/boundary/height_over_span", "1", "H*/b; NaN when there is no boundary"));
    found_ = schema.Add(OutputColumn::Integer(ColumnType::kInt8, "results/boundary/found", "1",
                                              "1 when a boundary was found in the scanned range",
                                              {"false", "true"}));
    crossings_ = schema.Add(OutputColumn::Integer(
        ColumnType::kInt32, "results/boundary/crossing_count", "1",
        "Number of crossings found in the scanned range: of the imaginary axis by any eigenvalue "
        "(method hurwitz), of sigma through 0 (method sampled)"));
    lowest_ = schema.Add(
        OutputColumn::Real("results/boundary/lowest_crossing_height_m", "m",
                           "Lowest crossing found (equals H* when there is one crossing); NaN when none"));
    evaluations_ = schema.Add(OutputColumn::Integer(ColumnType::kInt32, "results/boundary/margin_evaluations",
                                                    "1", "Eigen-analyses spent locating it"));
    certified_ = schema.Add(OutputColumn::Integer(
        ColumnType::kInt8, "results/boundary/certified", "1",
        "1 when every crossing in the range was isolated with certainty (method hurwitz; "
        "docs/model.md, 'The boundary by the Hurwitz criterion'); 0 for method sampled",
        {"false", "true"}));
  }

  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    const BoundaryResult result = FindBoundary(*context.model, context.value(speed_), options_);
    row.Set(found_, result.height_m ? 1.0 : 0.0);
    row.Set(crossings_, static_cast<double>(result.crossings.size()));
    row.Set(evaluations_, result.margin_evaluations);
    row.Set(certified_, result.certified ? 1.0 : 0.0);
    if (!result.crossings.empty()) row.Set(lowest_, result.crossings.back().height_m);
    if (result.height_m) {
      row.Set(height_, *result.height_m);
      row.Set(height_over_span_, *result.height_m / wingspan_m_);
      return AnalysisOutcome::Ok();
    }
    // No boundary is a finding, not a failure: H* is NaN and the message says why.
    return AnalysisOutcome::Ok("none (" + result.reason + ")");  // stored as "boundary: none (...)"
  }

 private:
  double wingspan_m_;
  BoundaryOptions options_;
  ParameterId speed_ = RequireParameter("speed_mps");
  int height_ = 0, height_over_span_ = 0, found_ = 0, crossings_ = 0, lowest_ = 0, evaluations_ = 0,
      certified_ = 0;
};

std::unique_ptr<Analysis> MakeBoundaryAnalysis(const TomlSection& settings, const Aircraft* aircraft) {
  settings.RejectUnknownKeys(
      {"lower_height_m", "upper_height_m", "tolerance_m", "samples_per_segment", "method"});
  BoundaryOptions options;
  if (settings.Has("method")) {
    const std::string method = settings.String("method");
    if (method == "sampled") {
      options.method = BoundaryMethod::kSampled;
    } else if (method != "hurwitz") {
      settings.Fail("method", method,
                    "expected \"hurwitz\" (certified, the default) or \"sampled\" (the former search)");
    }
  }
  if (const auto lower = settings.OptionalLimitedNumber("lower_height_m", "height_m"))
    options.lower_height_m = *lower;
  if (const auto upper = settings.OptionalLimitedNumber("upper_height_m", "height_m"))
    options.upper_height_m = *upper;
  const double lower =
      std::isnan(options.lower_height_m) ? aircraft->wheel_contact_height_m : options.lower_height_m;
  const double upper =
      std::isnan(options.upper_height_m) ? aircraft->table_heights_m.back() : options.upper_height_m;
  if (lower < aircraft->wheel_contact_height_m) {
    settings.Fail("lower_height_m", ShortNumber(lower),
                  "expected a height >= the wheel-contact height " +
                      ShortNumber(aircraft->wheel_contact_height_m) + " m of " + aircraft->source_path);
  }
  if (!(upper > lower)) {
    settings.Fail(settings.Has("upper_height_m") ? "upper_height_m" : "lower_height_m", ShortNumber(lower),
                  "expected lower_height_m < upper_height_m (" + ShortNumber(upper) + " m)");
  }
  if (const auto tolerance = settings.OptionalLimitedNumber("tolerance_m", "boundary.tolerance_m")) {
    options.tolerance_m = *tolerance;
  }
  if (const auto samples = settings.OptionalInteger("samples_per_segment")) {
    if (*samples < 1 || *samples > kMaximumSamplesPerSegment) {
      settings.Fail("samples_per_segment", std::to_string(*samples),
                    "expected 1 to " + std::to_string(kMaximumSamplesPerSegment));
    }
    options.samples_per_segment = static_cast<int>(*samples);
  }
  return std::make_unique<BoundaryAnalysis>(*aircraft, options);
}

}  // namespace

const AnalysisRegistrar kRegistrar{
    {"boundary", "The stability boundary H* of the run's model at its speed_mps (docs/model.md section 6).",
     true, &MakeBoundaryAnalysis, 300}};

}  // namespace gesweep
