#pragma once
/// Reading the per-run columns and the attributes of an archive without HDF5 types: the API through
/// which engine/query (`gesweep query`, its column catalogue and `--describe`, the rebuilt run
/// models) reads, so that engine/archive alone includes HDF5 (schemas/archive.md is the layout).
///
/// Every function reads through an open ArchiveReader (archive_reader.h), so a snapshot of an archive
/// that a sweep is writing is read as ArchiveReader opened it. Memory is bounded by what is asked for
/// (a block of rows, one object's attributes). Every failure to read is an ArchiveError naming the
/// dataset or attribute and the archive.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gesweep {

class ArchiveReader;

/// How the elements of a dataset are stored.
enum class StoredType {
  kFloat,            ///< IEEE floating point
  kSignedInteger,    ///< signed integer of any width
  kUnsignedInteger,  ///< unsigned integer of any width
  kText,             ///< a string (fixed or variable length)
  kCompound,         ///< a compound (e.g. the complex {re, im} eigenvalues)
  kOther,            ///< anything else (enum, array, opaque, reference, ...)
};

/// One dataset of an archive with the attributes that describe a column.
struct DatasetInfo {
  std::string path;                 ///< without a leading "/", e.g. "design/height_m"
  std::vector<std::int64_t> shape;  ///< dimensions ({} for a scalar dataset)
  StoredType type = StoredType::kOther;
  std::size_t element_bytes = 0;     ///< bytes of one stored element
  std::string units;                 ///< attribute `units` ("" when absent)
  std::string description;           ///< attribute `description` ("" when absent)
  std::string time_axis;             ///< attribute `time_axis` of a time series ("" when absent)
  std::vector<std::string> levels;   ///< attribute `levels`: names of the codes 0, 1, ... ({} when absent)
  std::optional<std::int64_t> fill;  ///< attribute `fill` of an integer dataset: "no value"
};

/// Every dataset of `archive`, in ArchiveReader::Datasets() order, with its shape, stored type and
/// describing attributes. Throws ArchiveError when a dataset or attribute cannot be read.
std::vector<DatasetInfo> DescribeDatasets(const ArchiveReader& archive);

/// Reads rows [first, first + count) of the 1-D numeric dataset at `path` as doubles into `out`
/// (resized to `count`); integers are converted (exact up to 2^53). Throws ArchiveError.
void ReadDoubleRows(const ArchiveReader& archive, const std::string& path, std::int64_t first,
                    std::int64_t count, std::vector<double>& out);

/// Reads rows [first, first + count) of the 1-D integer dataset at `path` as exact 64-bit unsigned
/// integers into `out` (resized to `count`). Throws ArchiveError.
void ReadUnsignedRows(const ArchiveReader& archive, const std::string& path, std::int64_t first,
                      std::int64_t count, std::vector<std::uint64_t>& out);

/// Reads rows [first, first + count) of the 1-D string dataset at `path` (fixed or variable length;
/// a fixed-length string ends at its first NUL). runs/message is read by ArchiveReader::ReadMessages,
/// whatever its storage. Throws ArchiveError.
std::vector<std::string> ReadTextRows(const ArchiveReader& archive, const std::string& path,
                                      std::int64_t first, std::int64_t count);

/// An attribute as stored: text or numbers, one (scalar) or a list.
struct AttributeValue {
  enum class Kind { kText, kInteger, kFloat, kOther };
  std::string name;
  Kind kind = Kind::kOther;
  bool scalar = true;              ///< a scalar dataspace (else a list, possibly of one)
  std::vector<std::string> texts;  ///< kText
  std::vector<double> numbers;     ///< kInteger (converted, exact up to 2^53) and kFloat
};

/// Every attribute of the object (group or dataset) at `path` ("/" for the root), in name order.
/// Throws ArchiveError when the object or an attribute cannot be read.
std::vector<AttributeValue> ReadObjectAttributes(const ArchiveReader& archive, const std::string& path);

/// The string-list attribute `name` of the object at `path` ({} when absent; a scalar string gives
/// a list of one). Throws ArchiveError when it is of another kind or cannot be read.
std::vector<std::string> ReadStringListAttribute(const ArchiveReader& archive, const std::string& path,
                                                 const std::string& name);

/// The numeric-list attribute `name` of the object at `path`, as doubles ({} when absent). Throws
/// ArchiveError when it is not numeric or cannot be read.
std::vector<double> ReadDoubleListAttribute(const ArchiveReader& archive, const std::string& path,
                                            const std::string& name);

}  // namespace gesweep
