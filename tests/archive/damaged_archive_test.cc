// Damaged archives (issue 26, item 8; docs/reliability.md 11.4): the child-process guard
// (archive::RunInChild, GuardArchiveDecode) and ArchiveReader::Open of the eight files on which
// libhdf5 1.10.8 itself hangs or crashes (tests/fuzz/hdf5_defects), each refused with one InputError
// naming the file, in time, its bytes unchanged; a resume onto a truncated archive that is not one of
// its study leaves the file as it was.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "engine/archive/archive_error.h"
#include "engine/archive/archive_probe.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

namespace fs = std::filesystem;
using archive::ProbeOutcome;

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";
const fs::path kDefects = fs::path(GESWEEP_SOURCE_DIR) / "tests/fuzz/hdf5_defects";

// The brief's bound on each refusal (the default deadline is 3 s).
constexpr double kRefusalSeconds = 5.0;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class DamagedArchiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("GESWEEP_ARCHIVE_CHECK_S");
    directory_ =
        fs::temp_directory_path() / ("gesweep_damaged_test_" + std::to_string(getpid()) + "_" +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(directory_);
    fs::create_directories(directory_);
  }
  void TearDown() override {
    unsetenv("GESWEEP_ARCHIVE_CHECK_S");
    fs::remove_all(directory_);
  }

  // 16 modes runs over height in batches of 4; another speed is another study.
  fs::path StudyFile(const std::string& name, double speed_mps) {
    const auto path = directory_ / name;
    std::ofstream(path) << "format_version = 1\nname = \"" << name << "\"\naircraft = \"" << kAircraft
                        << "\"\n[analyses.modes]\n[output]\nchunk_runs = 4\n[parameters]\nspeed_mps = "
                        << speed_mps << "\n[design]\nkind = \"grid\"\n[[design.parameter]]\nname = "
                        << "\"height_m\"\nlinspace = [1.0, 5.0, 16]\n";
    return path;
  }

  void Run(const fs::path& study, const fs::path& archive) {
    SweepPlan plan(LoadStudy(study), ShardSpec{0, 1});
    ArchiveOpenReport opened;
    auto writer =
        ArchiveWriter::Open(archive, plan, RunProvenance{"test", 1}, ArchiveOpenMode::kCreate, &opened);
    RunSweep(plan, opened.pending_blocks, *writer, RunnerOptions{1, nullptr, 1}, nullptr);
    writer->Finish();
  }

  fs::path directory_;
};

TEST_F(DamagedArchiveTest, ChildOutcomes) {
  EXPECT_EQ(archive::RunInChild([] {}, 5).kind, ProbeOutcome::Kind::kFinished);
  // A refusal in the child comes back as the same error, rebuilt here.
  const ProbeOutcome threw = archive::RunInChild([] { throw InputError("x.h5", "key", "v", "why\tnot"); }, 5);
  ASSERT_EQ(threw.kind, ProbeOutcome::Kind::kThrew);
  try {
    std::rethrow_exception(threw.error);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), std::string(InputError("x.h5", "key", "v", "why\tnot").what()));
    EXPECT_EQ(e.source(), "x.h5");
  }
  const ProbeOutcome request = archive::RunInChild(
      [] { throw RequestError("y.h5", "", "", "cut short", "resume_repairs", "y.h5"); }, 5);
  ASSERT_EQ(request.kind, ProbeOutcome::Kind::kThrew);
  EXPECT_EQ(request.remedy, "resume_repairs");
  EXPECT_THROW(std::rethrow_exception(request.error), RequestError);
  const ProbeOutcome archive_error = archive::RunInChild([] { throw ArchiveError("read x: bad", "bad"); }, 5);
  ASSERT_EQ(archive_error.kind, ProbeOutcome::Kind::kThrew);
  EXPECT_THROW(std::rethrow_exception(archive_error.error), ArchiveError);
  const ProbeOutcome segv = archive::RunInChild([] { std::raise(SIGSEGV); }, 5);
  EXPECT_EQ(segv.kind, ProbeOutcome::Kind::kSignal);
  EXPECT_EQ(segv.signal, SIGSEGV);
  const ProbeOutcome abrt = archive::RunInChild([] { std::abort(); }, 5);
  EXPECT_EQ(abrt.kind, ProbeOutcome::Kind::kSignal);
  EXPECT_EQ(abrt.signal, SIGABRT);
  const ProbeOutcome exited = archive::RunInChild([] { _exit(1); }, 5);  // AddressSanitizer's way
  EXPECT_EQ(exited.kind, ProbeOutcome::Kind::kExited);
  EXPECT_EQ(exited.exit_code, 1);
  // A child that never ends is killed at the deadline (SIGINT and SIGTERM it ignores).
  const auto start = std::chrono::steady_clock::now();
  const ProbeOutcome hung = archive::RunInChild(
      [] {
        for (;;) pause();
      },
      0.3);
  EXPECT_EQ(hung.kind, ProbeOutcome::Kind::kTimedOut);
  EXPECT_LT(SecondsSince(start), 0.3 + 2.0);
  EXPECT_GE(SecondsSince(start), 0.3);
}

