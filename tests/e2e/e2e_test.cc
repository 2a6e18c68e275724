// End-to-end: the real `gesweep` binary (GESWEEP_BINARY_DIR/gesweep) on small studies, reading the
// HDF5 it writes. Exit codes, one-line errors with nothing half-written, determinism across thread
// counts and shards, and a sweep killed with SIGKILL then resumed.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <thread>

#include "engine/archive/archive_reader.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

const std::string kBinary = std::string(GESWEEP_BINARY_DIR) + "/gesweep";
const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

class EndToEnd : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("gesweep_e2e_" + std::to_string(getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(directory_);
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::filesystem::path Write(const std::string& name, const std::string& text) {
    std::ofstream(directory_ / name) << text;
    return directory_ / name;
  }

  // Starts gesweep with `args`; stderr goes to `stderr_path`.
  pid_t Start(const std::vector<std::string>& args, const std::filesystem::path& stderr_path) {
    const pid_t pid = fork();
    if (pid == 0) {
      const int err = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(err, STDERR_FILENO);
      const int null = ::open("/dev/null", O_WRONLY);
      dup2(null, STDOUT_FILENO);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(kBinary.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(kBinary.c_str(), argv.data());
      _exit(127);
    }
    return pid;
  }
  static int Wait(pid_t pid) {
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  // Runs gesweep to completion; returns the exit code and fills `error` with its stderr.
  int Gesweep(const std::vector<std::string>& args, std::string* error = nullptr) {
    const auto stderr_path = directory_ / "stderr.txt";
    const int code = Wait(Start(args, stderr_path));
    if (error) {
      std::ifstream in(stderr_path);
      std::stringstream text;
      text << in.rdbuf();
      *error = text.str();
    }
    return code;
  }

  std::string Header(const std::string& analyses) {
    return "format_version = 1\nname = \"e2e\"\naircraft = \"" + kAircraft + "\"\n" + analyses;
  }

  // Every per-run dataset (and time axis) as raw bytes, by path.
  static std::map<std::string, std::vector<unsigned char>> Contents(const std::filesystem::path& archive,
                                                                    bool complete_only = false) {
    ArchiveReader reader = ArchiveReader::Open(archive);
    const auto status = reader.ReadStatus(0, reader.run_count());
    std::map<std::string, std::vector<unsigned char>> contents;
    for (const std::string& path : reader.Datasets()) {
      hdf5::Handle dataset(H5Dopen2(reader.file(), path.c_str(), H5P_DEFAULT), "open");
      hdf5::Handle type(H5Dget_type(dataset.get()), "type");
      const auto dims = hdf5::Dimensions(dataset.get());
      const std::size_t row_bytes =
          H5Tget_size(type.get()) * static_cast<std::size_t>(dims.size() == 2 ? dims[1] : 1);
      if (dims[0] != reader.run_count()) continue;
      std::vector<unsigned char> bytes(static_cast<std::size_t>(reader.run_count()) * row_bytes);
      reader.ReadRows(path, 0, reader.run_count(), type.get(), bytes.data());
      if (complete_only) {
        // Blank the runs that are not complete, so a snapshot compares with a finished archive.
        for (std::size_t r = 0; r < status.size(); ++r) {
          if (status[r] == 0)
            std::fill_n(bytes.begin() + static_cast<std::ptrdiff_t>(r * row_bytes), row_bytes, 0);
        }
      }
      contents[path] = std::move(bytes);
    }
    return contents;
  }

  std::filesystem::path directory_;
};

TEST_F(EndToEnd, RunsAStudyAndDryRunWritesNothing) {
  const auto study = Write("s.toml", Header("[analyses.modes]\n") + R"(
[parameters]
speed_mps = 32.0208
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 5.0, 9]
)");
  const auto archive = directory_ / "a.h5";
  std::string error;
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string(), "--dry-run"}, &error), 0);
  EXPECT_FALSE(std::filesystem::exists(archive));
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string()}, &error), 0) << error;
  ArchiveReader reader = ArchiveReader::Open(archive);
  EXPECT_EQ(reader.run_count(), 9);
  EXPECT_EQ(reader.IntegerAttribute("runs_ok"), 9);
  // Boundary of docs/model.md §6: unstable below H* = 2.7008 m at this speed, stable above (the
  // engine core's published value; the 0.5 m grid brackets it between 2.5 m and 3.0 m).
  const auto margins = reader.ReadDoubles("results/modes/stability_margin_per_s", 0, 9);
  EXPECT_GT(margins[3], 0.0);  // H = 2.5 m
  EXPECT_LT(margins[4], 0.0);  // H = 3.0 m
}

