#include <cmath>
#include <string>

#include "engine/aircraft/aircraft.h"
#include "engine/common/toml_reader.h"

namespace gesweep {
namespace {

std::vector<std::string> TabulatedNames() {
  return std::vector<std::string>(kCoefficientNames.begin(), kCoefficientNames.begin() + kTabulatedCount);
}

void ReadTable(const TomlSection& table, Aircraft& aircraft) {
  std::vector<std::string> allowed = TabulatedNames();
  allowed.push_back("height_m");
  allowed.push_back("free_flight");
  table.RejectUnknownKeys(allowed);

  aircraft.table_heights_m = table.NumberArray("height_m");
  const auto& heights = aircraft.table_heights_m;
  if (heights.size() < 2) {
    table.Fail("height_m", std::to_string(heights.size()) + " rows", "expected at least 2 finite rows");
  }
  for (std::size_t i = 0; i < heights.size(); ++i) {
    if (!(heights[i] > 0.0)) {
      table.Fail("height_m", ShortNumber(heights[i]),
                 "expected heights > 0 (entry " + std::to_string(i + 1) + ")");
    }
    if (i > 0 && !(heights[i] > heights[i - 1])) {
      table.Fail("height_m", ShortNumber(heights[i]),
                 "expected strictly increasing heights (entry " + std::to_string(i + 1) + " is not above " +
                     ShortNumber(heights[i - 1]) + ")");
    }
  }
  aircraft.rows.assign(heights.size(), CoefficientRow{});
  for (int c = 0; c < kTabulatedCount; ++c) {
    const std::string name(kCoefficientNames[c]);
    const std::vector<double> column = table.NumberArray(name);
    if (column.size() != heights.size()) {
      table.Fail(name, std::to_string(column.size()) + " values",
                 "expected " + std::to_string(heights.size()) + " values, one per height_m row");
    }
    for (std::size_t i = 0; i < column.size(); ++i) aircraft.rows[i][c] = column[i];
  }

  const TomlSection free_flight = table.Section("free_flight");
  free_flight.RejectUnknownKeys(TabulatedNames());
  for (int c = 0; c < kTabulatedCount; ++c) {
    aircraft.free_flight[c] = free_flight.Number(kCoefficientNames[c]);
  }
}

}  // namespace

std::vector<double> Aircraft::Column(Coefficient c) const {
  std::vector<double> column;
  column.reserve(rows.size());
  for (const auto& row : rows) column.push_back(row[Index(c)]);
  return column;
}

Aircraft ParseAircraft(std::string_view text, const std::string& source) {
  const toml::table document = ParseToml(text, source);
  const TomlSection root(document, source, "");
  root.RejectUnknownKeys(
      {"format_version", "name", "description", "geometry", "mass", "aerodynamics", "limits", "table"});

  Aircraft aircraft;
  aircraft.source_path = source;
  aircraft.source_text = std::string(text);
  if (auto version = root.OptionalInteger("format_version"); version && *version != 1) {
    root.Fail("format_version", std::to_string(*version), "expected 1");
  }
  aircraft.name = root.String("name");
  if (aircraft.name.empty()) root.Fail("name", "\"\"", "expected a non-empty name");

  const TomlSection geometry = root.Section("geometry");
  geometry.RejectUnknownKeys({"wingspan_m", "mean_chord_m", "wing_area_m2"});
  aircraft.wingspan_m = geometry.PositiveNumber("wingspan_m");
  aircraft.mean_chord_m = geometry.PositiveNumber("mean_chord_m");
  aircraft.wing_area_m2 = geometry.PositiveNumber("wing_area_m2");

  const TomlSection mass = root.Section("mass");
  mass.RejectUnknownKeys({"mass_kg", "pitch_inertia_kgm2", "cg_over_chord"});
  aircraft.mass_kg = mass.PositiveNumber("mass_kg");
  aircraft.pitch_inertia_kgm2 = mass.PositiveNumber("pitch_inertia_kgm2");
  aircraft.cg_over_chord = mass.Number("cg_over_chord");

  const TomlSection aerodynamics = root.Section("aerodynamics");
  aerodynamics.RejectUnknownKeys({"CDo", "CDu", "CLu", "CMu", "CDde"});
  aircraft.CDo = aerodynamics.Number("CDo");
  if (aircraft.CDo < 0) aerodynamics.Fail("CDo", ShortNumber(aircraft.CDo), "expected CDo >= 0");
  aircraft.CDu = aerodynamics.OptionalNumber("CDu").value_or(0.0);
  aircraft.CLu = aerodynamics.OptionalNumber("CLu").value_or(0.0);
  aircraft.CMu = aerodynamics.OptionalNumber("CMu").value_or(0.0);
  aircraft.CDde = aerodynamics.OptionalNumber("CDde").value_or(0.0);

  const TomlSection limits = root.Section("limits");
  limits.RejectUnknownKeys({"stall_speed_mps", "wheel_contact_height_m", "field_elevation_m"});
  aircraft.stall_speed_mps = limits.PositiveNumber("stall_speed_mps");
  aircraft.wheel_contact_height_m = limits.PositiveNumber("wheel_contact_height_m");
  aircraft.field_elevation_m = limits.OptionalNumber("field_elevation_m").value_or(0.0);
  if (aircraft.field_elevation_m < -500 || aircraft.field_elevation_m > 9000) {
    limits.Fail("field_elevation_m", ShortNumber(aircraft.field_elevation_m),
                "expected a field elevation in [-500, 9000] m (ISA troposphere)");
  }

  ReadTable(root.Section("table"), aircraft);
  if (!(aircraft.wheel_contact_height_m < aircraft.table_heights_m.back())) {
    limits.Fail("wheel_contact_height_m", ShortNumber(aircraft.wheel_contact_height_m),
                "expected a wheel-contact height below the last finite table height " +
                    ShortNumber(aircraft.table_heights_m.back()) + " m");
  }
  return aircraft;
}

Aircraft LoadAircraftFile(const std::filesystem::path& path) {
  const std::string text = ReadTextFile(path, "aircraft file");
  return ParseAircraft(text, path.string());
}

}  // namespace gesweep
