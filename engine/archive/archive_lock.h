#pragma once
/// An exclusive claim on an archive for adding a derived product to it (/analysis/boundary by
/// `gesweep boundary --archive`, /analysis/sensitivity by `gesweep sensitivity`): a flock on
/// ARCHIVE.lock, the lock `gesweep run` holds while it writes the archive
/// (engine/archive/archive_writer.h), and `gesweep merge` while it writes its output. While held, no
/// sweep or merge can start writing the archive; it is not granted while one writes.

#include <filesystem>
#include <string>

#include "engine/common/copy_rules.h"

namespace gesweep {

/// The claim; released (and its lock file removed when this claim created it) on destruction.
class ArchiveLock {
 public:
  /// Takes the lock without waiting. Throws InputError (source the archive) when a gesweep process
  /// holds it ("archive in use: ..."; `retry_hint` says what to do, e.g. "run gesweep boundary again
  /// once it has finished, or pass --no-write"), or when the lock file cannot be created.
  static ArchiveLock Acquire(const std::filesystem::path& archive, const std::string& retry_hint);
  /// The same claim on an archive about to be written whole, which need not exist yet (`gesweep merge`'s
  /// output, as `gesweep run` claims its output): throws InputError("command line", `field`, archive, ...)
  /// when a gesweep process holds it ("archive in use: ...") or the lock file cannot be created.
  static ArchiveLock AcquireOutput(const std::filesystem::path& archive, const std::string& field);

  GESWEEP_MOVE_CONSTRUCT_ONLY(ArchiveLock);
  ~ArchiveLock();

 private:
  ArchiveLock() = default;
  /// Sets lock_path_ (ARCHIVE.lock) and opens it, created when missing, into fd_ (-1 when it cannot
  /// be; errno says why); returns whether it existed before. Takes no lock.
  bool OpenLockFile(const std::filesystem::path& archive);
  std::filesystem::path lock_path_;
  int fd_ = -1;
  bool created_ = false;
};

}  // namespace gesweep
