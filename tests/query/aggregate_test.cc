// engine/query/aggregate.h on archives written in-process by the real sweep: every statistic per
// group against an independent computation in this file (a sort per group, long-double sums, the
// two-pass variance) on the raw columns; exact medians and quantiles equal whatever the memory budget
// (one pass, or many passes of collecting and histogram narrowing, including heavy ties that
// narrow to a single value); missing values skipped; the refusals (bad items, too many groups, an
// unknown --sort) before any output.
#include "engine/query/aggregate.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Streaming mean and Welford's variance against long-double two-pass sums: a few ulps of the values'
// scale per 10^4 runs.
constexpr double kMomentRelative = 1e-12;

struct Collector : QueryRowSink {
  std::vector<std::string> names;
  std::vector<std::vector<QueryCell>> rows;
  QuerySummary summary;
  bool begun = false;
  void Begin(const std::vector<const RunColumn*>& columns) override {
    begun = true;
    for (const auto* c : columns) names.push_back(c->name);
  }
  void Row(const std::vector<QueryCell>& cells) override { rows.push_back(cells); }
  void End(const QuerySummary& s) override { summary = s; }
};

std::filesystem::path WriteArchive(const std::filesystem::path& directory, const std::string& name,
                                   const std::string& body) {
  const auto study_path = directory / (name + ".toml");
  std::ofstream(study_path) << "format_version = 1\nname = \"" << name << "\"\naircraft = \""
                            << testing::AnceAircraftPath().string() << "\"\n"
                            << body;
  SweepPlan plan(LoadStudy(study_path), ShardSpec{});
  const auto archive_path = directory / (name + ".h5");
  ArchiveOpenReport report;
  auto writer =
      ArchiveWriter::Open(archive_path, plan, RunProvenance{name, 2}, ArchiveOpenMode::kCreate, &report);
  RunSweep(plan, report.pending_blocks, *writer, RunnerOptions{2, nullptr, 2}, nullptr);
  writer->Finish();
  return archive_path;
}

class AggregateTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    directory_ = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                           ("gesweep_aggregate_test_" + std::to_string(getpid())));
    std::filesystem::remove_all(*directory_);
    std::filesystem::create_directories(*directory_);
    // 20,000 modes runs: 10 speeds x 2000 heights.
    modes_ = new std::filesystem::path(WriteArchive(*directory_, "modes_grid",
                                                    "[analyses.modes]\n[output]\nchunk_runs = 1024\n"
                                                    "[design]\nkind = \"grid\"\n"
                                                    "[[design.parameter]]\nname = \"speed_mps\"\n"
                                                    "linspace = [26.0, 60.0, 10]\n"
                                                    "[[design.parameter]]\nname = \"height_m\"\n"
                                                    "logspace = [0.79, 14.0, 2000]\n"));
    // 400 runs with a per-run boundary: NaN where a speed has none.
    boundary_ = new std::filesystem::path(WriteArchive(*directory_, "boundary_grid",
                                                       "[analyses.modes]\n[analyses.boundary]\n[output]\n"
                                                       "chunk_runs = 64\n[design]\nkind = \"grid\"\n"
                                                       "[[design.parameter]]\nname = \"h_derivatives\"\n"
                                                       "values = [true, false]\n"
                                                       "[[design.parameter]]\nname = \"speed_mps\"\n"
                                                       "values = [25.0, 28.0, 32.0208, 45.0, 60.0]\n"
                                                       "[[design.parameter]]\nname = \"height_m\"\n"
                                                       "logspace = [0.79, 14.0, 40]\n"));
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*directory_);
    delete directory_;
    delete modes_;
    delete boundary_;
  }

  static Collector Run(const std::filesystem::path& path, AggregateRequest request) {
    const ArchiveReader archive = ArchiveReader::Open(path);
    const ColumnCatalog catalog = ColumnCatalog::Of(archive);
    Collector sink;
    RunAggregateQuery(archive, catalog, request, sink);
    return sink;
  }

  static std::string Refusal(const std::filesystem::path& path, AggregateRequest request) {
    const ArchiveReader archive = ArchiveReader::Open(path);
    const ColumnCatalog catalog = ColumnCatalog::Of(archive);
    Collector sink;
    try {
      RunAggregateQuery(archive, catalog, request, sink);
    } catch (const InputError& e) {
      EXPECT_FALSE(sink.begun) << "output begun before the refusal";
      return e.what();
    }
    return "";
  }

  static std::vector<double> Raw(const std::filesystem::path& path, const std::string& dataset) {
    const ArchiveReader archive = ArchiveReader::Open(path);
    return archive.ReadDoubles(dataset, 0, archive.run_count());
  }

  static std::filesystem::path* directory_;
  static std::filesystem::path* modes_;
  static std::filesystem::path* boundary_;
};

