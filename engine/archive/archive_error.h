#pragma once
/// The error of the archive layer, without HDF5's headers (the CLI and the engine above
/// engine/archive catch it; only engine/archive includes HDF5).

#include <stdexcept>
#include <string>
#include <utility>

namespace gesweep {

/// An archive could not be read or written (I/O error, disk full, corrupt file). Not a person's
/// bad input (that is InputError); the CLI reports it and exits with code 1. what() is one line,
/// "<what was being done>: <cause>"; cause() is the cause alone ("no space left on device") when
/// known, else what().
class ArchiveError : public std::runtime_error {
 public:
  explicit ArchiveError(const std::string& message) : std::runtime_error(message) {}
  ArchiveError(const std::string& message, std::string cause)
      : std::runtime_error(message), cause_(std::move(cause)) {}
  std::string cause() const { return cause_.empty() ? std::string(what()) : cause_; }

 private:
  std::string cause_;
};

}  // namespace gesweep
