#pragma once
// Paths the tests share: the repository, the ANCE aircraft file and the shared data beside the repo.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace gesweep::testing {

inline std::filesystem::path SourceDir() { return GESWEEP_SOURCE_DIR; }
inline std::filesystem::path AnceAircraftPath() { return SourceDir() / "studies/aircraft/ance.toml"; }
/// ../shared/data beside the repository (present in CI and on developer machines).
inline std::filesystem::path SharedDataDir() { return SourceDir().parent_path() / "shared/data"; }

inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace gesweep::testing
