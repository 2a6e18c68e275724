// The archive: its layout and attributes, the values it stores (against direct engine calls),
// refusal to overwrite, resume after a clean stop, and merge of shards (equal, bit for bit, to one
// process's archive; refused when a shard is missing, overlaps, is incomplete or foreign).
#include <gtest/gtest.h>

#include <cstdio>
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

TEST(ArchiveFormat, FingerprintTextIsSixteenLowercaseHexDigits) {
  // Oracle: C's printf conversion %016llx, which the attribute has been written as.
  for (const unsigned long long value : {0ULL, 0x1234abcdULL, 0x00ff00ff00ff00ffULL, ~0ULL}) {
    char expected[17];
    std::snprintf(expected, sizeof(expected), "%016llx", value);
    EXPECT_EQ(archive::FingerprintText(value), expected) << value;
  }
}

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

// Every stored chunk of every dataset, as bytes (the filtered chunks themselves, not the values).
std::map<std::string, std::vector<unsigned char>> StoredChunks(const std::filesystem::path& archive) {
  ArchiveReader reader = ArchiveReader::Open(archive);
  std::map<std::string, std::vector<unsigned char>> chunks;
  for (const std::string& path : reader.Datasets()) {
    hdf5::Handle dataset(H5Dopen2(reader.file(), path.c_str(), H5P_DEFAULT), "open");
    hdf5::Handle space(H5Dget_space(dataset.get()), "space");
    hdf5::Handle dcpl(H5Dget_create_plist(dataset.get()), "dcpl");
    if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED) continue;
    hsize_t count = 0;
    H5Dget_num_chunks(dataset.get(), space.get(), &count);
    for (hsize_t i = 0; i < count; ++i) {
      hsize_t offset[2] = {0, 0};
      unsigned mask = 0;
      haddr_t address = 0;
      hsize_t size = 0;
      H5Dget_chunk_info(dataset.get(), space.get(), i, offset, &mask, &address, &size);
      std::vector<unsigned char> bytes(size);
      std::uint32_t filters = 0;
      H5Dread_chunk(dataset.get(), H5P_DEFAULT, offset, &filters, bytes.data());
      bytes.push_back(static_cast<unsigned char>(filters));
      chunks[path + "@" + std::to_string(offset[0])] = std::move(bytes);
    }
  }
  return chunks;
}

TEST_F(ArchiveTest, OneAndTwoThreadsStoreTheSameChunksByteForByte) {
  const auto study = StudyFile("s.toml", 8);
  SweepPlan one(LoadStudy(study), ShardSpec{});
  {
    auto writer = ArchiveWriter::Open(directory_ / "one.h5", one, RunProvenance{"test", 1},
                                      ArchiveOpenMode::kCreate, nullptr);
    RunSweep(one, std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13}, *writer,
             RunnerOptions{1, nullptr, 1}, nullptr);
    writer->Finish();
  }
  SweepPlan two(LoadStudy(study), ShardSpec{});
  Run(two, directory_ / "two.h5", ArchiveOpenMode::kCreate);
  EXPECT_EQ(Contents(directory_ / "one.h5"), Contents(directory_ / "two.h5"));
  const auto chunks = StoredChunks(directory_ / "one.h5");
  EXPECT_EQ(chunks.size(), StoredChunks(directory_ / "two.h5").size());
  EXPECT_TRUE(chunks == StoredChunks(directory_ / "two.h5"));
  EXPECT_GT(chunks.size(), 14u * 30u);  // every dataset has a chunk per batch (runs/message none: no message)
}

TEST_F(ArchiveTest, ThreeShardsMergedVirtuallyOrByCopyEqualOneProcess) {
  const auto study = StudyFile("s.toml", 8);
  SweepPlan whole(LoadStudy(study), ShardSpec{});
  Run(whole, directory_ / "whole.h5", ArchiveOpenMode::kCreate);
  std::vector<std::filesystem::path> shards;
  std::uintmax_t shard_bytes = 0;
  for (int i = 0; i < 3; ++i) {
    SweepPlan plan(LoadStudy(study), ShardSpec{i, 3});
    EXPECT_EQ(plan.first_run() % 8, 0) << "shards start at a batch boundary";
    shards.push_back(directory_ / ("shard" + std::to_string(i) + ".h5"));
    Run(plan, shards.back(), ArchiveOpenMode::kCreate);
    shard_bytes += std::filesystem::file_size(shards.back());
  }
  const MergeReport virtual_report = MergeArchives(shards, directory_ / "virtual.h5", false, "test");
  EXPECT_EQ(virtual_report.kind, MergeKind::kVirtual);
  EXPECT_EQ(virtual_report.sources, (std::vector<std::string>{"shard0.h5", "shard1.h5", "shard2.h5"}));
  EXPECT_EQ(Contents(directory_ / "virtual.h5"), Contents(directory_ / "whole.h5"));
  {
    ArchiveReader reader = ArchiveReader::Open(directory_ / "virtual.h5");
    EXPECT_EQ(reader.StringAttribute("merge_kind"), "virtual");
    hdf5::Handle status(H5Dopen2(reader.file(), "runs/status", H5P_DEFAULT), "open");
    hdf5::Handle dcpl(H5Dget_create_plist(status.get()), "dcpl");
    EXPECT_EQ(H5Pget_layout(dcpl.get()), H5D_VIRTUAL);
  }

  const MergeReport copy_report =
      MergeArchives(shards, directory_ / "copy.h5", false, "test", MergeKind::kCopy);
  EXPECT_EQ(Contents(directory_ / "copy.h5"), Contents(directory_ / "whole.h5"));
  EXPECT_GT(copy_report.chunks_copied, 0);
  EXPECT_EQ(copy_report.chunks_rewritten, 0) << "shards cut at batch boundaries: every chunk coincides";
  // The copy holds the shards' chunks as they were stored: the same bytes as one process's archive.
  EXPECT_TRUE(StoredChunks(directory_ / "copy.h5") == StoredChunks(directory_ / "whole.h5"));
  // The virtual archive is small: a mapping, not a copy.
  EXPECT_LT(std::filesystem::file_size(directory_ / "virtual.h5"), shard_bytes);

  // A shard the virtual archive reads is moved away: refused, naming it (HDF5 would read fill values).
  std::filesystem::rename(shards[1], directory_ / "moved.h5");
  try {
    ArchiveReader::Open(directory_ / "virtual.h5");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shard1.h5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must stay"), std::string::npos) << e.what();
  }
  // The copy is self-contained.
  EXPECT_EQ(Contents(directory_ / "copy.h5"), Contents(directory_ / "whole.h5"));
}

