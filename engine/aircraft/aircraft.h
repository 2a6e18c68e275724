#pragma once
/// An aircraft as described by an aircraft file (studies/aircraft/*.toml; schemas/aircraft.schema.json):
/// geometry, mass properties, the speed-independent coefficients, the limits, and the coefficient
/// table against height with its free-flight row (docs/model.md §1–§2).

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "engine/aircraft/coefficient.h"

namespace gesweep {

/// Everything an aircraft file says. SI units. Invariants established by the loader: every number
/// finite, lengths, areas, mass and inertia > 0, table heights > 0 and strictly increasing, every
/// table column as long as `table_heights_m`, at least two finite rows.
struct Aircraft {
  std::string name;
  std::string source_path;  ///< the file it was read from ("<memory>" when parsed from text)
  std::string source_text;  ///< the file's full text, kept for archive provenance

  double wingspan_m = 0;
  double mean_chord_m = 0;
  double wing_area_m2 = 0;
  double mass_kg = 0;
  double pitch_inertia_kgm2 = 0;
  double cg_over_chord = 0;  ///< CG position as a fraction of the mean chord (Table A1: 0.25)

  double CDo = 0;  ///< parasite drag coefficient
  double CDu = 0;  ///< speed derivatives: zero for a low-speed, incompressible aircraft (docs/model.md §2)
  double CLu = 0;
  double CMu = 0;
  double CDde = 0;  ///< elevator drag derivative (not tabulated; zero by default)

  double stall_speed_mps = 0;
  double wheel_contact_height_m = 0;  ///< height of the mean chord when the tires touch
  double field_elevation_m = 0;       ///< ISA altitude of the ground; ρ is evaluated at this + H

  /// Finite table heights H of the mean chord above ground, strictly increasing.
  std::vector<double> table_heights_m;
  /// rows[i][Index(c)] for the tabulated coefficients; the CDh entry is 0 (derived later).
  std::vector<CoefficientRow> rows;
  /// The free-flight (H = ∞) row; CDh entry 0.
  CoefficientRow free_flight{};

  /// One tabulated column across the finite rows.
  std::vector<double> Column(Coefficient c) const;
};

/// Loads and validates an aircraft file. Throws InputError naming the file, key, value and expectation.
Aircraft LoadAircraftFile(const std::filesystem::path& path);

/// Parses and validates aircraft TOML text; `source` names it in errors.
Aircraft ParseAircraft(std::string_view text, const std::string& source);

}  // namespace gesweep
