// `gesweep simulate` end to end: the CSV header and row count, the JSON layout, and refusals of bad
// flags with exit code 2 and one line naming the flag (docs/simulation.md).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

struct Output {
  int exit_code = -1;
  std::string out;
  std::string err;
};

Output RunGesweep(const std::string& arguments) {
  const std::string err_path = std::string(GESWEEP_BINARY_DIR) + "/simulate_cli_test.stderr";
  const std::string command = std::string(GESWEEP_BINARY_DIR) +
                              "/gesweep simulate --aircraft " GESWEEP_SOURCE_DIR
                              "/studies/aircraft/ance.toml " +
                              arguments + " 2>" + err_path;
  Output result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer;
  std::size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (FILE* err = std::fopen(err_path.c_str(), "r")) {
    while ((n = fread(buffer.data(), 1, buffer.size(), err)) > 0) result.err.append(buffer.data(), n);
    std::fclose(err);
  }
  return result;
}

TEST(SimulateCliTest, CsvHasUnitSuffixedHeaderAndOneRowPerSample) {
  const Output r = RunGesweep("--height-m 2.0 --speed-mps 32.0208 --duration-s 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string header;
  std::getline(lines, header);
  EXPECT_EQ(header,
            "time_s,height_m,speed_mps,delta_u_mps,delta_w_mps,pitch_rate_radps,delta_theta_rad,delta_h_m,"
            "elevator_rad");
  int rows = 0;
  std::string line, last;
  while (std::getline(lines, line)) {
    ++rows;
    last = line;
  }
  // Samples at 0, 0.015, …, 0.99 (67) and the end point 1.0, which is off the grid.
  EXPECT_EQ(rows, 68);
  EXPECT_EQ(last.substr(0, 2), "1,");
}

TEST(SimulateCliTest, JsonHasSummaryAndSeries) {
  const Output r = RunGesweep("--height-m 1.0374 --speed-mps 32.0208 --format json --output-dt-s 0.1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const auto& summary = j.at("summary");
  EXPECT_EQ(summary.at("end_event"), "touchdown");  // the paper: starts this low sink to the ground
  EXPECT_EQ(summary.at("final_state").size(), 5u);
  EXPECT_DOUBLE_EQ(summary.at("final_height_m").get<double>(), 0.788);
  for (const char* key : {"end_time_s", "min_height_m", "min_height_time_s", "max_abs_pitch_rate_radps",
                          "steps", "rhs_calls"}) {
    EXPECT_TRUE(summary.contains(key)) << key;
  }
  const auto& series = j.at("series");
  EXPECT_EQ(series.at("time_s").size(), series.at("height_m").size());
  EXPECT_EQ(series.at("time_s").back(), summary.at("end_time_s"));

  const Output s = RunGesweep("--height-m 1.0374 --speed-mps 32.0208 --format json --summary-only");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_TRUE(nlohmann::json::parse(s.out).at("series").is_null());
}

TEST(SimulateCliTest, BadFlagsExitWithCodeTwoAndNameTheFlag) {
  struct Case {
    const char* arguments;
    const char* mentions;
  };
  for (const Case& c :
       {Case{"--height-m 2 --speed-mps 32 --dt-s 0", "--dt-s"},
        Case{"--height-m 2 --speed-mps -3", "--speed-mps"},
        Case{"--height-m 0.5 --speed-mps 32", "wheel-contact"}, Case{"--height-m 2 --speed-mps 20", "stall"},
        Case{"--height-m 2 --speed-mps 32 --integrator euler", "--integrator"},
        Case{"--height-m 2 --speed-mps 32 --duration-s -1", "--duration-s"},
        Case{"--height-m 2 --speed-mps 32 --pulse-s 0", "--pulse-s"}}) {
    const Output r = RunGesweep(c.arguments);
    EXPECT_EQ(r.exit_code, 2) << c.arguments;
    EXPECT_TRUE(r.out.empty()) << c.arguments;  // nothing half-written
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.arguments << ": " << r.err;
  }
}

}  // namespace
