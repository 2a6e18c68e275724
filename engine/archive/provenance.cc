#include "engine/archive/provenance.h"

#include <unistd.h>

#include <chrono>
#include <ctime>

namespace gesweep {

std::string EngineVersion() { return GESWEEP_VERSION; }

std::string EngineGitCommit() { return GESWEEP_GIT_COMMIT; }

std::string CompilerDescription() {
#if defined(__clang__)
  std::string compiler = std::string("Clang ") + __clang_version__;
#elif defined(__GNUC__)
  std::string compiler = std::string("GCC ") + __VERSION__;
#else
  std::string compiler = "unknown compiler";
#endif
  return compiler + ", C++" + std::to_string(__cplusplus / 100 % 100);
}

std::string HostName() {
  char name[256] = {0};
  if (gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

std::string UtcTimestamp() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

}  // namespace gesweep
