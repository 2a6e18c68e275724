// Adapters: verification models with known answers, run through the same sweep machinery as the
// flight analyses, so the designs and the sensitivity estimators can be checked end to end
// (as Dakota and SALib ship theirs).
//  - ishigami: f = sin x1 + a sin² x2 + b x3⁴ sin x1 (Ishigami & Homma 1990), a = 7, b = 0.1 by
//    default; x1..x3 uniform on [−π, π] give first-order Sobol indices (0.3139, 0.4424, 0) and total
//    indices (0.5576, 0.4424, 0.2437).
//  - linear: f = intercept + Σ cᵢ xᵢ; Morris' μ* of xᵢ over [0, 1] is |cᵢ|.
#include <cmath>

#include "engine/analyses/analysis.h"
#include "engine/estimators/ishigami.h"

namespace gesweep {
namespace {

constexpr double kVerificationCost_us = 0.05;  // a few floating-point operations

class IshigamiAnalysis final : public Analysis {
 public:
  IshigamiAnalysis(double a, double b) : a_(a), b_(b) {}
  std::string_view name() const override { return "ishigami"; }
  bool needs_model() const override { return false; }
  std::vector<ParameterId> parameters_used() const override { return {x_[0], x_[1], x_[2]}; }
  double nominal_run_cost_us() const override { return kVerificationCost_us; }
  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    output_ = schema.Add(
        OutputColumn::Real("results/ishigami/ishigami", "1",
                           "Ishigami function sin x1 + a sin^2 x2 + b x3^4 sin x1 (verification model)"));
  }
  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    row.Set(output_, Ishigami({context.value(x_[0]), context.value(x_[1]), context.value(x_[2])}, a_, b_));
    return AnalysisOutcome::Ok();
  }

 private:
  double a_, b_;
  ParameterId x_[3] = {RequireParameter("x1"), RequireParameter("x2"), RequireParameter("x3")};
  int output_ = 0;
};

class LinearAnalysis final : public Analysis {
 public:
  LinearAnalysis(std::vector<double> coefficients, double intercept)
      : coefficients_(std::move(coefficients)), intercept_(intercept) {
    for (std::size_t i = 0; i < coefficients_.size(); ++i) {
      std::string name = "x";
      name += std::to_string(i + 1);
      x_.push_back(RequireParameter(name));
    }
  }
  std::string_view name() const override { return "linear"; }
  bool needs_model() const override { return false; }
  std::vector<ParameterId> parameters_used() const override { return x_; }
  double nominal_run_cost_us() const override { return kVerificationCost_us; }
  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    output_ = schema.Add(OutputColumn::Real("results/linear/linear", "1",
                                            "Linear function intercept + sum c_i x_i (verification model)"));
  }
  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    double sum = intercept_;
    for (std::size_t i = 0; i < x_.size(); ++i) sum += coefficients_[i] * context.value(x_[i]);
    row.Set(output_, sum);
    return AnalysisOutcome::Ok();
  }

 private:
  std::vector<double> coefficients_;
  double intercept_;
  std::vector<ParameterId> x_;
  int output_ = 0;
};

std::unique_ptr<Analysis> MakeIshigamiAnalysis(const TomlSection& settings, const Aircraft*) {
  settings.RejectUnknownKeys({"a", "b"});
  return std::make_unique<IshigamiAnalysis>(settings.OptionalNumber("a").value_or(kIshigamiA),
                                            settings.OptionalNumber("b").value_or(kIshigamiB));
}

std::unique_ptr<Analysis> MakeLinearAnalysis(const TomlSection& settings, const Aircraft*) {
  settings.RejectUnknownKeys({"coefficients", "intercept"});
  std::vector<double> coefficients = settings.NumberArray("coefficients");
  if (coefficients.empty() || coefficients.size() > 8) {
    settings.Fail("coefficients", "[...]", "expected 1 to 8 coefficients (for x1..x8)");
  }
  return std::make_unique<LinearAnalysis>(std::move(coefficients),
                                          settings.OptionalNumber("intercept").value_or(0.0));
}

}  // namespace

const AnalysisRegistrar kIshigamiRegistrar{
    {"ishigami", "Verification: the Ishigami function of x1..x3 (output results/ishigami/ishigami).", false,
     &MakeIshigamiAnalysis, 900}};
const AnalysisRegistrar kLinearRegistrar{
    {"linear", "Verification: intercept + sum c_i x_i (output results/linear/linear).", false,
     &MakeLinearAnalysis, 910}};

}  // namespace gesweep
