#pragma once
/// The records the command line prints as JSON and the Python module returns as dicts, each described
/// once (issue 29): a boundary crossing, a boundary with its sensitivities, the landing's LQR design
/// and the settings a landing flew. A record is a function template over a sink; the command line's
/// sink builds a JSON object (engine/cli/record_json.h), the module's a dict (engine/python), so the
/// two cannot disagree on a key or a value. The sink is a superset of VisitOutputs' sink
/// (described_values.h), so a described struct's output fields go into a record unchanged.
///
/// A sink has, for a key:
/// - `Plain(key, value)`: a bool, an integer or a text as it is;
/// - `Number(key, double)`: NaN is JSON's null and Python's nan;
/// - `Array(key, values, names)`: VisitOutputs' array (values and "<key>_names");
/// - `Null(key)`: JSON's null, Python's None (a part that does not exist, e.g. the gain of a failed
///   design);
/// - `Complex(key, z)`: JSON's [re, im], Python's complex;
/// - `Complexes(key, zs)`, `Numbers(key, values)`, `Texts(key, texts)`: lists of those;
/// - `Range(key, low, high)`: JSON's [low, high], Python's tuple;
/// - `NamedNumbers(key, names, values)`: an object (dict) of numbers under the names;
/// - `Records(key, count, fill)`: a list of `count` records, `fill(i, sink)` writing record i.

#include <complex>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/described_values.h"
#include "engine/control/landing_design.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/estimators/local_sensitivity.h"
#include "engine/modal/boundary.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {

/// One crossing of the imaginary axis (BoundaryCrossing); the mode and its eigenvalue only where a
/// mode crosses (a Hopf or a real crossing).
template <class Sink>
void CrossingRecord(const BoundaryCrossing& c, Sink& s) {
  s.Number("height_m", c.height_m);
  s.Number("height_over_span", c.height_over_span);
  s.Plain("kind", std::string(ToString(c.kind)));
  s.Plain("stable_below", c.stable_below);
  s.Plain("stable_above", c.stable_above);
  if (c.kind == CrossingKind::kHopf || c.kind == CrossingKind::kReal) {
    s.Plain("mode", c.mode);
    s.Complex("eigenvalue", c.eigenvalue);
    s.Complex("eigenvalue_height_derivative_per_s_per_m", c.eigenvalue_height_derivative);
    s.Plain("mode_stable_above", c.mode_stable_above);
    s.Number("bracket_width_m", c.bracket_width_m);
  }
}

/// The sensitivities of one boundary (docs/sensitivity.md, "gesweep boundary"), ranked by relative
/// effect; without a valid boundary, an empty list and the reason.
template <class Sink>
void SensitivitiesRecord(const BoundarySensitivities& b, Sink& s) {
  if (!b.valid) {
    s.Records("sensitivities", 0, [](std::size_t, Sink&) {});
    s.Plain("sensitivities_reason", b.reason);
    return;
  }
  const std::vector<BoundaryParameterSensitivity> ranked = RankByRelativeEffect(b);
  s.Records("sensitivities", ranked.size(), [&](std::size_t i, Sink& e) {
    const BoundaryParameterSensitivity& p = ranked[i];
    e.Plain("parameter", p.parameter.Name());
    e.Number("value", p.value);
    e.Plain("value_unit", std::string(p.parameter.Unit()));
    e.Number("dH_dp", p.height_derivative);
    e.Plain("dH_dp_unit", HeightDerivativeUnit(p.parameter));
    e.Number("dH_dp_implicit", p.implicit_height_derivative);
    e.Number("p_dH_dp_m", p.relative_height_derivative_m);
    e.Number("dsigma_dp_per_s", p.margin_derivative);
    e.Plain("method", std::string(p.method == DerivativeMethod::kExact ? "exact" : "central_difference"));
  });
  std::vector<std::string> no_effect;
  for (const auto& p : b.parameters) {
    if (!p.enters_state_matrix) no_effect.push_back(p.parameter.Name());
  }
  s.Plain("sensitivity_mode", b.mode);
  s.Number("dsigma_dH_per_s_per_m", b.margin_height_derivative_per_s_per_m);
  s.Texts("no_effect_parameters", no_effect);
}

