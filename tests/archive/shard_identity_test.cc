// Shard identity (issue 26): every archive's identity, written once; a virtual archive's record of
// its sources; the reader refusing each way a source can go wrong (replaced, re-run for another
// shard, swapped, copied over, deleted, a link to the merge, of another study, a cycle) before it reads
// a value; merge as a writer (the output's lock, the guard over the files its inputs read), --copy of
// a virtual archive, a '%' in a shard's path, and archives written before identities.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "engine/archive/archive_identity.h"
#include "engine/archive/archive_merge.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

namespace fs = std::filesystem;

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";
const fs::path kOldArchives = fs::path(GESWEEP_SOURCE_DIR) / "tests/bad_inputs/old_archives";

class ShardIdentityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ =
        fs::temp_directory_path() / ("gesweep_identity_test_" + std::to_string(getpid()) + "_" +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(directory_);
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  // 40 modes runs over speed x height in batches of 8; another top speed is another study.
  fs::path StudyFile(const std::string& name, double speed_top = 40.0) {
    const auto path = directory_ / name;
    std::ofstream(path) << "format_version = 1\nname = \"" << name << "\"\naircraft = \"" << kAircraft
                        << "\"\n[analyses.modes]\n[output]\nchunk_runs = 8\n[design]\nkind = \"grid\"\n"
                        << "[[design.parameter]]\nname = \"speed_mps\"\nlinspace = [28.0, " << speed_top
                        << ", 4]\n[[design.parameter]]\nname = \"height_m\"\nlinspace = [0.8, 6.0, 10]\n";
    return path;
  }

  // Runs shard `shard` of `study` (whole when shard.count is 1) into `archive`, `max_blocks` batches
  // of it (all when negative), in `mode`.
  void Run(const fs::path& study, ShardSpec shard, const fs::path& archive,
           ArchiveOpenMode mode = ArchiveOpenMode::kCreate, std::int64_t max_blocks = -1,
           ArchiveOpenReport* report = nullptr) {
    SweepPlan plan(LoadStudy(study), shard);
    ArchiveOpenReport local;
    ArchiveOpenReport& opened = report ? *report : local;
    auto writer = ArchiveWriter::Open(archive, plan, RunProvenance{"test", 2}, mode, &opened);
    std::vector<std::int64_t> blocks = opened.pending_blocks;
    if (max_blocks >= 0 && static_cast<std::int64_t>(blocks.size()) > max_blocks)
      blocks.resize(static_cast<std::size_t>(max_blocks));
    RunSweep(plan, blocks, *writer, RunnerOptions{2, nullptr, 2}, nullptr);
    writer->Finish();
  }

  // shard0.h5 and shard1.h5 (shards 0/2, 1/2 of s.toml), merged virtually into merged.h5; returns it.
  fs::path MergedOfTwoShards() {
    const auto study = StudyFile("s.toml");
    for (int i = 0; i < 2; ++i) Run(study, ShardSpec{i, 2}, Shard(i));
    MergeArchives({Shard(0), Shard(1)}, directory_ / "merged.h5", false, "test");
    return directory_ / "merged.h5";
  }
  fs::path Shard(int i) const { return directory_ / ("shard" + std::to_string(i) + ".h5"); }

  // Every per-run dataset's raw bytes, by path.
  static std::map<std::string, std::vector<unsigned char>> Contents(const fs::path& archive) {
    ArchiveReader reader = ArchiveReader::Open(archive);
    std::map<std::string, std::vector<unsigned char>> contents;
    for (const std::string& path : reader.Datasets()) {
      hdf5::Handle dataset(H5Dopen2(reader.file(), path.c_str(), H5P_DEFAULT), "open");
      hdf5::Handle type(H5Dget_type(dataset.get()), "type");
      const auto dims = hdf5::Dimensions(dataset.get());
      if (dims.empty() || dims[0] != reader.run_count()) continue;
      std::size_t elements = 1;
      for (auto d : dims) elements *= static_cast<std::size_t>(d);
      std::vector<unsigned char> bytes(elements * H5Tget_size(type.get()));
      reader.ReadRows(path, 0, reader.run_count(), type.get(), bytes.data());
      contents[path] = std::move(bytes);
    }
    return contents;
  }

  // The message Open(archive) refuses it with (a failure when it opens).
  static std::string Refusal(const fs::path& archive) {
    try {
      ArchiveReader::Open(archive);
    } catch (const InputError& e) {
      return e.what();
    }
    ADD_FAILURE() << archive << " opened";
    return "";
  }

  static std::string Root(const fs::path& archive, const std::string& name) {
    return ArchiveReader::Open(archive).StringAttribute(name);
  }

  fs::path directory_;
};

