// Adapter: the `modes` analysis. Eigenvalues, modes and stability margin of Eq. (1) at the run's
// height and speed (docs/model.md §5-§6), by AnalyzeModes(model.StateMatrix(H, u0)).
#include <array>
#include <cmath>
#include <sstream>

#include "engine/analyses/analysis.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {
namespace {

// Measured (docs/sweep.md): one 5×5 eigen-analysis and its bookkeeping, about 8 µs on one core.
constexpr double kModesCost_us = 8.0;

class ModesAnalysis final : public Analysis {
 public:
  explicit ModesAnalysis(const Aircraft& aircraft) : wingspan_m_(aircraft.wingspan_m) {}

  std::string_view name() const override { return "modes"; }
  std::vector<ParameterId> parameters_used() const override { return {height_, speed_}; }
  double nominal_run_cost_us() const override { return kModesCost_us; }

  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    OutputColumn eigenvalues = OutputColumn::Complex(
        "results/modes/eigenvalues", "1/s",
        "Eigenvalues of A (Eq. 1): short period (2), phugoid (2), height (1); a pair with "
        "Im > 0 first (docs/model.md §6)",
        5);
    eigenvalues.component_names = {"short_period", "short_period", "phugoid", "phugoid", "height"};
    eigenvalues_ = schema.Add(eigenvalues);
    margin_ = schema.Add(OutputColumn::Real(
        "results/modes/stability_margin_per_s", "1/s",
        "Stability margin sigma = the largest Re(lambda), the neutral height root left out "
        "(docs/model.md §6); stable when < 0"));
    stable_ = schema.Add(OutputColumn::Integer(ColumnType::kInt8, "results/modes/stable", "1",
                                               "1 when sigma < 0, else 0", {"false", "true"}));
    classification_ = schema.Add(OutputColumn::Integer(
        ColumnType::kInt8, "results/modes/classification", "1",
        "How the eigenvalues were assigned to modes (levels attribute)", EnumLevels<ModeClassification>()));
    height_over_span_ =
        schema.Add(OutputColumn::Real("results/modes/height_over_span", "1", "H/b of the run's height_m"));
    const std::array<const char*, 3> modes = {"short_period", "phugoid", "height"};
    const std::array<const char*, 3> titles = {"short-period", "phugoid", "height (subsidence)"};
    for (std::size_t m = 0; m < modes.size(); ++m) {
      const std::string base = std::string("results/modes/") + modes[m] + "/";
      const std::string title = titles[m];
      ModeColumns& c = mode_columns_[m];
      c.re = schema.Add(
          OutputColumn::Real(base + "eigenvalue_re_per_s", "1/s", "Re(lambda) of the " + title + " mode"));
      c.im = schema.Add(OutputColumn::Real(base + "eigenvalue_im_per_s", "1/s",
                                           "Im(lambda) >= 0 of the " + title + " mode"));
      c.frequency = schema.Add(OutputColumn::Real(base + "natural_frequency_radps", "rad/s",
                                                  "Natural frequency |lambda| of the " + title + " mode"));
      c.damping = schema.Add(OutputColumn::Real(
          base + "damping_ratio", "1",
          "Damping ratio -Re(lambda)/|lambda| of the " + title + " mode (NaN when neutral)"));
      c.period = schema.Add(OutputColumn::Real(
          base + "period_s", "s", "Period 2 pi/|Im lambda| of the " + title + " mode (inf when real)"));
      c.half_double = schema.Add(OutputColumn::Real(base + "time_to_half_or_double_s", "s",
                                                    "ln 2/|Re lambda| of the " + title +
                                                        " mode: to half amplitude when stable, to double "
                                                        "when unstable"));
      c.oscillatory = schema.Add(OutputColumn::Integer(ColumnType::kInt8, base + "oscillatory", "1",
                                                       "1 when the " + title + " mode is a complex pair",
                                                       {"false", "true"}));
    }
  }

  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    const double height_m = context.value(height_);
    const double speed_mps = context.value(speed_);
    const ModalAnalysis modal = AnalyzeModes(context.model->StateMatrix(height_m, speed_mps));
    row.Set(height_over_span_, height_m / wingspan_m_);
    if (!modal.finite) {
      std::ostringstream message;
      message << "state matrix not finite at H = " << height_m << " m, u0 = " << speed_mps << " m/s";
      return AnalysisOutcome::Failed(message.str());
    }
    double* lambda = row.Slot(eigenvalues_);
    for (std::size_t i = 0; i < modal.eigenvalues.size(); ++i) {
      lambda[2 * i] = modal.eigenvalues[i].real();
      lambda[2 * i + 1] = modal.eigenvalues[i].imag();
    }
    row.Set(margin_, modal.stability_margin_per_s);
    row.Set(stable_, modal.stable ? 1.0 : 0.0);
    row.Set(classification_, static_cast<double>(static_cast<int>(modal.classification)));
    const std::array<const ModeProperties*, 3> modes = {&modal.short_period, &modal.phugoid, &modal.height};
    for (std::size_t m = 0; m < modes.size(); ++m) {
      const ModeProperties& mode = *modes[m];
      const ModeColumns& c = mode_columns_[m];
      row.Set(c.re, mode.eigenvalue.real());
      row.Set(c.im, mode.eigenvalue.imag());
      row.Set(c.frequency, mode.natural_frequency_radps);
      row.Set(c.damping, mode.damping_ratio);
      row.Set(c.period, mode.period_s);
      row.Set(c.half_double, mode.time_to_half_or_double_s);
      row.Set(c.oscillatory, mode.oscillatory ? 1.0 : 0.0);
    }
    return AnalysisOutcome::Ok();
  }

 private:
  struct ModeColumns {
    int re = 0, im = 0, frequency = 0, damping = 0, period = 0, half_double = 0, oscillatory = 0;
  };
  double wingspan_m_;
  ParameterId height_ = RequireParameter("height_m");
  ParameterId speed_ = RequireParameter("speed_mps");
  int eigenvalues_ = 0, margin_ = 0, stable_ = 0, classification_ = 0, height_over_span_ = 0;
  std::array<ModeColumns, 3> mode_columns_{};
};

std::unique_ptr<Analysis> MakeModesAnalysis(const TomlSection& settings, const Aircraft* aircraft) {
  settings.RejectUnknownKeys({});
  return std::make_unique<ModesAnalysis>(*aircraft);
}

}  // namespace

const AnalysisRegistrar kRegistrar{
    {"modes",
     "Eigenvalues, modes and stability margin at the run's height_m and speed_mps (docs/model.md section 6).",
     true, &MakeModesAnalysis, 100}};

}  // namespace gesweep