std::filesystem::path* AggregateTest::directory_ = nullptr;
std::filesystem::path* AggregateTest::modes_ = nullptr;
std::filesystem::path* AggregateTest::boundary_ = nullptr;

// The oracle: statistics of `values` (NaN skipped) computed the plain way.
struct Expected {
  double count = 0, min = NAN, max = NAN, mean = NAN, std1 = NAN, std0 = NAN, median = NAN;
  std::map<double, double> quantiles;
};

Expected Compute(std::vector<double> values, const std::vector<double>& ps) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }),
               values.end());
  std::sort(values.begin(), values.end());
  Expected e;
  const auto n = values.size();
  e.count = static_cast<double>(n);
  if (n == 0) return e;
  e.min = values.front();
  e.max = values.back();
  long double sum = 0;
  for (double v : values) sum += v;
  const long double mean = sum / static_cast<long double>(n);
  long double squares = 0;
  for (double v : values) squares += (v - mean) * (v - mean);
  e.mean = static_cast<double>(mean);
  e.std0 = static_cast<double>(std::sqrt(squares / static_cast<long double>(n)));
  e.std1 = n > 1 ? static_cast<double>(std::sqrt(squares / static_cast<long double>(n - 1))) : NAN;
  e.median = n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2.0;
  for (double p : ps) {
    // NumPy's "linear": h = (n - 1) p, between the neighbours, computed from the upper one for a
    // fraction >= 1/2 (numpy.lib.function_base._lerp).
    const double h = static_cast<double>(n - 1) * p;
    const auto lo = static_cast<std::size_t>(std::floor(h));
    if (lo + 1 >= n) {
      e.quantiles[p] = values[n - 1];
      continue;
    }
    const double t = h - static_cast<double>(lo), a = values[lo], b = values[lo + 1];
    e.quantiles[p] = t >= 0.5 ? b - (b - a) * (1 - t) : a + (b - a) * t;
  }
  return e;
}

void ExpectNear(double actual, double expected, const std::string& what) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what << ": " << actual;
    return;
  }
  EXPECT_NEAR(actual, expected, kMomentRelative * std::max(1.0, std::abs(expected))) << what;
}