bool IsArchiveId(const std::string& id) {
  return id.size() == 32 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
}

TEST(ArchiveId, Is128RandomBitsInHex) {
  // 32 hex digits; 1000 draws all distinct (two equal 128-bit draws: probability ~1e-33).
  std::set<std::string> seen;
  for (int i = 0; i < 1000; ++i) {
    const std::string id = archive::NewArchiveId();
    EXPECT_TRUE(IsArchiveId(id)) << id;
    seen.insert(id);
  }
  EXPECT_EQ(seen.size(), 1000u);
}

TEST(VirtualFilePattern, DoublesEveryPercentSign) {
  EXPECT_EQ(archive::VirtualFilePattern("a/b.h5"), "a/b.h5");
  EXPECT_EQ(archive::VirtualFilePattern("x%b/%%/s%.h5"), "x%%b/%%%%/s%%.h5");
}

TEST(SourceCandidates, FollowHdf5sOrder) {
  // HDF5 1.10's H5F_prefix_open_file and H5D__build_file_prefix: the environment's prefixes, the
  // whole value with ${ORIGIN} expanded, the archive's directory, the working directory.
  ::unsetenv("HDF5_VDS_PREFIX");
  EXPECT_EQ(archive::SourceCandidates("/data/run/m.h5", "s0.h5"),
            (std::vector<fs::path>{"/data/run/s0.h5", "s0.h5", "/data/run/s0.h5"}));
  ::setenv("HDF5_VDS_PREFIX", "/p:/q/", 1);
  EXPECT_EQ(archive::SourceCandidates("/data/run/m.h5", "s0.h5"),
            (std::vector<fs::path>{"/p/s0.h5", "/q/s0.h5", "/p:/q/s0.h5", "/data/run/s0.h5", "s0.h5",
                                   "/data/run/s0.h5"}));
  ::setenv("HDF5_VDS_PREFIX", "${ORIGIN}/sub", 1);
  EXPECT_EQ(archive::SourceCandidates("/data/run/m.h5", "s0.h5"),
            (std::vector<fs::path>{"${ORIGIN}/sub/s0.h5", "/data/run//sub/s0.h5", "/data/run/s0.h5", "s0.h5",
                                   "/data/run/s0.h5"}));
  ::unsetenv("HDF5_VDS_PREFIX");
  // An absolute name first as given, then its last component where HDF5 looks.
  EXPECT_EQ(archive::SourceCandidates("/data/run/m.h5", "/old/place/s0.h5"),
            (std::vector<fs::path>{"/old/place/s0.h5", "/data/run/s0.h5", "s0.h5", "/data/run/s0.h5"}));
}

TEST_F(ShardIdentityTest, EveryArchiveGetsItsOwnIdentityWhichAResumeKeepsAndForceRenews) {
  const auto study = StudyFile("s.toml");
  Run(study, ShardSpec{}, directory_ / "a.h5", ArchiveOpenMode::kCreate, 2);
  Run(study, ShardSpec{}, directory_ / "b.h5");
  const std::string a = Root(directory_ / "a.h5", "archive_id");
  EXPECT_TRUE(IsArchiveId(a)) << a;
  EXPECT_NE(a, Root(directory_ / "b.h5", "archive_id"));
  // Resumed in place: the same archive.
  ArchiveOpenReport report;
  Run(study, ShardSpec{}, directory_ / "a.h5", ArchiveOpenMode::kResume, 1, &report);
  EXPECT_EQ(report.kind, ArchiveOpenReport::Kind::kResumedClean);
  EXPECT_EQ(Root(directory_ / "a.h5", "archive_id"), a);
  // Resumed into a fresh file (a reader holds it open): still the same archive.
  {
    ArchiveReader holder = ArchiveReader::Open(directory_ / "a.h5");
    Run(study, ShardSpec{}, directory_ / "a.h5", ArchiveOpenMode::kResume, 1, &report);
    EXPECT_EQ(report.kind, ArchiveOpenReport::Kind::kResumedAfterCrash);
  }
  EXPECT_EQ(Root(directory_ / "a.h5", "archive_id"), a);
  // Replaced: another archive.
  Run(study, ShardSpec{}, directory_ / "a.h5", ArchiveOpenMode::kForce);
  const std::string forced = Root(directory_ / "a.h5", "archive_id");
  EXPECT_TRUE(IsArchiveId(forced));
  EXPECT_NE(forced, a);
}

