// The archive: its layout and attributes, the values it stores (against direct engine calls),
// refusal to overwrite, resume after a clean stop, and merge of shards (equal, bit for bit, to one
// process's archive; refused when a shard is missing, overlaps, is incomplete or foreign).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_merge.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/modal/modal_analysis.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

class ArchiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("gesweep_archive_test_" + std::to_string(getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(directory_);
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  // A modes study over speed × height (and a scale factor when `scale` differs from 1).
  std::filesystem::path StudyFile(const std::string& name, int chunk_runs, double speed_top = 40.0) {
    const auto path = directory_ / name;
    std::ofstream(path)
        << "format_version = 1\nname = \"" << name << "\"\naircraft = \"" << kAircraft
        << "\"\n[analyses.modes]\n[output]\nchunk_runs = " << chunk_runs
        << "\n[design]\nkind = \"grid\"\n[[design.parameter]]\nname = \"speed_mps\"\nlinspace = [28.0, "
        << speed_top << ", 5]\n[[design.parameter]]\nname = \"height_m\"\nlinspace = [0.8, 6.0, 21]\n";
    return path;
  }

  // Runs `blocks` (all when empty) of a plan into `archive`; returns the writer's counts.
  void Run(SweepPlan& plan, const std::filesystem::path& archive, ArchiveOpenMode mode,
           std::int64_t max_blocks = -1, ArchiveOpenReport* report = nullptr) {
    ArchiveOpenReport local;
    ArchiveOpenReport& opened = report ? *report : local;
    auto writer = ArchiveWriter::Open(archive, plan, RunProvenance{"test", 2}, mode, &opened);
    std::vector<std::int64_t> blocks = opened.pending_blocks;
    if (max_blocks >= 0 && static_cast<std::int64_t>(blocks.size()) > max_blocks)
      blocks.resize(static_cast<std::size_t>(max_blocks));
    RunSweep(plan, blocks, *writer, RunnerOptions{2, nullptr, 2}, nullptr);
    writer->Finish();
  }

  // Every per-run dataset's raw bytes, by path.
  static std::map<std::string, std::vector<unsigned char>> Contents(const std::filesystem::path& archive) {
    ArchiveReader reader = ArchiveReader::Open(archive);
    std::map<std::string, std::vector<unsigned char>> contents;
    for (const std::string& path : reader.Datasets()) {
      hdf5::Handle dataset(H5Dopen2(reader.file(), path.c_str(), H5P_DEFAULT), "open");
      hdf5::Handle type(H5Dget_type(dataset.get()), "type");
      const auto dims = hdf5::Dimensions(dataset.get());
      std::size_t elements = 1;
      for (auto d : dims) elements *= static_cast<std::size_t>(d);
      std::vector<unsigned char> bytes(elements * H5Tget_size(type.get()));
      if (dims[0] == reader.run_count()) {
        reader.ReadRows(path, 0, reader.run_count(), type.get(), bytes.data());
      } else {
        H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
      }
      contents[path] = std::move(bytes);
    }
    return contents;
  }

  std::filesystem::path directory_;
};

TEST_F(ArchiveTest, StoresEveryRunWithUnitsDescriptionsAndProvenance) {
  SweepPlan plan(LoadStudy(StudyFile("s.toml", 16)), ShardSpec{});
  const auto archive = directory_ / "a.h5";
  Run(plan, archive, ArchiveOpenMode::kCreate);
  EXPECT_FALSE(std::filesystem::exists(archive.string() + ".partial"));
  EXPECT_FALSE(std::filesystem::exists(archive.string() + ".lock"));

  ArchiveReader reader = ArchiveReader::Open(archive);
  EXPECT_FALSE(reader.snapshot());
  EXPECT_EQ(reader.run_count(), 105);
  EXPECT_EQ(reader.StringAttribute("format"), "gesweep-archive");
  EXPECT_EQ(reader.IntegerAttribute("format_version"), archive::kFormatVersion);
  EXPECT_EQ(reader.IntegerAttribute("complete"), 1);
  EXPECT_EQ(reader.IntegerAttribute("runs_ok"), 105);
  EXPECT_EQ(reader.IntegerAttribute("threads"), 2);
  EXPECT_EQ(reader.StringAttribute("shard"), "0/1");
  EXPECT_NE(reader.StringAttribute("study_text").find("[analyses.modes]"), std::string::npos);
  EXPECT_NE(reader.StringAttribute("aircraft_text").find("ANCE"), std::string::npos);
  EXPECT_FALSE(reader.StringAttribute("git_commit").empty());
  EXPECT_FALSE(reader.StringAttribute("compiler").empty());
  EXPECT_FALSE(reader.StringAttribute("start_time").empty());
  EXPECT_FALSE(reader.StringAttribute("end_time").empty());

  // Every dataset says what it holds and in which units.
  for (const std::string& path : reader.Datasets()) {
    hdf5::Handle dataset(H5Dopen2(reader.file(), path.c_str(), H5P_DEFAULT), "open");
    EXPECT_TRUE(hdf5::ReadStringAttribute(dataset.get(), "units").has_value()) << path;
    EXPECT_FALSE(hdf5::ReadStringAttribute(dataset.get(), "description").value_or("").empty()) << path;
  }

  // The values: each run's margin and eigenvalues equal a direct eigen-analysis of its parameters.
  const auto speeds = reader.ReadDoubles("design/speed_mps", 0, 105);
  const auto heights = reader.ReadDoubles("design/height_m", 0, 105);
  const auto margins = reader.ReadDoubles("results/modes/stability_margin_per_s", 0, 105);
  const auto index = reader.ReadDoubles(archive::kRunIndex, 0, 105);
  std::vector<double> eigenvalues(105 * 10);
  hdf5::Handle complex = hdf5::ComplexType();
  reader.ReadRows("results/modes/eigenvalues", 0, 105, complex.get(), eigenvalues.data());
  const LongitudinalModel model(LoadAircraftFile(kAircraft), ModelOptions{});
  for (int i = 0; i < 105; ++i) {
    EXPECT_EQ(index[static_cast<std::size_t>(i)], i);
    EXPECT_EQ(speeds[static_cast<std::size_t>(i)], 28.0 + 3.0 * (i / 21));
    const ModalAnalysis direct = AnalyzeModes(
        model.StateMatrix(heights[static_cast<std::size_t>(i)], speeds[static_cast<std::size_t>(i)]));
    EXPECT_EQ(margins[static_cast<std::size_t>(i)], direct.stability_margin_per_s);
    EXPECT_EQ(eigenvalues[static_cast<std::size_t>(i * 10 + 3)], direct.eigenvalues[1].imag());
  }
  for (auto s : reader.ReadStatus(0, 105)) EXPECT_EQ(s, 1);
}

TEST_F(ArchiveTest, NeverOverwritesWithoutResumeOrForceAndNeedsAnExistingDirectory) {
  const auto study = StudyFile("s.toml", 16);
  const auto archive = directory_ / "a.h5";
  std::ofstream(archive) << "precious";
  SweepPlan plan(LoadStudy(study), ShardSpec{});
  EXPECT_THROW(ArchiveWriter::Open(archive, plan, RunProvenance{}, ArchiveOpenMode::kCreate, nullptr),
               InputError);
  std::ifstream in(archive);
  std::string text;
  in >> text;
  EXPECT_EQ(text, "precious");
  EXPECT_THROW(ArchiveWriter::Open(directory_ / "missing" / "a.h5", plan, RunProvenance{},
                                   ArchiveOpenMode::kCreate, nullptr),
               InputError);
  EXPECT_FALSE(std::filesystem::exists(directory_ / "missing"));
  // --force replaces it.
  Run(plan, archive, ArchiveOpenMode::kForce);
  EXPECT_EQ(ArchiveReader::Open(archive).run_count(), 105);
}

TEST_F(ArchiveTest, ResumeAfterACleanStopRunsOnlyThePendingBatchesAndEqualsAnUninterruptedRun) {
  const auto study = StudyFile("s.toml", 8);
  SweepPlan reference_plan(LoadStudy(study), ShardSpec{});
  Run(reference_plan, directory_ / "reference.h5", ArchiveOpenMode::kCreate);

  SweepPlan plan(LoadStudy(study), ShardSpec{});
  const auto archive = directory_ / "resumed.h5";
  Run(plan, archive, ArchiveOpenMode::kCreate, 5);  // 5 of 14 batches, then a clean stop
  {
    ArchiveReader partial = ArchiveReader::Open(archive);
    EXPECT_EQ(partial.IntegerAttribute("complete"), 0);
    EXPECT_EQ(partial.IntegerAttribute("runs_pending"), 105 - 40);
  }
  SweepPlan again(LoadStudy(study), ShardSpec{});
  ArchiveOpenReport report;
  Run(again, archive, ArchiveOpenMode::kResume, -1, &report);
  EXPECT_EQ(report.kind, ArchiveOpenReport::Kind::kResumedClean);
  EXPECT_EQ(report.runs_complete, 40);
  EXPECT_EQ(report.pending_blocks.size(), 9u);
  EXPECT_EQ(report.pending_blocks.front(), 5);
  EXPECT_EQ(Contents(archive), Contents(directory_ / "reference.h5"));
  ArchiveReader done = ArchiveReader::Open(archive);
  EXPECT_EQ(done.IntegerAttribute("complete"), 1);
  EXPECT_FALSE(done.StringAttribute("resumed_at").empty());
  EXPECT_EQ(done.StringAttribute("resumed_at").find(","), std::string::npos) << "resumed once";
}

TEST_F(ArchiveTest, ResumeRefusesAnArchiveOfAnotherStudy) {
  SweepPlan plan(LoadStudy(StudyFile("s.toml", 8)), ShardSpec{});
  const auto archive = directory_ / "a.h5";
  Run(plan, archive, ArchiveOpenMode::kCreate, 2);
  SweepPlan other(LoadStudy(StudyFile("s.toml", 8, 45.0)), ShardSpec{});
  try {
    ArchiveWriter::Open(archive, other, RunProvenance{}, ArchiveOpenMode::kResume, nullptr);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.expected().find("study fingerprint"), std::string::npos);
  }
  SweepPlan shard(LoadStudy(StudyFile("s.toml", 8)), ShardSpec{1, 2});
  EXPECT_THROW(ArchiveWriter::Open(archive, shard, RunProvenance{}, ArchiveOpenMode::kResume, nullptr),
               InputError);
}