TEST_F(ArchiveTest, ShardsOfASmallDesignStillCoverItWhenTheyCannotAllBeWholeBatches) {
  // 105 runs in batches of 64 over 4 shards: batches of min(64, 105/4 = 26) runs, shards of whole
  // batches; merged by copy every chunk still coincides.
  const auto study = StudyFile("s.toml", 64);
  SweepPlan whole(LoadStudy(study), ShardSpec{});
  Run(whole, directory_ / "whole.h5", ArchiveOpenMode::kCreate);
  std::vector<std::filesystem::path> shards;
  for (int i = 0; i < 4; ++i) {
    SweepPlan plan(LoadStudy(study), ShardSpec{i, 4});
    EXPECT_EQ(plan.chunk_runs(), 26);  // ShardBatchRuns(105, 64, 4) = min(64, 105 / 4)
    shards.push_back(directory_ / ("shard" + std::to_string(i) + ".h5"));
    Run(plan, shards.back(), ArchiveOpenMode::kCreate);
  }
  MergeArchives(shards, directory_ / "copy.h5", false, "test", MergeKind::kCopy);
  EXPECT_EQ(Contents(directory_ / "copy.h5"), Contents(directory_ / "whole.h5"));
  MergeArchives(shards, directory_ / "virtual.h5", false, "test");
  EXPECT_EQ(Contents(directory_ / "virtual.h5"), Contents(directory_ / "whole.h5"));
}

TEST_F(ArchiveTest, LongMessagesAreStoredWholeAndOnlyTheirChunksWritten) {
  // One long message (an LQR failure's reason runs past the old 160-byte cut) and one past the
  // limit, with multi-byte UTF-8 characters at the cut.
  SweepPlan plan(LoadStudy(StudyFile("s.toml", 64)), ShardSpec{});
  const auto archive = directory_ / "a.h5";
  auto writer =
      ArchiveWriter::Open(archive, plan, RunProvenance{"test", 1}, ArchiveOpenMode::kCreate, nullptr);
  ResultBlock block;
  block.Allocate(plan);
  block.Reset(plan, 0);
  RunWorkspace workspace(plan);
  for (int r = 0; r < block.rows; ++r)
    ExecuteRun(plan, block.design_index[static_cast<std::size_t>(r)], workspace, block, r);
  std::string lqr =
      "landing: design_failed: (Q, A) is not detectable: the mode at lambda = -0.0123+0.4567i is "
      "unweighted by Q and not stable; ";
  while (lqr.size() < 700) lqr += "the useful part of the reason continues past the old cut at 160 bytes; ";
  std::string huge;
  while (huge.size() < 3000) huge += "\u00e9t\u00e9 ";  // "été ": two-byte characters
  TruncateMessage(huge);
  EXPECT_EQ(huge.size() <= static_cast<std::size_t>(kMessageLength), true);
  EXPECT_EQ(huge.substr(huge.size() - 3), "...");
  block.message[3] = lqr;
  block.message[40] = huge;
  block.status[3] = 2;
  writer->Write(block);
  for (std::int64_t b = 1; b < plan.block_count(); ++b) {
    block.Reset(plan, b);
    for (int r = 0; r < block.rows; ++r)
      ExecuteRun(plan, block.design_index[static_cast<std::size_t>(r)], workspace, block, r);
    writer->Write(block);
  }
  writer->Finish();
  writer.reset();
  ArchiveReader reader = ArchiveReader::Open(archive);
  const auto messages = reader.ReadMessages(0, reader.run_count());
  EXPECT_EQ(messages[3], lqr);
  EXPECT_EQ(messages[40], huge);
  for (std::size_t r = 0; r < messages.size(); ++r) {
    if (r != 3 && r != 40) {
      EXPECT_EQ(messages[r], "") << r;
    }
  }
  // Sparse: the two message chunks (rows 0..63 in 64-run chunks -- one chunk) are all that is stored.
  hdf5::Handle dataset(H5Dopen2(reader.file(), "runs/message", H5P_DEFAULT), "open");
  hdf5::Handle space(H5Dget_space(dataset.get()), "space");
  hsize_t count = 0;
  H5Dget_num_chunks(dataset.get(), space.get(), &count);
  EXPECT_EQ(count, 1u);
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
