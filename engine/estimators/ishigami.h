#pragma once
/// The Ishigami function, the verification model of global sensitivity analysis that Dakota and SALib
/// ship (Ishigami & Homma 1990): f(x) = sin x1 + a sin² x2 + b x3⁴ sin x1 on x ∈ [−π, π]³, with the
/// usual a = 7, b = 0.1. Its Sobol' indices are known in closed form (docs/sensitivity.md).

#include <array>
#include <string_view>
#include <vector>

#include "engine/estimators/sensitivity_common.h"

namespace gesweep {

/// The name of the output of the Ishigami verification model in studies and archives.
inline constexpr std::string_view kIshigamiOutputName = "ishigami";
/// The coefficients of the standard Ishigami function.
inline constexpr double kIshigamiA = 7.0;
inline constexpr double kIshigamiB = 0.1;

/// f(x) = sin x1 + a sin² x2 + b x3⁴ sin x1 (dimensionless). Defined for any real x; the standard
/// input ranges are IshigamiRanges().
double Ishigami(const std::array<double, 3>& x, double a = kIshigamiA, double b = kIshigamiB);

/// The three inputs x1, x2, x3, each uniform on [−π, π].
std::vector<ParameterRange> IshigamiRanges();

}  // namespace gesweep