TEST_F(ShardIdentityTest, AVirtualMergeRecordsEachSourcesIdentity) {
  const auto merged = MergedOfTwoShards();
  ArchiveReader reader = ArchiveReader::Open(merged);
  EXPECT_TRUE(reader.is_virtual());
  EXPECT_TRUE(reader.notes().empty());
  const std::string id = reader.StringAttribute("archive_id");
  EXPECT_TRUE(IsArchiveId(id));
  std::vector<std::string> ids;
  for (int i = 0; i < 2; ++i) ids.push_back(Root(Shard(i), "archive_id"));
  EXPECT_EQ(reader.StringListAttribute("virtual_source_ids"), ids);
  EXPECT_EQ(reader.StringListAttribute("merged_from_ids"), ids);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), id), 0) << "the merge is an archive of its own";
  EXPECT_EQ(reader.StringListAttribute("virtual_source_shards"), (std::vector<std::string>{"0/2", "1/2"}));
  ASSERT_EQ(reader.sources().size(), 2u);
  for (int i = 0; i < 2; ++i) {
    ArchiveReader shard = ArchiveReader::Open(Shard(i));
    const auto& source = reader.sources()[static_cast<std::size_t>(i)];
    EXPECT_TRUE(fs::equivalent(source.path, Shard(i)));
    EXPECT_EQ(source.identity.first_run, shard.IntegerAttribute("first_run"));
    EXPECT_EQ(source.identity.run_count, shard.run_count());
  }
  EXPECT_EQ(reader.files_read().size(), 2u);
}

TEST_F(ShardIdentityTest, TheReaderRefusesEveryWayASourceGoesWrongBeforeReadingAValue) {
  const auto merged = MergedOfTwoShards();
  const auto study = directory_ / "s.toml";
  const fs::path keep0 = directory_ / "keep0.h5", keep1 = directory_ / "keep1.h5";
  fs::copy_file(Shard(0), keep0);
  fs::copy_file(Shard(1), keep1);
  auto restore = [&] {
    fs::remove(Shard(0));
    fs::remove(Shard(1));
    fs::copy_file(keep0, Shard(0));
    fs::copy_file(keep1, Shard(1));
  };
  auto expect = [&](const std::string& what, const std::string& fragment) {
    const std::string message = Refusal(merged);
    EXPECT_NE(message.find(merged.string() + ": virtual_sources = "), std::string::npos)
        << what << ": " << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << what << ": " << message;
    EXPECT_NE(message.find("merge again"), std::string::npos) << what << ": " << message;
    restore();
  };
  const std::string at0 = "shard file " + Shard(0).string(), at1 = "shard file " + Shard(1).string();
  // Shard 0/2 holds runs 0..15 (two batches of 8 of the 40), shard 1/2 runs 16..39.
  const std::string holds_one = "holds runs 16..39 of 40 (shard 1/2), expected runs 0..15 of 40 (shard 0/2)";

  Run(study, ShardSpec{1, 2}, Shard(0), ArchiveOpenMode::kForce);  // re-run with the wrong shard
  expect("re-run for the wrong shard", at0 + " " + holds_one);
  Run(study, ShardSpec{0, 2}, Shard(0), ArchiveOpenMode::kForce);  // re-run of the same runs
  expect("re-run", at0 + " is not the file that was merged: its archive_id is ");
  fs::rename(Shard(0), directory_ / "t.h5");
  fs::rename(Shard(1), Shard(0));
  fs::rename(directory_ / "t.h5", Shard(1));
  expect("swapped", at0 + " " + holds_one);
  fs::copy_file(Shard(1), Shard(0), fs::copy_options::overwrite_existing);
  expect("copied over", at0 + " " + holds_one);
  fs::remove(Shard(1));
  expect("deleted", at1 + " is missing");
  fs::create_directory(directory_ / "away");
  fs::rename(Shard(1), directory_ / "away" / "shard1.h5");
  expect("moved", at1 + " is missing");
  fs::remove(Shard(0));
  fs::create_symlink("merged.h5", Shard(0));
  expect("a link to the merge", at0 + " is this virtual archive itself");
  fs::remove(Shard(1));
  Run(StudyFile("t.toml", 45.0), ShardSpec{1, 2}, Shard(1));
  expect("another study", at1 + " is an archive of another study");
  fs::remove(Shard(1));
  Run(study, ShardSpec{1, 2}, Shard(1), ArchiveOpenMode::kCreate, 1);
  expect("incomplete", at1 + " is not complete");
  fs::remove(Shard(1));
  std::ofstream(Shard(1)) << "not an archive";
  expect("not HDF5", at1 + " cannot be opened");
  // Put back: it reads again.
  EXPECT_EQ(ArchiveReader::Open(merged).run_count(), 40);
}