TEST_F(EndToEnd, FlyingQualitiesRateTheModesOfTheSameArchiveByTheCategoryCLimits) {
  // The levels the `flying_qualities` analysis stores are those the table of docs/model.md §11
  // gives for the damping ratios and real parts the `modes` analysis stores beside them, run by run,
  // and the airplane's level is the worse of the two (codes: level n is n − 1).
  const auto study = Write("s.toml", Header("[analyses.modes]\n[analyses.flying_qualities]\n") + R"(
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
values = [32.0208, 52.21]
[[design.parameter]]
name = "height_m"
logspace = [0.8, 14.0, 60]
)");
  const auto archive = directory_ / "a.h5";
  std::string error;
  ASSERT_EQ(Gesweep({"run", study.string(), "-o", archive.string()}, &error), 0) << error;
  ArchiveReader reader = ArchiveReader::Open(archive);
  const std::int64_t n = reader.run_count();
  ASSERT_EQ(n, 120);
  const std::string fq = "results/flying_qualities/";
  const std::vector<std::string> names = {"level 1", "level 2", "level 3", "worse than level 3"};
  for (const char* column : {"short_period_level", "phugoid_level", "level"})
    EXPECT_EQ(reader.StringListAttributeOf(fq + column, "levels"), names) << column;
  const auto classification = reader.ReadIntegers("results/modes/classification", 0, n);
  const auto zeta_sp = reader.ReadDoubles("results/modes/short_period/damping_ratio", 0, n);
  const auto zeta_p = reader.ReadDoubles("results/modes/phugoid/damping_ratio", 0, n);
  const auto re_p = reader.ReadDoubles("results/modes/phugoid/eigenvalue_re_per_s", 0, n);
  const auto sp_level = reader.ReadIntegers(fq + "short_period_level", 0, n);
  const auto p_level = reader.ReadIntegers(fq + "phugoid_level", 0, n);
  const auto level = reader.ReadIntegers(fq + "level", 0, n);
  const auto rated_zeta_p = reader.ReadDoubles(fq + "phugoid_damping_ratio", 0, n);
  std::map<std::int64_t, int> seen;
  for (std::int64_t r = 0; r < n; ++r) {
    ASSERT_EQ(classification[r], 0) << "run " << r << ": both modes oscillatory over this range";
    const double z = zeta_sp[r];
    const int expected_sp = z >= 0.35 && z <= 1.30 ? 0 : z >= 0.25 && z <= 2.00 ? 1 : z >= 0.15 ? 2 : 3;
    const int expected_p = zeta_p[r] >= 0.04 ? 0 : zeta_p[r] >= 0 ? 1 : std::log(2.0) / re_p[r] >= 55 ? 2 : 3;
    EXPECT_EQ(sp_level[r], expected_sp) << "run " << r;
    EXPECT_EQ(p_level[r], expected_p) << "run " << r;
    EXPECT_EQ(level[r], std::max(expected_sp, expected_p)) << "run " << r;
    EXPECT_EQ(rated_zeta_p[r], zeta_p[r]) << "run " << r;  // the same ζ, rated
    ++seen[p_level[r]];
  }
  // Over 0.8-14 m at these speeds the phugoid passes through every level (docs/model.md §11): the
  // comparison above covers each branch of the table.
  EXPECT_EQ(seen.size(), 4u);
}

