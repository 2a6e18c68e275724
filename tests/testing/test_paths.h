#pragma once
// Paths the tests share: the repository, the ANCE aircraft file and the paper's tables in the repository.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace gesweep::testing {

inline std::filesystem::path SourceDir() { return GESWEEP_SOURCE_DIR; }
inline std::filesystem::path AnceAircraftPath() { return SourceDir() / "studies/aircraft/ance.toml"; }
/// The paper's Tables A1 and A2 as CSV, kept in the repository (docs/model.md §1–2).
inline std::filesystem::path PaperDataDir() { return SourceDir() / "studies/aircraft/data"; }

inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace gesweep::testing