TEST_F(ShardIdentityTest, ArchivesWrittenBeforeIdentitiesAreReadWithANoteAndStillChecked) {
  for (const auto& entry : fs::directory_iterator(kOldArchives))
    fs::copy_file(entry.path(), directory_ / entry.path().filename());
  std::vector<std::string> sent;
  archive::SetArchiveNoteHandler([&](const std::string& note) { sent.push_back(note); });
  {
    ArchiveReader merged = ArchiveReader::Open(directory_ / "merged.h5");
    ASSERT_EQ(merged.notes().size(), 1u);
    EXPECT_NE(merged.notes()[0].find("merged before shard identities"), std::string::npos)
        << merged.notes()[0];
    EXPECT_EQ(sent, merged.notes());
    // The runs are the shards' runs.
    const auto all = merged.ReadDoubles("results/modes/stability_margin_per_s", 0, 8);
    const auto first =
        ArchiveReader::Open(directory_ / "s0.h5").ReadDoubles("results/modes/stability_margin_per_s", 0, 4);
    const auto second =
        ArchiveReader::Open(directory_ / "s1.h5").ReadDoubles("results/modes/stability_margin_per_s", 0, 4);
    EXPECT_EQ(std::vector<double>(all.begin(), all.begin() + 4), first);
    EXPECT_EQ(std::vector<double>(all.begin() + 4, all.end()), second);
    EXPECT_TRUE(ArchiveReader::Open(directory_ / "s0.h5").notes().empty())
        << "a plain archive has no sources";
  }
  archive::SetArchiveNoteHandler(nullptr);
  // Without identities, the mapping still says which runs each shard holds.
  fs::rename(directory_ / "s0.h5", directory_ / "t.h5");
  fs::rename(directory_ / "s1.h5", directory_ / "s0.h5");
  fs::rename(directory_ / "t.h5", directory_ / "s1.h5");
  EXPECT_NE(
      Refusal(directory_ / "merged.h5").find("holds runs 4..7 of 8 (shard 1/2), expected runs 0..3 of 8"),
      std::string::npos);
  fs::rename(directory_ / "s0.h5", directory_ / "t.h5");
  fs::rename(directory_ / "s1.h5", directory_ / "s0.h5");
  fs::rename(directory_ / "t.h5", directory_ / "s1.h5");
  // nested.h5 reads merged.h5, nested2.h5 reads nested.h5: in merged.h5's place, a cycle. The readers
  // of 0.1.0 died with SIGSEGV on it inside libhdf5; it is refused, never followed.
  fs::rename(directory_ / "merged.h5", directory_ / "merged_away.h5");
  fs::rename(directory_ / "nested2.h5", directory_ / "merged.h5");
  const std::string cycle = Refusal(directory_ / "nested.h5");
  EXPECT_NE(cycle.find("is the virtual archive " + (directory_ / "nested.h5").string() + " again"),
            std::string::npos)
      << cycle;
  EXPECT_NE(cycle.find("cycle"), std::string::npos) << cycle;
}