TEST_F(EndToEnd, BadStudyExitsTwoWithOneLineAndLeavesNoArchive) {
  const auto study =
      Write("bad.toml", Header("[analyses.modes]\n") + "[parameters]\nspeed_mps = 30\nheigth_m = 2\n");
  const auto archive = directory_ / "a.h5";
  std::string error;
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string()}, &error), 2);
  EXPECT_EQ(std::count(error.begin(), error.end(), '\n'), 1) << error;
  EXPECT_NE(error.find("bad.toml:7"), std::string::npos) << error;
  EXPECT_NE(error.find("did you mean 'height_m'"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(archive));
  EXPECT_FALSE(std::filesystem::exists(archive.string() + ".partial"));
  EXPECT_FALSE(std::filesystem::exists(archive.string() + ".lock"));
}

TEST_F(EndToEnd, ExistingArchiveIsNeverOverwrittenWithoutResumeOrForce) {
  const auto study =
      Write("s.toml", Header("[analyses.modes]\n") + "[parameters]\nspeed_mps = 30\nheight_m = 2\n");
  const auto archive = Write("a.h5", "keep me");
  std::string error;
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string()}, &error), 2);
  EXPECT_NE(error.find("--resume"), std::string::npos) << error;
  std::ifstream in(archive);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "keep me");
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", (directory_ / "no" / "a.h5").string()}, &error), 2);
  EXPECT_NE(error.find("does not exist"), std::string::npos) << error;
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string(), "--force"}, &error), 0) << error;
}

TEST_F(EndToEnd, FailedRunsAreStoredAndExitThree) {
  // Absurd (but positive) mass and inertia overflow the state matrix (Mw_dot·Zw ~ 1e600): that run
  // fails, the others do not.
  const auto study = Write("s.toml", Header("[analyses.modes]\n") + R"(
[parameters]
speed_mps = 32
height_m = 2
[design]
kind = "list"
columns = ["mass_kg", "pitch_inertia_kgm2"]
rows = [[182.055, 400.0], [1e-300, 1e-300], [200.0, 420.0]]
)");
  const auto archive = directory_ / "a.h5";
  std::string error;
  EXPECT_EQ(Gesweep({"run", study.string(), "-o", archive.string()}, &error), 3) << error;
  ArchiveReader reader = ArchiveReader::Open(archive);
  const auto status = reader.ReadStatus(0, 3);
  EXPECT_EQ(status, (std::vector<std::int8_t>{1, 2, 1}));
  const auto messages = reader.ReadMessages(0, 3);
  EXPECT_EQ(messages[0], "");
  EXPECT_NE(messages[1].find("modes: state matrix not finite"), std::string::npos) << messages[1];
}

TEST_F(EndToEnd, ThreadCountAndShardsGiveTheSameArchiveBitForBit) {
  const auto study = Write("s.toml", Header("[analyses.modes]\n[analyses.boundary]\n") + R"(
[parameters]
height_m = 2.0
[output]
chunk_runs = 4
[design]
kind = "grid"
[[design.parameter]]
name = "scale.CMh"
values = [0.8, 1.0, 1.2]
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 50.0, 7]
)");
  std::string error;
  ASSERT_EQ(
      Gesweep({"run", study.string(), "-o", (directory_ / "one.h5").string(), "--threads", "1"}, &error), 0)
      << error;
  ASSERT_EQ(
      Gesweep({"run", study.string(), "-o", (directory_ / "three.h5").string(), "--threads", "3"}, &error),
      0);
  std::vector<std::string> merge = {"merge"};
  for (int i = 0; i < 3; ++i) {
    const auto shard = directory_ / ("shard" + std::to_string(i) + ".h5");
    ASSERT_EQ(
        Gesweep({"run", study.string(), "-o", shard.string(), "--shard", std::to_string(i) + "/3"}, &error),
        0)
        << error;
    merge.push_back(shard.string());
  }
  merge.insert(merge.end(), {"-o", (directory_ / "merged.h5").string()});
  ASSERT_EQ(Gesweep(merge, &error), 0) << error;
  const auto one = Contents(directory_ / "one.h5");
  EXPECT_EQ(one, Contents(directory_ / "three.h5"));
  EXPECT_EQ(one, Contents(directory_ / "merged.h5"));
  EXPECT_TRUE(one.count("results/boundary/height_m"));
  // A merge that misses a shard is refused and names it.
  EXPECT_EQ(Gesweep({"merge", merge[1], merge[3], "-o", (directory_ / "bad.h5").string()}, &error), 2);
  EXPECT_NE(error.find("shard 1/3 not given"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(directory_ / "bad.h5"));
}

