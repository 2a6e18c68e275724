#include "engine/archive/archive_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "engine/common/errors.h"
#include "engine/common/output_guard.h"

namespace gesweep {

bool ArchiveLock::OpenLockFile(const std::filesystem::path& archive) {
  lock_path_ = archive.string() + ".lock";
  std::error_code ec;
  const bool existed = std::filesystem::exists(lock_path_, ec);
  fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  return existed;
}

ArchiveLock ArchiveLock::Acquire(const std::filesystem::path& archive, const std::string& retry_hint) {
  // Before the lock file is made beside it: a device or a FIFO is no archive to write into.
  RequireRegularFile(archive, "archive");
  ArchiveLock lock;
  const bool existed = lock.OpenLockFile(archive);
  if (lock.fd_ < 0) {
    throw InputError(archive.string(), "", "",
                     "cannot write into the archive: cannot create its lock file " +
                         lock.lock_path_.string() + " (" + std::strerror(errno) + "); " + retry_hint);
  }
  lock.created_ = !existed;
  if (flock(lock.fd_, LOCK_EX | LOCK_NB) != 0) {
    throw InputError(archive.string(), "", "",
                     "archive in use: a gesweep process is writing it (" + lock.lock_path_.string() +
                         " is locked); " + retry_hint);
  }
  return lock;
}

ArchiveLock ArchiveLock::AcquireOutput(const std::filesystem::path& archive, const std::string& field) {
  ArchiveLock lock;
  const bool existed = lock.OpenLockFile(archive);
  if (lock.fd_ < 0) {
    throw InputError(
        "command line", field, archive.string(),
        "cannot create its lock file " + lock.lock_path_.string() + " (" + std::strerror(errno) + ")");
  }
  if (flock(lock.fd_, LOCK_EX | LOCK_NB) != 0) {
    throw InputError("command line", field, archive.string(),
                     "archive in use: another gesweep process is writing it (" + lock.lock_path_.string() +
                         " is locked); run this again once it has finished, or choose another output");
  }
  lock.created_ = !existed;  // removed with the claim, once it is ours
  return lock;
}

ArchiveLock::ArchiveLock(ArchiveLock&& other) noexcept
    : lock_path_(std::move(other.lock_path_)), fd_(other.fd_), created_(other.created_) {
  other.fd_ = -1;
  other.created_ = false;
}

ArchiveLock::~ArchiveLock() {
  if (fd_ < 0) return;
  // Removed while still locked, as ArchiveWriter does, so nobody locks a file about to disappear.
  if (created_) {
    std::error_code ec;
    std::filesystem::remove(lock_path_, ec);
  }
  close(fd_);
}

}  // namespace gesweep
