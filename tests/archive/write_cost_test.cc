// The archive's share of the dry run's estimate (engine/archive/write_cost.h): what it measures, and
// that it leaves nothing behind. (How close the estimate comes to real sweeps is measured on the
// shipped studies in docs/sweep.md, not asserted: no timing assertion in a test.)
#include "engine/archive/write_cost.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "engine/analyses/analysis.h"

namespace gesweep {
namespace {

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

SweepPlan ModesPlan() {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table empty;
  Study study;
  study.path = "<test>";
  study.aircraft = aircraft;
  study.analyses.push_back(MakeAnalysis("modes", TomlSection(empty, "<test>", "analyses.modes"), &aircraft));
  study.design.kind = DesignKind::kGrid;
  DesignParameter heights;
  heights.id = RequireParameter("height_m");
  for (int i = 0; i < 200; ++i) heights.values.push_back(1.0 + 0.05 * i);
  study.design.parameters = {heights};
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}};
  return SweepPlan(std::move(study), ShardSpec{});
}

// A temporary directory of the test's own (TMPDIR, which std::filesystem::temp_directory_path
// reads), so that other tests' dry runs running beside it do not show in it.
class WriteCost : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (std::filesystem::temp_directory_path() / "write_cost_test.XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
    const char* previous = std::getenv("TMPDIR");
    if (previous != nullptr) previous_ = previous;
    had_previous_ = previous != nullptr;
    setenv("TMPDIR", directory_.c_str(), 1);
  }
  void TearDown() override {
    if (had_previous_) {
      setenv("TMPDIR", previous_.c_str(), 1);
    } else {
      unsetenv("TMPDIR");
    }
    std::filesystem::remove_all(directory_);
  }
  bool Empty() const { return std::filesystem::is_empty(directory_); }

  std::filesystem::path directory_;
  std::string previous_;
  bool had_previous_ = false;
};

TEST_F(WriteCost, MeasuresTheBatchesAndTheArchivesSetUpAndCloseThenDeletesTheScratchArchive) {
  SweepPlan plan = ModesPlan();
  plan.set_chunk_runs(50);  // 4 batches
  const WriteCostEstimate e = MeasureWriteCost(plan, 1e-6, 10.0, 10.0);
  EXPECT_TRUE(Empty()) << "the scratch archive is deleted";
  ASSERT_TRUE(e.measured);
  // At least one batch, at most each of the 4 once, whole batches (how many fit the budget is timing).
  EXPECT_GE(e.runs_written, 50);
  EXPECT_LE(e.runs_written, 200);
  EXPECT_EQ(e.runs_written % 50, 0);
  EXPECT_GT(e.seconds_per_run, 0.0);
  EXPECT_GT(e.encode_seconds_per_run, 0.0);
  EXPECT_LE(e.seconds_per_run_low, e.seconds_per_run);
  EXPECT_GE(e.seconds_per_run_high, e.seconds_per_run);
  EXPECT_TRUE(e.archive_measured);
  EXPECT_GT(e.open_seconds, 0.0);
  EXPECT_GT(e.close_seconds, 0.0);
}

TEST_F(WriteCost, ABatchTooDearForTheBudgetIsSkippedButTheArchivesSetUpAndCloseAreStillTimed) {
  SweepPlan plan = ModesPlan();
  // 200 runs of 1 s each against a budget of 1 s: no batch is computed.
  const WriteCostEstimate e = MeasureWriteCost(plan, 1.0, 1.0, 1.0);
  EXPECT_TRUE(Empty()) << "the scratch archive is deleted";
  EXPECT_FALSE(e.measured);
  EXPECT_EQ(e.runs_written, 0);
  EXPECT_EQ(e.seconds_per_run, 0.0);
  EXPECT_TRUE(e.archive_measured);
  EXPECT_GT(e.open_seconds, 0.0);
  EXPECT_GT(e.close_seconds, 0.0);
}

}  // namespace
}  // namespace gesweep
