#pragma once
/// Where and how an archive was made: engine version and commit, compiler, host, times
/// (root attributes of the archive; schemas/archive.md, "Provenance").

#include <string>

namespace gesweep {

/// The engine version (CMake PROJECT_VERSION) this library was built as.
std::string EngineVersion();
/// The git commit the engine was built from ("unknown" outside a git checkout).
std::string EngineGitCommit();
/// The compiler and language standard, e.g. "GCC 12.2.0, C++20".
std::string CompilerDescription();
/// This machine's host name.
std::string HostName();
/// The current time in UTC, ISO 8601 with seconds ("2024-05-01T12:00:00Z").
std::string UtcTimestamp();

}  // namespace gesweep