TEST_F(AggregateTest, EveryStatisticPerGroupEqualsAPlainComputation) {
  const std::vector<double> speed = Raw(*modes_, "design/speed_mps");
  const std::vector<double> sigma = Raw(*modes_, "results/modes/stability_margin_per_s");
  std::map<double, std::vector<double>> by_speed;
  for (std::size_t i = 0; i < speed.size(); ++i) by_speed[speed[i]].push_back(sigma[i]);
  ASSERT_EQ(by_speed.size(), 10U);

  AggregateRequest request;
  request.group_by = {"speed_mps"};
  request.aggregates = {
      "count, count(stability_margin_per_s), min(stability_margin_per_s), max(stability_margin_per_s)",
      "mean(stability_margin_per_s),std(stability_margin_per_s),std(stability_margin_per_s, 0)",
      "median(stability_margin_per_s), quantile(stability_margin_per_s, "
      "0.05),quantile(stability_margin_per_s,0.95)",
      "quantile(stability_margin_per_s, 0), quantile(stability_margin_per_s, 1), "
      "sum(stability_margin_per_s)"};
  const Collector result = Run(*modes_, request);
  ASSERT_EQ(result.names.size(), 14U);
  EXPECT_EQ(result.names[0], "speed_mps");
  EXPECT_EQ(result.names[9], "quantile(stability_margin_per_s, 0.05)");
  EXPECT_EQ(result.names[6], "std(stability_margin_per_s)");
  EXPECT_EQ(result.names[7], "std(stability_margin_per_s, 0)");
  ASSERT_EQ(result.rows.size(), 10U);
  EXPECT_EQ(result.summary.groups, 10);
  EXPECT_EQ(result.summary.matched, 20000);
  EXPECT_EQ(result.summary.passes, 1);
  std::size_t r = 0;
  for (const auto& [group_speed, values] : by_speed) {  // ascending, as the output
    const auto& row = result.rows[r++];
    const Expected e = Compute(values, {0.05, 0.95, 0.0, 1.0});
    EXPECT_EQ(row[0].number, group_speed);
    EXPECT_EQ(row[1].number, 2000);
    EXPECT_EQ(row[2].number, e.count);
    EXPECT_EQ(row[3].number, e.min);
    EXPECT_EQ(row[4].number, e.max);
    ExpectNear(row[5].number, e.mean, "mean");
    ExpectNear(row[6].number, e.std1, "std ddof 1");
    ExpectNear(row[7].number, e.std0, "std ddof 0");
    EXPECT_EQ(row[8].number, e.median);  // order statistics are exact
    EXPECT_EQ(row[9].number, e.quantiles.at(0.05));
    EXPECT_EQ(row[10].number, e.quantiles.at(0.95));
    EXPECT_EQ(row[11].number, e.min);
    EXPECT_EQ(row[12].number, e.max);
    ExpectNear(row[13].number, e.mean * e.count, "sum");
  }
}

TEST_F(AggregateTest, MediansAndQuantilesAreExactWhateverTheMemoryBudget) {
  const std::vector<double> sigma = Raw(*modes_, "results/modes/stability_margin_per_s");
  const std::vector<double> height = Raw(*modes_, "design/height_m");
  const std::vector<double> speed = Raw(*modes_, "design/speed_mps");
  const Expected sigma_all = Compute(sigma, {0.001, 0.37, 0.999});
  const Expected height_all = Compute(height, {0.25});
  const Expected speed_all = Compute(speed, {0.3, 0.85});  // 10 values, 2000 times each: ties
  AggregateRequest request;
  request.aggregates = {"median(stability_margin_per_s), quantile(stability_margin_per_s, 0.001)",
                        "quantile(stability_margin_per_s, 0.37), quantile(stability_margin_per_s, 0.999)",
                        "median(height_m), quantile(height_m, 0.25), quantile(speed_mps, 0.3)",
                        "quantile(speed_mps, 0.85), median(speed_mps)"};
  const std::vector<double> expected = {sigma_all.median,
                                        sigma_all.quantiles.at(0.001),
                                        sigma_all.quantiles.at(0.37),
                                        sigma_all.quantiles.at(0.999),
                                        height_all.median,
                                        height_all.quantiles.at(0.25),
                                        speed_all.quantiles.at(0.3),
                                        speed_all.quantiles.at(0.85),
                                        speed_all.median};
  // 20,000 values per column x 3 columns x 16 bytes = 960 KB kept by one pass; smaller budgets need
  // collecting passes (64 KB, 1 MB per column) or histogram narrowing (16 KB: one histogram at a time).
  for (const std::int64_t budget : {std::int64_t{16} << 10, std::int64_t{64} << 10, std::int64_t{400} << 10,
                                    std::int64_t{1} << 20, std::int64_t{256} << 20}) {
    request.memory_bytes = budget;
    const Collector result = Run(*modes_, request);
    ASSERT_EQ(result.rows.size(), 1U);
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_EQ(result.rows[0][k].number, expected[k]) << result.names[k] << " with a budget of " << budget;
    }
    if (budget >= (std::int64_t{1} << 20)) {
      EXPECT_EQ(result.summary.passes, 1) << budget;
    } else {
      EXPECT_GT(result.summary.passes, 1) << budget;
    }
  }
  // Grouped, with a budget that holds some groups' values but not all: collecting passes per group.
  AggregateRequest grouped;
  grouped.group_by = {"speed_mps"};
  grouped.aggregates = {"median(stability_margin_per_s), quantile(height_m, 0.9)"};
  const Collector large = Run(*modes_, grouped);
  grouped.memory_bytes = 40 << 10;  // 2 x 2000 values of a group need 64 KB: one column of one group
  const Collector small = Run(*modes_, grouped);
  EXPECT_GT(small.summary.passes, 2);
  ASSERT_EQ(small.rows.size(), large.rows.size());
  for (std::size_t g = 0; g < large.rows.size(); ++g) {
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(small.rows[g][k].number, large.rows[g][k].number) << g << k;
  }
}