// [output] deflate_encoder = "libdeflate" writes other compressed bytes, the same values: every
// per-run dataset read back equals the zlib archive's, also through a --copy merge of libdeflate
// shards; an encoder nobody defined is refused with one line.
TEST_F(EndToEnd, LibdeflateArchivesHoldTheSameValuesAsZlibOnes) {
  const std::string body = R"(
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [28.0, 50.0, 40]
[[design.parameter]]
name = "height_m"
logspace = [0.8, 14.0, 50]
)";
  const auto zlib = Write("zlib.toml", Header("[analyses.modes]\n[output]\nchunk_runs = 256\n") + body);
  const auto fast =
      Write("fast.toml", Header("[analyses.modes]\n[output]\nchunk_runs = 256\ndeflate_encoder = "
                                "\"libdeflate\"\n") +
                             body);
  std::string error;
  ASSERT_EQ(Gesweep({"run", zlib.string(), "-o", (directory_ / "zlib.h5").string()}, &error), 0) << error;
  ASSERT_EQ(Gesweep({"run", fast.string(), "-o", (directory_ / "fast.h5").string()}, &error), 0) << error;
  std::vector<std::string> merge = {"merge", "--copy"};
  for (int i = 0; i < 2; ++i) {
    const auto shard = directory_ / ("fast" + std::to_string(i) + ".h5");
    ASSERT_EQ(
        Gesweep({"run", fast.string(), "-o", shard.string(), "--shard", std::to_string(i) + "/2"}, &error), 0)
        << error;
    merge.push_back(shard.string());
  }
  merge.insert(merge.end(), {"-o", (directory_ / "fast_merged.h5").string()});
  ASSERT_EQ(Gesweep(merge, &error), 0) << error;
  const auto expected = Contents(directory_ / "zlib.h5");
  EXPECT_TRUE(expected.count("results/modes/stability_margin_per_s"));
  EXPECT_EQ(expected, Contents(directory_ / "fast.h5"));
  EXPECT_EQ(expected, Contents(directory_ / "fast_merged.h5"));
  const auto bad =
      Write("bad.toml", Header("[analyses.modes]\n[output]\ndeflate_encoder = \"lz4\"\n") + body);
  EXPECT_EQ(Gesweep({"run", bad.string(), "-o", (directory_ / "bad.h5").string()}, &error), 2);
  EXPECT_NE(error.find("deflate_encoder = \"lz4\": expected zlib or libdeflate"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(directory_ / "bad.h5"));
}

TEST_F(EndToEnd, MonteCarloThreadsAndShardsGiveTheSameArchiveBitForBit) {
  const auto study = Write("s.toml", Header("[analyses.modes]\n") + R"(
[output]
chunk_runs = 8
[design]
kind = "monte_carlo"
samples = 61
seed = 757
[[design.parameter]]
name = "speed_mps"
truncated_normal = [32.0, 2.0, 28.0, 36.0]
[[design.parameter]]
name = "height_m"
lognormal = [1.0, 0.05]
[[design.parameter]]
name = "cdh"
values = ["polar", "zero"]
weights = [3, 1]
)");
  std::string error;
  ASSERT_EQ(
      Gesweep({"run", study.string(), "-o", (directory_ / "one.h5").string(), "--threads", "1"}, &error), 0)
      << error;
  ASSERT_EQ(
      Gesweep({"run", study.string(), "-o", (directory_ / "two.h5").string(), "--threads", "2"}, &error), 0)
      << error;
  std::vector<std::string> merge = {"merge"};
  for (int i = 0; i < 3; ++i) {
    const auto shard = directory_ / ("shard" + std::to_string(i) + ".h5");
    ASSERT_EQ(
        Gesweep({"run", study.string(), "-o", shard.string(), "--shard", std::to_string(i) + "/3"}, &error),
        0)
        << error;
    merge.push_back(shard.string());
  }
  merge.insert(merge.end(), {"-o", (directory_ / "merged.h5").string()});
  ASSERT_EQ(Gesweep(merge, &error), 0) << error;
  const auto one = Contents(directory_ / "one.h5");
  EXPECT_EQ(one, Contents(directory_ / "two.h5"));
  EXPECT_EQ(one, Contents(directory_ / "merged.h5"));
  ASSERT_TRUE(one.count("design/speed_mps"));
  // The dry run works for it too.
  EXPECT_EQ(Gesweep({"run", study.string(), "--dry-run"}, &error), 0) << error;
}