TEST_F(DamagedArchiveTest, GuardNamesTheFile) {
  try {
    archive::GuardArchiveDecode("some/archive.h5", [] { std::raise(SIGSEGV); });
    FAIL() << "a crash in the child must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "some/archive.h5");
    EXPECT_NE(
        std::string(e.what()).find("libhdf5 crashed (SIGSEGV) while decoding the file: a damaged archive"),
        std::string::npos)
        << e.what();
  }
  setenv("GESWEEP_ARCHIVE_CHECK_S", "0.2", 1);
  try {
    archive::GuardArchiveDecode("slow.h5", [] {
      for (;;) pause();
    });
    FAIL() << "a child past the deadline must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did not finish decoding the file within 0.2 s"), std::string::npos)
        << e.what();
  }
  setenv("GESWEEP_ARCHIVE_CHECK_S", "soon", 1);
  EXPECT_THROW(archive::GuardArchiveDecode("x.h5", [] {}), InputError);
  setenv("GESWEEP_ARCHIVE_CHECK_S", "0.01", 1);
  EXPECT_THROW(archive::GuardArchiveDecode("x.h5", [] {}), InputError);
  // Off: the probe is not run in a child at all (here: it would have been refused).
  setenv("GESWEEP_ARCHIVE_CHECK_S", "0", 1);
  EXPECT_NO_THROW(archive::GuardArchiveDecode("x.h5", [] { std::raise(SIGSEGV); }));
}

TEST_F(DamagedArchiveTest, EveryHdf5DefectIsOneInputError) {
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(kDefects)) {
    if (entry.path().filename() == "README.md") continue;
    ++seen;
    const std::string input = Bytes(entry.path());
    ASSERT_FALSE(input.empty());
    ASSERT_EQ(input[0], '\0') << entry.path() << ": not a raw-file input";
    const fs::path file = directory_ / (entry.path().filename().string() + ".h5");
    std::ofstream(file, std::ios::binary) << input.substr(1);
    const auto start = std::chrono::steady_clock::now();
    try {
      ArchiveReader::Open(file);
      ADD_FAILURE() << file << ": opened";
    } catch (const InputError& e) {
      // libhdf5 crashed or hung in the child (the guard's line), or failed cleanly there (the reader's
      // refusal, sent back): either way this process did not decode the file.
      EXPECT_EQ(e.source(), file.string());
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
    EXPECT_LT(SecondsSince(start), kRefusalSeconds) << file;
    EXPECT_EQ(Bytes(file), input.substr(1)) << file << ": changed";
  }
  EXPECT_EQ(seen, 8);
}

