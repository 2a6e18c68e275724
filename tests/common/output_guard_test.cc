// The one output check (engine/common/output_guard.h): an output never resolves to an input, and an
// existing output is a regular file (or a directory where one is wanted).
#include "engine/common/output_guard.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

namespace fs = std::filesystem;

class OutputGuard : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("gesweep_guard_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    study_ = dir_ / "study.toml";
    std::ofstream(study_) << "format_version = 1\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The message of the InputError the check throws, or "" when it accepts.
  std::string Refusal(const fs::path& output, OutputKind kind = OutputKind::kFile,
                      const std::vector<fs::path>& sidecars = {}) {
    try {
      CheckOutputPath(output, kind, {{study_, "study file"}}, "-o", sidecars);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_, study_;
};

TEST_F(OutputGuard, AcceptsANewPathAndAnExistingRegularFile) {
  EXPECT_EQ(Refusal(dir_ / "out.h5"), "");
  std::ofstream(dir_ / "old.h5") << "an earlier archive";
  EXPECT_EQ(Refusal(dir_ / "old.h5"), "");
  EXPECT_EQ(Refusal(dir_ / "report"), "");  // a new directory
  EXPECT_EQ(Refusal(dir_, OutputKind::kDirectory), "");
}

TEST_F(OutputGuard, RefusesTheInputItself) {
  const std::string text = Refusal(study_);
  EXPECT_NE(text.find("is the study file"), std::string::npos) << text;
  EXPECT_NE(text.find("an output never replaces an input"), std::string::npos) << text;
  // Spelt another way: the same file.
  EXPECT_NE(Refusal(dir_ / "." / "study.toml").find("is the study file"), std::string::npos);
}

TEST_F(OutputGuard, RefusesAHardLinkAndASymlinkToTheInput) {
  fs::create_hard_link(study_, dir_ / "hard.h5");
  fs::create_symlink(study_, dir_ / "soft.h5");
  fs::create_symlink(dir_ / "soft.h5", dir_ / "soft2.h5");  // a chain of symlinks
  for (const char* name : {"hard.h5", "soft.h5", "soft2.h5"}) {
    const std::string text = Refusal(dir_ / name);
    EXPECT_NE(text.find("a hard link or a symlink to it"), std::string::npos) << name << ": " << text;
  }
}

TEST_F(OutputGuard, RefusesASidecarThatIsAnInput) {
  // run -o X writes X.partial; a study named X.partial would be replaced.
  const std::string text = Refusal(dir_ / "study.toml.x", OutputKind::kFile, {study_});
  EXPECT_NE(text.find("writing it would replace"), std::string::npos) << text;
}

TEST_F(OutputGuard, RefusesWhatIsNotARegularFile) {
  EXPECT_NE(Refusal("/dev/null").find("is a character device, not a regular file"), std::string::npos);
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  EXPECT_NE(Refusal(dir_ / "fifo").find("is a FIFO"), std::string::npos);
  fs::create_directories(dir_ / "sub");
  EXPECT_NE(Refusal(dir_ / "sub").find("is a directory"), std::string::npos);
  // A directory where a directory is wanted: fine; a file there: refused.
  EXPECT_EQ(Refusal(dir_ / "sub", OutputKind::kDirectory), "");
  std::ofstream(dir_ / "file") << "x";
  EXPECT_NE(Refusal(dir_ / "file", OutputKind::kDirectory).find("expected a directory"), std::string::npos);
}

TEST_F(OutputGuard, ADanglingSymlinkIsANewPathAndALoopIsRefused) {
  fs::create_symlink(dir_ / "nowhere", dir_ / "dangling.h5");
  EXPECT_EQ(Refusal(dir_ / "dangling.h5"), "");
  fs::create_symlink(dir_ / "loop_b", dir_ / "loop_a");
  fs::create_symlink(dir_ / "loop_a", dir_ / "loop_b");
  EXPECT_NE(Refusal(dir_ / "loop_a").find("symbolic links"), std::string::npos);
}

TEST_F(OutputGuard, SameFileComparesInodes) {
  fs::create_hard_link(study_, dir_ / "hard.toml");
  EXPECT_TRUE(SameFile(study_, dir_ / "hard.toml"));
  std::ofstream(dir_ / "copy.toml") << "format_version = 1\n";  // equal bytes, another file
  EXPECT_FALSE(SameFile(study_, dir_ / "copy.toml"));
  EXPECT_FALSE(SameFile(study_, dir_ / "missing"));
}

TEST_F(OutputGuard, RequireRegularFileNamesWhatItFound) {
  auto refusal = [](const fs::path& path) {
    try {
      RequireRegularFile(path, "archive");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refusal(study_), "");
  EXPECT_NE(refusal(dir_ / "missing.h5").find("no such archive"), std::string::npos);
  EXPECT_NE(refusal(dir_).find("is a directory, not an archive"), std::string::npos);
  EXPECT_NE(refusal("/dev/zero").find("is a character device, not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace gesweep
