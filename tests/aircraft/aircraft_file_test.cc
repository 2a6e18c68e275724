#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>

#include "engine/aircraft/aircraft.h"
#include "engine/common/errors.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

using testing::AnceAircraftPath;
using testing::PaperDataDir;
using testing::ReadFile;

// The oracle for the transcription of ance.toml: the paper's Tables A1 and A2 as CSV in
// studies/aircraft/data (copied from the paper's Appendix A independently of ance.toml).
std::vector<std::vector<std::string>> ReadCsv(const std::filesystem::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream text(ReadFile(path));
  std::string line;
  while (std::getline(text, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::istringstream cells_text(line);
    std::string cell;
    while (std::getline(cells_text, cell, ',')) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(AircraftFile, AnceMatchesThePapersTables) {
  const Aircraft aircraft = LoadAircraftFile(AnceAircraftPath());
  const auto a2_path = PaperDataDir() / "ance_table_a2.csv";
  const auto a1_path = PaperDataDir() / "ance_table_a1.csv";
  ASSERT_TRUE(std::filesystem::is_regular_file(a1_path)) << "missing " << a1_path;
  ASSERT_TRUE(std::filesystem::is_regular_file(a2_path)) << "missing " << a2_path;

  std::map<std::string, double> a1;
  for (const auto& row : ReadCsv(a1_path)) {
    if (row[0] != "name") a1[row[0]] = std::stod(row[1]);
  }
  EXPECT_EQ(aircraft.wingspan_m, a1["wingspan"]);
  EXPECT_EQ(aircraft.mean_chord_m, a1["mean_chord"]);
  EXPECT_EQ(aircraft.wing_area_m2, a1["wing_area"]);
  EXPECT_EQ(aircraft.mass_kg, a1["mass"]);
  EXPECT_EQ(aircraft.pitch_inertia_kgm2, a1["pitch_inertia"]);
  EXPECT_EQ(aircraft.cg_over_chord, a1["cg_position"]);
  EXPECT_EQ(aircraft.CDo, a1["CDo"]);
  EXPECT_EQ(aircraft.stall_speed_mps, a1["stall_speed"]);
  EXPECT_EQ(aircraft.wheel_contact_height_m, a1["wheel_contact_height"]);

  const auto table = ReadCsv(a2_path);
  ASSERT_GE(table.size(), 2u) << a2_path << ": a header and at least one row expected";
  const auto& header = table[0];
  std::size_t finite_row = 0;
  bool free_flight_row_seen = false;
  for (std::size_t r = 1; r < table.size(); ++r) {
    const bool free_flight = table[r][0] == "inf";
    free_flight_row_seen = free_flight_row_seen || free_flight;
    if (!free_flight) {
      EXPECT_EQ(aircraft.table_heights_m[finite_row], std::stod(table[r][0]));
    }
    for (std::size_t col = 0; col < header.size(); ++col) {
      const auto coefficient = CoefficientFromName(header[col]);
      if (!coefficient) continue;
      const double expected = std::stod(table[r][col]);
      const double actual = free_flight ? aircraft.free_flight[Index(*coefficient)]
                                        : aircraft.rows[finite_row][Index(*coefficient)];
      EXPECT_EQ(actual, expected) << header[col] << " row " << r;
    }
    if (!free_flight) ++finite_row;
  }
  EXPECT_EQ(finite_row, aircraft.table_heights_m.size());
  EXPECT_TRUE(free_flight_row_seen) << a2_path << ": no free-flight (inf) row";
}

// A minimal valid aircraft, edited by each bad-input case.
std::string ValidAircraft() {
  std::string text = R"(name = "test"
[geometry]
wingspan_m = 5.0
mean_chord_m = 0.5
wing_area_m2 = 2.5
[mass]
mass_kg = 100.0
pitch_inertia_kgm2 = 50.0
cg_over_chord = 0.25
[aerodynamics]
CDo = 0.02
[limits]
stall_speed_mps = 20.0
wheel_contact_height_m = 0.5
[table]
height_m = [0.5, 1.0, 2.0]
)";
  for (int c = 0; c < kTabulatedCount; ++c) {
    text += std::string(kCoefficientNames[c]) + " = [0.1, 0.2, 0.3]\n";
  }
  text += "[table.free_flight]\n";
  for (int c = 0; c < kTabulatedCount; ++c) text += std::string(kCoefficientNames[c]) + " = 0.3\n";
  return text;
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Expects ParseAircraft to throw an InputError whose message contains every fragment.
void ExpectRejected(const std::string& text, std::initializer_list<std::string> fragments) {
  try {
    ParseAircraft(text, "bad.toml");
    ADD_FAILURE() << "accepted an invalid aircraft; expected: " << *fragments.begin();
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("bad.toml"), std::string::npos) << message;
    for (const auto& fragment : fragments) EXPECT_NE(message.find(fragment), std::string::npos) << message;
  }
}

TEST(AircraftFile, ValidMinimalFileLoads) {
  const Aircraft aircraft = ParseAircraft(ValidAircraft(), "ok.toml");
  EXPECT_EQ(aircraft.rows.size(), 3u);
  EXPECT_EQ(aircraft.rows[2][Index(Coefficient::CMh)], 0.3);
}

TEST(AircraftFile, RejectsBadInputNamingKeyAndProblem) {
  const std::string ok = ValidAircraft();
  ExpectRejected(Replace(ok, "wingspan_m = 5.0\n", ""), {"geometry.wingspan_m", "missing"});
  ExpectRejected(Replace(ok, "wingspan_m", "wingspam_m"),
                 {"geometry.wingspam_m", "did you mean 'wingspan_m'"});
  ExpectRejected(Replace(ok, "mass_kg = 100.0", "mass_kg = \"heavy\""),
                 {"mass.mass_kg", "\"heavy\"", "number"});
  ExpectRejected(Replace(ok, "mass_kg = 100.0", "mass_kg = -1.0"), {"mass.mass_kg", "> 0"});
  ExpectRejected(Replace(ok, "CDo = 0.02", "CDo = nan"), {"aerodynamics.CDo", "finite"});
  ExpectRejected(Replace(ok, "mean_chord_m = 0.5", "mean_chord_m = inf"),
                 {"geometry.mean_chord_m", "finite"});
  ExpectRejected(Replace(ok, "height_m = [0.5, 1.0, 2.0]", "height_m = [0.5, 2.0, 1.0]"),
                 {"table.height_m", "strictly increasing"});
  ExpectRejected(Replace(ok, "CLh = [0.1, 0.2, 0.3]", "CLh = [0.1, 0.2]"), {"table.CLh", "3 values"});
  ExpectRejected(Replace(ok, "CMq = [0.1, 0.2, 0.3]", "CMq = [0.1, inf, 0.3]"), {"table.CMq[1]", "finite"});
  ExpectRejected(Replace(ok, "CLo = [0.1, 0.2, 0.3]\n", ""), {"table.CLo", "missing"});
  ExpectRejected(Replace(ok, "[geometry]", "[geometry\n"), {"TOML syntax error"});
  ExpectRejected(Replace(ok, "wheel_contact_height_m = 0.5", "wheel_contact_height_m = 2.5"),
                 {"limits.wheel_contact_height_m", "below the last finite table height 2"});
  ExpectRejected(ok + "extra = 1\n", {"table.free_flight.extra", "unknown key"});
}

TEST(AircraftFile, ErrorsCarryTheLine) {
  try {
    ParseAircraft(Replace(ValidAircraft(), "mass_kg = 100.0", "mass_kg = -1.0"), "bad.toml");
    FAIL() << "accepted a negative mass";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 7);  // the line of `mass_kg` in ValidAircraft()
  }
}

TEST(AircraftFile, MissingFileIsAnInputError) {
  EXPECT_THROW(LoadAircraftFile("/nonexistent/aircraft.toml"), InputError);
}

}  // namespace
}  // namespace gesweep