// Kills a sweep with SIGKILL at a random moment (twice, the second time during the resume), checks
// that the archive opens after each kill and holds only correct complete runs, resumes, and compares
// the result with an uninterrupted run, run by run.
TEST_F(EndToEnd, KilledSweepResumesWithNoRunLostOrDuplicated) {
  // The sampled boundary search (about 1 ms a run, 20x the certified finder): the sweep must last
  // long enough to be killed twice.
  const auto study = Write("s.toml", Header("[analyses.boundary]\nmethod = \"sampled\"\n") + R"(
[output]
chunk_runs = 8
[design]
kind = "grid"
[[design.parameter]]
name = "scale.CMalphadot"
linspace = [0.7, 1.3, 25]
[[design.parameter]]
name = "speed_mps"
linspace = [27.0, 55.0, 48]
)");
  std::string error;
  const auto reference = directory_ / "reference.h5";
  ASSERT_EQ(Gesweep({"run", study.string(), "-o", reference.string()}, &error), 0) << error;
  const auto expected = Contents(reference);

  const auto archive = directory_ / "killed.h5";
  std::mt19937 random(static_cast<unsigned>(::testing::UnitTest::GetInstance()->random_seed()));
  int kills = 0;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const pid_t pid =
        Start({"run", study.string(), "-o", archive.string(), "--resume", "-q"}, directory_ / "err.txt");
    // Wait until some batches are on disk, then a random moment more.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    std::int64_t complete = 0;
    while (std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      try {
        ArchiveReader reader = ArchiveReader::Open(archive);
        const auto status = reader.ReadStatus(0, reader.run_count());
        complete = std::count_if(status.begin(), status.end(), [](std::int8_t s) { return s != 0; });
        if (complete >= 16 * (attempt + 1)) break;
      } catch (const std::exception&) {
        // Not created yet, being set up, or being replaced by a resume: try again.
      }
    }
    std::this_thread::sleep_for(
        std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 100)(random)));
    kill(pid, SIGKILL);
    if (Wait(pid) != 128 + SIGKILL) break;  // it finished first: nothing to test this time
    // The archive opens after the kill, and what it holds is right. Normally it is a snapshot of the
    // complete batches; if the kill landed after the writer had closed the file (the process was
    // already exiting), the archive is closed cleanly and must then be whole.
    ArchiveReader after = ArchiveReader::Open(archive);
    const bool closed_before_the_kill = !after.snapshot();
    after.Close();
    if (closed_before_the_kill) {
      EXPECT_EQ(Contents(archive), expected) << "clean archive after a late kill " << attempt;
      break;
    }
    ++kills;
    auto partial = Contents(archive, /*complete_only=*/true);
    ArchiveReader again = ArchiveReader::Open(archive);
    const auto status = again.ReadStatus(0, again.run_count());
    again.Close();
    for (auto& [path, bytes] : partial) {
      std::vector<unsigned char> want = expected.at(path);
      const std::size_t row_bytes = want.size() / status.size();
      for (std::size_t r = 0; r < status.size(); ++r) {
        if (status[r] == 0)
          std::fill_n(want.begin() + static_cast<std::ptrdiff_t>(r * row_bytes), row_bytes, 0);
      }
      EXPECT_EQ(bytes, want) << path << " after kill " << kills;
    }
  }
  EXPECT_GE(kills, 1) << "the sweep finished before any kill: make it longer";
  ASSERT_EQ(Gesweep({"run", study.string(), "-o", archive.string(), "--resume"}, &error), 0) << error;
  EXPECT_NE(error.find("resuming"), std::string::npos) << error;
  EXPECT_EQ(Contents(archive), expected);
  EXPECT_FALSE(std::filesystem::exists(archive.string() + ".partial"));
}

}  // namespace
}  // namespace gesweep