TEST_F(ArchiveTest, MergedShardsEqualOneProcessBitForBit) {
  const auto study = StudyFile("s.toml", 8);
  SweepPlan whole(LoadStudy(study), ShardSpec{});
  Run(whole, directory_ / "whole.h5", ArchiveOpenMode::kCreate);
  std::vector<std::filesystem::path> shards;
  for (int i = 2; i >= 0; --i) {  // any order
    SweepPlan plan(LoadStudy(study), ShardSpec{i, 3});
    shards.push_back(directory_ / ("shard" + std::to_string(i) + ".h5"));
    Run(plan, shards.back(), ArchiveOpenMode::kCreate);
  }
  const MergeReport report = MergeArchives(shards, directory_ / "merged.h5", false, "test");
  EXPECT_EQ(report.shards, 3);
  EXPECT_EQ(report.runs, 105);
  EXPECT_EQ(report.runs_ok, 105);
  EXPECT_EQ(Contents(directory_ / "merged.h5"), Contents(directory_ / "whole.h5"));
  ArchiveReader merged = ArchiveReader::Open(directory_ / "merged.h5");
  EXPECT_EQ(merged.StringListAttribute("merged_from").size(), 3u);
  EXPECT_EQ(merged.IntegerAttribute("complete"), 1);
}

