#pragma once
/// The model options of docs/model.md: every **choice** there is an option here, docs/model.md's choice the
/// default. Also the per-run modifications a sweep can make to an aircraft (scale factors, mass, CG).

#include <optional>
#include <string>
#include <string_view>

#include "engine/aircraft/coefficient.h"
#include "engine/common/describe.h"
#include "engine/common/enum_names.h"

namespace gesweep {

/// How CDh is obtained (docs/model.md §3).
enum class CdhMode {
  kPolar,  ///< d(k·CLo²)/dh by finite differences on the table rows (default)
  kZero,   ///< CDh = 0
};
GESWEEP_ENUM_NAMES(CdhMode, {kPolar, "polar"}, {kZero, "zero"});

/// How the table is interpolated between finite rows (docs/model.md §2).
enum class Interpolation {
  kLinear,  ///< piecewise linear in H (default)
  kPchip,   ///< monotone piecewise-cubic Hermite (Fritsch–Carlson, Boost.Math pchip)
};
GESWEEP_ENUM_NAMES(Interpolation, {kLinear, "linear"}, {kPchip, "pchip"});

/// Options of the model; a default-constructed value is docs/model.md's model.
struct ModelOptions {
  /// false: Xh = Zh = Mh = 0 and nothing else changes (docs/model.md §4).
  bool h_derivatives = true;
  CdhMode cdh = CdhMode::kPolar;
  Interpolation interpolation = Interpolation::kLinear;

  /// Multiplicative factors on each coefficient column, applied to the tabulated rows and the
  /// free-flight row before anything is derived. A factor on k also scales the polar CDh; the
  /// factor on CDh scales the derived column.
  CoefficientRow coefficient_scale = UnitScale();
  double CDo_scale = 1.0;  ///< multiplicative factor on CDo

  std::optional<double> mass_kg;             ///< overrides the aircraft's mass when set
  std::optional<double> pitch_inertia_kgm2;  ///< overrides the aircraft's Iy when set
  /// CG moved aft by this fraction of the mean chord (negative: forward). Moment coefficients are
  /// transferred to the new CG: CMx += CLx·shift for x in {o, α, α̇, q, δe, h} (docs/model.md).
  double cg_shift_over_chord = 0.0;

  /// The options a person gives (describe.h): each is a sweep's run parameter of the same key (its
  /// catalogue entry, engine/analyses/parameter_catalog.cc), a flag of every command that builds a
  /// model (engine/cli/model_flags.cc) and a keyword of the Python functions (gesweep.MODEL_OPTIONS).
  /// By hand, and why (docs/architecture.md, "Still by hand"): the scale factors (an array of
  /// columns keyed by coefficient name, and CDo's beside them: parameters scale.<name>, Python's
  /// scale={...} and CDo_scale), and the mass and pitch inertia (unset: the aircraft's; the field
  /// list has no optional number).
  template <class V>
  void Describe(V& v) {
    v(Field("h_derivatives", &h_derivatives)
          .RunParameter()
          .Doc("Whether Xh, Zh and Mh are in the model (docs/model.md §4)"));
    v(Field("cdh", &cdh)
          .RunParameter()
          .Doc("How CDh is obtained: polar = d(k CLo^2)/dh, zero (docs/model.md §3)"));
    v(Field("interpolation", &interpolation)
          .RunParameter()
          .Doc("Table interpolation in height: linear or pchip (docs/model.md §2)"));
    v(Field("cg_shift_over_chord", &cg_shift_over_chord)
          .Limit("cg_shift_over_chord")
          .RunParameter()
          .Doc("CG moved aft by this fraction of the mean chord (negative: forward)"));
  }

  bool operator==(const ModelOptions&) const = default;

  static CoefficientRow UnitScale() {
    CoefficientRow scale;
    scale.fill(1.0);
    return scale;
  }
};

// Their names: ToString, ParseEnum, EnumChoices of engine/common/enum_names.h.

}  // namespace gesweep
