#pragma once
/// The error of the archive layer, without HDF5's headers (the CLI and the engine above
/// engine/archive catch it; only engine/archive includes HDF5).

#include <stdexcept>

namespace gesweep {

/// An archive could not be read or written (I/O error, disk full, corrupt file). Not a person's
/// bad input (that is InputError); the CLI reports it and exits with code 1.
class ArchiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace gesweep
