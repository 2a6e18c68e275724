#pragma once
/// The height-dependent aerodynamic coefficients of an aircraft file's table (docs/model.md §2).

#include <array>
#include <optional>
#include <string_view>

namespace gesweep {

/// One column of the coefficient table. All are per radian and dimensionless; CLh, CMh and CDh are
/// derivatives with respect to h = H/c. CDh is not in aircraft files: it is derived (docs/model.md §3).
enum class Coefficient : int {
  k,           ///< induced-drag factor of the polar CD = CDo + k CL²
  CLo,         ///< lift coefficient at α = 0
  CMo,         ///< pitching-moment coefficient at α = 0
  CDalpha,     ///< dCD/dα
  CLalpha,     ///< dCL/dα
  CLalphadot,  ///< dCL/d(α̇ c/2u)
  CLq,         ///< dCL/d(q c/2u)
  CLde,        ///< dCL/dδe
  CMalpha,     ///< dCM/dα
  CMalphadot,  ///< dCM/d(α̇ c/2u)
  CMq,         ///< dCM/d(q c/2u)
  CMde,        ///< dCM/dδe
  ho_over_c,   ///< stick-fixed neutral point as a fraction of c (reported, not used by the dynamics)
  CLh,         ///< dCLo/dh
  CMh,         ///< dCMo/dh
  CDh,         ///< d(CD)/dh at α = 0; derived, never read from a file
};

/// Number of coefficient columns, CDh included.
inline constexpr int kCoefficientCount = 16;
/// Number of columns an aircraft file tabulates (all but CDh).
inline constexpr int kTabulatedCount = 15;

/// Names as they appear in aircraft files, study keys (`scale.CLh`) and archives.
inline constexpr std::array<std::string_view, kCoefficientCount> kCoefficientNames = {
    "k",       "CLo",        "CMo", "CDalpha", "CLalpha",   "CLalphadot", "CLq", "CLde",
    "CMalpha", "CMalphadot", "CMq", "CMde",    "ho_over_c", "CLh",        "CMh", "CDh"};

/// The column of a name, or nullopt.
std::optional<Coefficient> CoefficientFromName(std::string_view name);

/// Index of a coefficient into arrays of kCoefficientCount.
constexpr int Index(Coefficient c) { return static_cast<int>(c); }

/// A full set of coefficient values at one height, indexed by Index(Coefficient).
using CoefficientRow = std::array<double, kCoefficientCount>;

}  // namespace gesweep
