#pragma once
/// JSON helpers for the CLI: non-finite numbers become null (JSON has no NaN), +∞ heights "inf".

#include <cmath>
#include <nlohmann/json.hpp>

namespace gesweep::cli {

/// A number, or null when it is not finite.
inline nlohmann::json JsonNumber(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

/// A height: a number, or the string "inf" for free flight.
inline nlohmann::json JsonHeight(double height_m) {
  return std::isinf(height_m) ? nlohmann::json("inf") : nlohmann::json(height_m);
}

}  // namespace gesweep::cli