TEST_F(AggregateTest, MissingValuesAreSkippedAndLevelsCountAsCodes) {
  const std::vector<double> boundary = Raw(*boundary_, "results/boundary/height_m");
  const std::vector<double> speed = Raw(*boundary_, "design/speed_mps");
  const std::vector<double> h_derivatives = Raw(*boundary_, "design/h_derivatives");
  const std::vector<double> stable = Raw(*boundary_, "results/modes/stable");
  // (h_derivatives, speed) -> boundary heights and stable flags
  std::map<std::pair<double, double>, std::vector<double>> heights, flags;
  for (std::size_t i = 0; i < speed.size(); ++i) {
    heights[{h_derivatives[i], speed[i]}].push_back(boundary[i]);
    flags[{h_derivatives[i], speed[i]}].push_back(stable[i]);
  }
  AggregateRequest request;
  request.group_by = {"h_derivatives", "speed_mps"};
  request.aggregates = {"count, count(boundary/height_m), median(boundary/height_m), min(boundary/height_m)",
                        "mean(stable)"};
  const Collector result = Run(*boundary_, request);
  ASSERT_EQ(result.rows.size(), 10U);
  bool some_missing = false, some_empty = false;
  std::size_t r = 0;
  for (const auto& [key, values] : heights) {  // h_derivatives false (0) first, then speed ascending
    const auto& row = result.rows[r++];
    EXPECT_EQ(row[0].number, key.first);
    EXPECT_EQ(row[1].number, key.second);
    const Expected e = Compute(values, {});
    EXPECT_EQ(row[2].number, 40);
    EXPECT_EQ(row[3].number, e.count);
    some_missing = some_missing || e.count < 40;
    some_empty = some_empty || e.count == 0;
    if (e.count == 0) {
      EXPECT_TRUE(std::isnan(row[4].number) && std::isnan(row[5].number));
    } else {
      EXPECT_EQ(row[4].number, e.median);
      EXPECT_EQ(row[5].number, e.min);
    }
    const std::vector<double>& f = flags.at(key);
    ExpectNear(row[6].number, static_cast<double>(std::count(f.begin(), f.end(), 1.0)) / 40.0,
               "fraction stable");
  }
  EXPECT_TRUE(some_missing);  // the test means something only if some runs have no boundary
  EXPECT_TRUE(some_empty);    // and some groups none at all (25 m/s; no h-derivatives)
}