TEST_F(DamagedArchiveTest, HealthyArchiveStillOpens) {
  const fs::path archive = directory_ / "ok.h5";
  Run(StudyFile("a.toml", 32.0), archive);
  const std::string before = Bytes(archive);
  const ArchiveReader reader = ArchiveReader::Open(archive);
  EXPECT_EQ(reader.run_count(), 16);
  EXPECT_EQ(reader.ReadMessages(0, 16).size(), 16U);
  EXPECT_EQ(Bytes(archive), before);
}

TEST_F(DamagedArchiveTest, RefusedResumeOfATruncatedArchiveChangesNothing) {
  const fs::path other = directory_ / "other.h5";
  Run(StudyFile("b.toml", 33.0), other);
  const std::string whole = Bytes(other);
  const fs::path archive = directory_ / "cut.h5";
  const std::string cut = whole.substr(0, whole.size() * 3 / 4);
  std::ofstream(archive, std::ios::binary) << cut;
  SweepPlan plan(LoadStudy(StudyFile("a.toml", 32.0)), ShardSpec{0, 1});
  EXPECT_THROW(
      ArchiveWriter::Open(archive, plan, RunProvenance{"test", 1}, ArchiveOpenMode::kResume, nullptr),
      InputError);
  EXPECT_EQ(Bytes(archive), cut) << "a refused resume changed the file";
  EXPECT_FALSE(fs::exists(archive.string() + ".repair"));
  EXPECT_FALSE(fs::exists(archive.string() + ".partial"));
  // A reader (no repair) says what it is, and changes nothing either.
  EXPECT_THROW(ArchiveReader::Open(archive), InputError);
  EXPECT_EQ(Bytes(archive), cut);
}

TEST_F(DamagedArchiveTest, RepairedCopyIsRemovedWithTheReader) {
  // A file shorter than HDF5 recorded: Open(repair) reads a copy extended to the recorded size.
  const fs::path whole = directory_ / "whole.h5";
  Run(StudyFile("a.toml", 32.0), whole);
  const std::string bytes = Bytes(whole);
  const fs::path archive = directory_ / "short.h5";
  const std::string cut = bytes.substr(0, bytes.size() - 1);
  std::ofstream(archive, std::ios::binary) << cut;
  EXPECT_THROW(ArchiveReader::Open(archive), InputError);  // refused, saying why
  try {
    ArchiveReader reader = ArchiveReader::Open(archive, /*repair_truncated=*/true);
    EXPECT_TRUE(reader.repaired());
    EXPECT_TRUE(fs::exists(archive.string() + ".repair"));
    EXPECT_EQ(reader.path(), archive);
    reader.Close();
  } catch (const InputError& e) {
    // The last byte may be metadata the copy's zeros cannot stand for; then it is refused.
    EXPECT_EQ(e.source(), archive.string());
  }
  EXPECT_FALSE(fs::exists(archive.string() + ".repair"));
  EXPECT_EQ(Bytes(archive), cut);
}

TEST_F(DamagedArchiveTest, ResumeOfItsOwnTruncatedArchiveReplacesItWithItsCompleteBatches) {
  const fs::path study = StudyFile("a.toml", 32.0);
  const fs::path archive = directory_ / "own.h5";
  Run(study, archive);
  const std::string bytes = Bytes(archive);
  std::ofstream(archive, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 1);
  SweepPlan plan(LoadStudy(study), ShardSpec{0, 1});
  ArchiveOpenReport report;
  {
    auto writer =
        ArchiveWriter::Open(archive, plan, RunProvenance{"test", 1}, ArchiveOpenMode::kResume, &report);
    EXPECT_EQ(report.kind, ArchiveOpenReport::Kind::kResumedAfterCrash);
    EXPECT_EQ(report.runs_complete, 16);
    EXPECT_TRUE(report.pending_blocks.empty());
    EXPECT_FALSE(fs::exists(archive.string() + ".repair")) << "the copy outlived the resume's check";
    writer->Finish();
  }
  const ArchiveReader reader = ArchiveReader::Open(archive);
  EXPECT_EQ(reader.run_count(), 16);
  EXPECT_EQ(reader.CompleteBlocks(4).size(), 4U);
}

}  // namespace
}  // namespace gesweep
