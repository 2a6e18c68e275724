#pragma once
/// Writing a global sensitivity result into its archive, under /analysis/sensitivity/<output>/
/// (schemas/archive.md, "analysis/sensitivity"; docs/sensitivity.md), and the lock that keeps it
/// from racing a sweep that writes the same archive.

#include <filesystem>
#include <string>

#include "engine/sensitivity/archive_sensitivity.h"

namespace gesweep {

/// The group of an output's result: "analysis/sensitivity/" + output.name, e.g.
/// "analysis/sensitivity/boundary/height_m" for results/boundary/height_m.
std::string SensitivityGroupPath(const ArchiveOutput& output);

/// An exclusive claim on an archive for updating it: a flock on ARCHIVE.lock, the lock `gesweep run`
/// holds for as long as it writes the archive (engine/archive/archive_writer.h). While held, no sweep
/// can start writing the archive, and it is not acquired while one writes.
class ArchiveUpdateLock {
 public:
  /// Takes the lock without waiting. Throws InputError (source the archive, key --output) when a
  /// gesweep process holds it ("archive in use"), or when the lock file cannot be created (the
  /// archive's directory is not writable).
  static ArchiveUpdateLock Acquire(const std::filesystem::path& archive);

  /// Moves the claim; `other` no longer holds it.
  ArchiveUpdateLock(ArchiveUpdateLock&& other) noexcept;
  ArchiveUpdateLock& operator=(ArchiveUpdateLock&&) = delete;
  ArchiveUpdateLock(const ArchiveUpdateLock&) = delete;
  ArchiveUpdateLock& operator=(const ArchiveUpdateLock&) = delete;
  /// Releases the lock; removes the lock file when this lock created it.
  ~ArchiveUpdateLock();

 private:
  ArchiveUpdateLock() = default;
  std::filesystem::path lock_path_;
  int fd_ = -1;
  bool created_ = false;
};

/// Writes `result` (status kOk) into the archive at SensitivityGroupPath(result.output), replacing a
/// previous result for the same output: the new group is written under a temporary name and moved
/// into place only when complete, so a failure leaves the previous result untouched. Records the
/// indices and their intervals, the estimators, N, D, the bootstrap resamples, level and seed, the
/// blocks used and dropped, the parameter names, the method and `command_line`. Preconditions: the
/// caller holds ArchiveUpdateLock on the archive and has no handle open on it. Throws InputError when
/// the archive cannot be opened for writing (open elsewhere), ArchiveError on an I/O failure.
void WriteSensitivityGroup(const std::filesystem::path& archive, const ArchiveSensitivity& result,
                           const std::string& command_line);

}  // namespace gesweep