TEST_F(AggregateTest, WhereSortAndLimitApplyToRunsThenGroups) {
  AggregateRequest request;
  request.where = "stability_margin_per_s > 0";
  request.group_by = {"speed_mps"};
  request.aggregates = {"count", "max(height_m)"};
  request.sort = "count";
  request.descending = true;
  request.limit = 3;
  const Collector result = Run(*modes_, request);
  const std::vector<double> speed = Raw(*modes_, "design/speed_mps");
  const std::vector<double> sigma = Raw(*modes_, "results/modes/stability_margin_per_s");
  std::map<double, int> unstable;
  for (std::size_t i = 0; i < speed.size(); ++i) {
    if (sigma[i] > 0) ++unstable[speed[i]];
  }
  std::vector<int> counts;
  for (const auto& [s, c] : unstable) counts.push_back(c);
  std::sort(counts.rbegin(), counts.rend());
  ASSERT_EQ(result.rows.size(), 3U);
  EXPECT_EQ(result.summary.groups, static_cast<std::int64_t>(unstable.size()));
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(result.rows[k][1].number, counts[k]);
  // --sort by an aggregate written another way, or by a group column.
  request.sort = "max( design/height_m )";
  request.descending = false;
  request.limit = -1;
  const Collector by_height = Run(*modes_, request);
  for (std::size_t k = 1; k < by_height.rows.size(); ++k)
    EXPECT_LE(by_height.rows[k - 1][2].number, by_height.rows[k][2].number);
}

TEST_F(AggregateTest, RefusalsComeBeforeAnyOutput) {
  AggregateRequest request;
  request.aggregates = {"mean(stability_margin)"};
  EXPECT_NE(Refusal(*modes_, request).find("unknown column 'stability_margin'"), std::string::npos);
  request.aggregates = {"avg(height_m)"};
  EXPECT_NE(Refusal(*modes_, request).find("unknown statistic 'avg'"), std::string::npos);
  request.aggregates = {"quantile(height_m, 1.5)"};
  EXPECT_NE(Refusal(*modes_, request).find("expected a probability 0 <= p <= 1, found '1.5'"),
            std::string::npos);
  request.aggregates = {"quantile(height_m)"};
  EXPECT_NE(Refusal(*modes_, request).find("quantile takes a column and a probability"), std::string::npos);
  request.aggregates = {"std(height_m, 2)"};
  EXPECT_NE(Refusal(*modes_, request).find("expected ddof 0 (population) or 1 (sample)"), std::string::npos);
  request.aggregates = {"mean(message)"};
  EXPECT_NE(Refusal(*modes_, request).find("message is text"), std::string::npos);
  request.aggregates = {"median"};
  EXPECT_NE(Refusal(*modes_, request).find("median needs a column"), std::string::npos);
  request.aggregates = {"count"};
  request.group_by = {"height_m"};
  request.max_groups = 1999;
  EXPECT_NE(Refusal(*modes_, request).find("more than 1999 groups"), std::string::npos);
  request.max_groups = 2000;
  EXPECT_EQ(Refusal(*modes_, request), "");
  request.sort = "mean(height_m)";
  EXPECT_NE(Refusal(*modes_, request).find("sort by an output column: one of height_m, count"),
            std::string::npos);
}

TEST_F(AggregateTest, WildcardsExpandToOneStatisticPerNumericColumn) {
  AggregateRequest request;
  request.group_by = {"/design/*"};
  request.aggregates = {"max(phugoid/*)"};
  const Collector result = Run(*modes_, request);
  ASSERT_GE(result.names.size(), 4U);
  EXPECT_EQ(result.names[0], "speed_mps");
  EXPECT_EQ(result.names[1], "height_m");
  for (std::size_t k = 2; k < result.names.size(); ++k)
    EXPECT_EQ(result.names[k].rfind("max(phugoid/", 0), 0U) << result.names[k];
  EXPECT_EQ(result.rows.size(), 20000U);
}

}  // namespace
}  // namespace gesweep