/// The crossings of a boundary other than H* (all of them when there is no H*), m.
inline std::vector<double> OtherCrossings(const BoundaryResult& result) {
  constexpr double kSameCrossing_m = 1e-9;  // H* is one of the crossings, found by the same root
  std::vector<double> others;
  for (const auto& crossing : result.crossings) {
    if (!result.height_m || std::abs(crossing.height_m - *result.height_m) > kSameCrossing_m) {
      others.push_back(crossing.height_m);
    }
  }
  return others;
}

/// The boundary H* at one speed (BoundaryResult; `span` the wing span, m), with its sensitivities
/// when they were asked for. H* and H*/b are NaN (null) when there is none; `reason` says why
/// (empty when there is one).
template <class Sink>
void BoundaryRecord(double speed_mps, const BoundaryResult& result, double span_m,
                    const std::optional<BoundarySensitivities>& sensitivities, Sink& s) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  s.Number("speed_mps", speed_mps);
  s.Number("height_m", result.height_m.value_or(kNaN));
  s.Number("height_over_span", result.height_m ? *result.height_m / span_m : kNaN);
  s.Numbers("other_crossings_m", OtherCrossings(result));
  s.Records("crossings", result.crossings.size(),
            [&](std::size_t i, Sink& c) { CrossingRecord(result.crossings[i], c); });
  s.Plain("method", std::string(ToString(result.method)));
  s.Plain("certified", result.certified);
  s.Plain("certificate", result.certificate);
  s.Range("scanned_range_m", result.lower_height_m, result.upper_height_m);
  s.Plain("reason", result.reason);
  if (sensitivities) SensitivitiesRecord(*sensitivities, s);
}

/// The landing's LQR design (LandingDesign): the gain on the states of Eq. (14) by name (null when
/// the design failed) and the closed loop's eigenvalues, 1/s.
template <class Sink>
void DesignRecord(const LandingDesign& d, Sink& s) {
  s.Plain("status", std::string(ToString(d.status)));
  s.Plain("message", d.message);
  s.Number("design_height_m", d.design_height_m);
  s.Number("design_speed_mps", d.design_speed_mps);
  s.Plain("h_derivatives", d.design_h_derivatives);
  if (d.ok()) {
    s.NamedNumbers("gain", LandingStateNames(), d.gain);
  } else {
    s.Null("gain");
  }
  std::vector<std::complex<double>> eigenvalues;
  for (Eigen::Index i = 0; i < d.closed_loop_eigenvalues.size(); ++i) {
    eigenvalues.emplace_back(d.closed_loop_eigenvalues(i));
  }
  s.Complexes("closed_loop_eigenvalues_per_s", eigenvalues);
}

/// The model a run flew: the aircraft's name and the model options (ModelOptions::Describe).
template <class Sink>
void ModelRecord(const LongitudinalModel& model, Sink& s) {
  s.Plain("aircraft", model.aircraft().name);
  VisitOutputs(model.options(), s);
}

/// The settings an open-loop run flew (`gesweep simulate`'s run, gesweep.simulate's): OpenLoopConfig's
/// output fields, the model, and the seed and run index of its turbulence.
template <class Sink>
void OpenLoopRunRecord(const OpenLoopConfig& c, const LongitudinalModel& model, Sink& s) {
  VisitOutputs(c, s);
  ModelRecord(model, s);
  s.Plain("seed", c.seed);
  s.Plain("run_index", c.run_index);
}

/// The settings a landing flew: the model, LandingConfig's output fields with the automatic ones as
/// used (SettingsUsed) and the output weights by state, σ_w in force, and the names earlier versions
/// wrote (integrator, rtol, atol, plant_reference_height_m).
template <class Sink>
void LandingRunRecord(const LandingConfig& c, const LandingResult& r, const LongitudinalModel& model,
                      Sink& s) {
  ModelRecord(model, s);
  VisitOutputs(SettingsUsed(c, r), s);  // with q_weights, keyed by state
  s.Number("turbulence_sigma_w_mps", EffectiveSigmaW(c.disturbance));
  s.Plain("integrator", std::string("dopri5"));
  s.Number("rtol", c.integrator.relative_tolerance);
  s.Number("atol", c.integrator.absolute_tolerance);
  if (c.plant_height_reference == PlantHeightReference::kFixedHeight) {
    s.Number("plant_reference_height_m", r.plant_fixed_reference_height_m);
  }
}

}  // namespace gesweep
