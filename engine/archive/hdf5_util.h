#pragma once
/// Thin RAII and attribute helpers over the HDF5 C API (1.10), used only inside engine/archive.
/// Every failure becomes an ArchiveError carrying the innermost message of HDF5's error stack.

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/archive/archive_error.h"
#include "engine/common/copy_rules.h"

namespace gesweep {

namespace hdf5 {

/// Turns off HDF5's automatic error printing on the calling thread (errors become exceptions).
/// (hdf5_util.cc also turns off HDF5's clean-up at exit, at static initialisation: it crashes on a
/// file whose close failed on a full disk.)
void Quiet();

/// The cause of the calling thread's HDF5 error, in one line ("" when the stack is empty): the
/// operating system's reason when a system call failed (HDF5's "errno = 28" becomes "no space left
/// on device"), else the innermost description, with HDF5's embedded line breaks and raw counters
/// ("bytes actually written = 18446744073709551615") left out.
std::string LastError();

/// Throws ArchiveError("what: <LastError()>", LastError()) when `status` < 0; returns it otherwise.
std::int64_t Check(std::int64_t status, const std::string& what);

/// An owned HDF5 identifier, closed with the right H5?close on destruction.
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  Handle(hid_t id, const std::string& what) : id_(static_cast<hid_t>(Check(id, what))) {}
  ~Handle() { Reset(); }
  Handle(Handle&& other) noexcept : id_(other.id_) { other.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      Reset();
      id_ = other.id_;
      other.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  GESWEEP_NO_COPY(Handle);
  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  /// Closes now (errors reported, unlike the destructor's).
  void Close(const std::string& what);
  void Reset();

 private:
  hid_t id_ = H5I_INVALID_HID;
};

/// A file access property list: latest format (needed for SWMR), file locking that is ignored
/// where the file system does not support it.
Handle FileAccess();

/// Whether a link (e.g. "results/modes") exists, every intermediate group included.
bool Exists(hid_t location, const std::string& path);

/// Creates the groups of `path` that do not exist yet.
void CreateGroups(hid_t location, const std::string& path);

/// Replaces the group at `path` (e.g. "analysis/boundary") whole: `write(temporary)` creates and fills
/// a group under the hidden sibling name "<parent>/.<leaf>.partial" (a stale one is deleted first);
/// only when it returns is the old group deleted and the new one moved into place. If `write`
/// throws, the temporary group is deleted, the old group is left untouched, and the exception
/// propagates. Creates the parent groups when missing.
void ReplaceGroup(hid_t file, const std::string& path, const std::function<void(const std::string&)>& write);

/// Attribute writers (an existing attribute of the same name is replaced).
void WriteAttribute(hid_t object, const std::string& name, const std::string& value);
void WriteAttribute(hid_t object, const std::string& name, const char* value);
void WriteAttribute(hid_t object, const std::string& name, std::int64_t value);
void WriteAttribute(hid_t object, const std::string& name, double value);
void WriteAttribute(hid_t object, const std::string& name, const std::vector<std::string>& values);
void WriteAttribute(hid_t object, const std::string& name, const std::vector<double>& values);
void WriteAttribute(hid_t object, const std::string& name, const std::vector<std::int64_t>& values);

/// Rewrites the value of an existing scalar attribute in place (allowed in SWMR write mode, where
/// creating or deleting one is not). Throws ArchiveError when it is absent.
void UpdateAttribute(hid_t object, const std::string& name, const std::string& value);
void UpdateAttribute(hid_t object, const std::string& name, std::int64_t value);

/// The attribute `name` of `object`, opened (ArchiveError "open attribute NAME" when it cannot be).
Handle OpenAttribute(hid_t object, const std::string& name);

/// Attribute readers; nullopt when absent, ArchiveError when of another kind.
std::optional<std::string> ReadStringAttribute(hid_t object, const std::string& name);
std::optional<std::int64_t> ReadIntegerAttribute(hid_t object, const std::string& name);
std::optional<double> ReadDoubleAttribute(hid_t object, const std::string& name);
std::vector<std::string> ReadStringListAttribute(hid_t object, const std::string& name);
/// An integer attribute (scalar or list) as int64 values; empty when absent, ArchiveError when not integer.
std::vector<std::int64_t> ReadIntegerListAttribute(hid_t object, const std::string& name);

/// Copies every attribute of `from` to `to` (values and types as stored), but for the dimension
/// scale attributes (archive::IsDimensionScaleAttribute).
void CopyAttributes(hid_t from, hid_t to);

/// The compound {re, im} of two doubles (h5py reads it as complex128).
Handle ComplexType();
/// A fixed-length, null-padded UTF-8 string type of `length` bytes.
Handle FixedStringType(int length);

/// Selects rows [first, first + count) of a dataset of rank 1 or 2 (all columns) and returns the
/// file space; `memory` receives the matching memory space.
Handle SelectRows(hid_t dataset, std::int64_t first, std::int64_t count, Handle* memory);

/// Dimensions of a dataset.
std::vector<std::int64_t> Dimensions(hid_t dataset);

}  // namespace hdf5
}  // namespace gesweep