TEST_F(ArchiveTest, MergeNamesMissingOverlappingIncompleteAndForeignShards) {
  const auto study = StudyFile("s.toml", 8);
  std::vector<std::filesystem::path> shards;
  for (int i = 0; i < 3; ++i) {
    SweepPlan plan(LoadStudy(study), ShardSpec{i, 3});
    shards.push_back(directory_ / ("shard" + std::to_string(i) + ".h5"));
    Run(plan, shards.back(), ArchiveOpenMode::kCreate);
  }
  const auto out = directory_ / "merged.h5";
  auto error_of = [&](const std::vector<std::filesystem::path>& inputs) {
    try {
      MergeArchives(inputs, out, false, "test");
    } catch (const InputError& e) {
      EXPECT_FALSE(std::filesystem::exists(out));
      return std::string(e.what());
    }
    ADD_FAILURE() << "expected an InputError";
    return std::string();
  };
  EXPECT_NE(error_of({shards[0], shards[2]}).find("shard 1/3 not given"), std::string::npos);
  EXPECT_NE(error_of({shards[0], shards[1], shards[1], shards[2]}).find("overlaps"), std::string::npos);

  SweepPlan partial(LoadStudy(study), ShardSpec{1, 3});
  const auto incomplete = directory_ / "incomplete.h5";
  Run(partial, incomplete, ArchiveOpenMode::kCreate, 1);
  EXPECT_NE(error_of({shards[0], incomplete, shards[2]}).find("is incomplete"), std::string::npos);

  SweepPlan foreign(LoadStudy(StudyFile("t.toml", 8, 45.0)), ShardSpec{1, 3});
  const auto other = directory_ / "other.h5";
  Run(foreign, other, ArchiveOpenMode::kCreate);
  EXPECT_NE(error_of({shards[0], other, shards[2]}).find("same study"), std::string::npos);
}

TEST_F(ArchiveTest, ReaderRefusesWhatIsNotAnArchive) {
  std::ofstream(directory_ / "text.h5") << "not hdf5";
  EXPECT_THROW(ArchiveReader::Open(directory_ / "text.h5"), InputError);
  EXPECT_THROW(ArchiveReader::Open(directory_ / "absent.h5"), InputError);
}

TEST(SeriesChunkRows, DividesTheBatchAndStaysUnderAMebibyte) {
  EXPECT_EQ(SeriesChunkRows(256, 2001), 64);  // 64 × 2001 × 8 B = 1 024 512 B ≤ 1 MiB; 128 rows would not be
  EXPECT_EQ(SeriesChunkRows(256, 100000), 1);  // one run's series is bigger than a chunk: one per chunk
  EXPECT_EQ(SeriesChunkRows(10, 100), 10);
  EXPECT_EQ(SeriesChunkRows(7, 100000), 1);
}

}  // namespace
}  // namespace gesweep