TEST_F(ShardIdentityTest, MergeRefusesAnOutputItsInputsReadAndOneASweepIsWriting) {
  const auto merged = MergedOfTwoShards();
  const fs::path keep = directory_ / "keep.h5";
  fs::copy_file(Shard(0), keep);
  try {
    MergeArchives({merged}, Shard(0), /*force=*/true, "test");
    FAIL() << "merged onto a shard its input reads";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("that the input " + merged.string() + " reads"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(Contents(Shard(0)), Contents(keep));
  EXPECT_EQ(Root(Shard(0), "archive_id"), Root(keep, "archive_id"));
  EXPECT_EQ(ArchiveReader::Open(merged).run_count(), 40);

  // A sweep writing the output holds its lock: merge --force does not replace it under the sweep.
  const auto live = directory_ / "live.h5";
  SweepPlan plan(LoadStudy(directory_ / "s.toml"), ShardSpec{});
  auto sweep = ArchiveWriter::Open(live, plan, RunProvenance{"test", 1}, ArchiveOpenMode::kCreate, nullptr);
  try {
    MergeArchives({Shard(0), Shard(1)}, live, /*force=*/true, "test");
    FAIL() << "merged onto a live sweep";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("archive in use"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(live.string() + ".partial"));
  sweep->Finish();
  sweep.reset();
  EXPECT_EQ(ArchiveReader::Open(live).StringAttribute("merge_kind"), "") << "still the sweep's archive";
  // Once the sweep has finished, the merge may replace it (--force), and leaves no lock file.
  MergeArchives({Shard(0), Shard(1)}, live, /*force=*/true, "test");
  EXPECT_EQ(ArchiveReader::Open(live).StringAttribute("merge_kind"), "virtual");
  EXPECT_FALSE(fs::exists(live.string() + ".lock"));
}

TEST_F(ShardIdentityTest, CopyOfAVirtualArchiveIsSelfContainedAndEqualRunForRun) {
  const auto merged = MergedOfTwoShards();
  Run(directory_ / "s.toml", ShardSpec{}, directory_ / "whole.h5");
  const auto whole = Contents(directory_ / "whole.h5");
  EXPECT_EQ(Contents(merged), whole);
  const MergeReport copied = MergeArchives({merged}, directory_ / "copy.h5", false, "test", MergeKind::kCopy);
  EXPECT_EQ(copied.chunks_rewritten, 0) << "the shards' chunks copied raw";
  EXPECT_GT(copied.chunks_copied, 0);
  // A virtual merge of a virtual archive maps the shard files themselves.
  const MergeReport mapped = MergeArchives({merged}, directory_ / "again.h5", false, "test");
  EXPECT_EQ(mapped.sources, (std::vector<std::string>{"shard0.h5", "shard1.h5"}));
  EXPECT_EQ(Contents(directory_ / "again.h5"), whole);
  fs::remove(Shard(0));
  fs::remove(Shard(1));
  ArchiveReader copy = ArchiveReader::Open(directory_ / "copy.h5");
  EXPECT_FALSE(copy.is_virtual());
  EXPECT_EQ(copy.StringAttribute("merge_kind"), "copy");
  EXPECT_TRUE(copy.StringListAttribute("virtual_sources").empty());
  EXPECT_EQ(Contents(directory_ / "copy.h5"), whole);
}

TEST_F(ShardIdentityTest, APercentSignInAShardsPathReachesHdf5Escaped) {
  const auto study = StudyFile("s.toml");
  Run(study, ShardSpec{}, directory_ / "whole.h5");
  const fs::path odd = directory_ / "100%b %% d%s";
  fs::create_directory(odd);
  const fs::path s0 = odd / "s%b0.h5", s1 = odd / "s%%1.h5";
  Run(study, ShardSpec{0, 2}, s0);
  Run(study, ShardSpec{1, 2}, s1);
  const auto whole = Contents(directory_ / "whole.h5");
  const MergeReport report = MergeArchives({s0, s1}, directory_ / "virtual.h5", false, "test");
  EXPECT_EQ(report.sources, (std::vector<std::string>{"100%b %% d%s/s%b0.h5", "100%b %% d%s/s%%1.h5"}));
  EXPECT_EQ(Contents(directory_ / "virtual.h5"), whole);
  MergeArchives({s0, s1}, odd / "in%here.h5", false, "test");
  EXPECT_EQ(Contents(odd / "in%here.h5"), whole);
  MergeArchives({directory_ / "virtual.h5"}, directory_ / "copy.h5", false, "test", MergeKind::kCopy);
  EXPECT_EQ(Contents(directory_ / "copy.h5"), whole);
}

}  // namespace
}  // namespace gesweep
