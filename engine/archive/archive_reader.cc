#include "engine/archive/archive_reader.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_probe.h"
#include "engine/archive/archive_writer.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"
#include "engine/common/request_error.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

herr_t CollectDataset(hid_t, const char* name, const H5O_info_t* info, void* data) {
  if (info->type == H5O_TYPE_DATASET) static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

// The physical and the recorded size of a file HDF5 refused as truncated, from its message
// ("truncated file: eof = 3145728, sblock->base_addr = 0, stored_eof = 3390612"), when it is that.
std::optional<std::pair<std::uintmax_t, std::uintmax_t>> TruncatedSizes(const std::string& error) {
  const auto eof = error.find("truncated file: eof = ");
  const auto stored = error.find("stored_eof = ");
  if (eof == std::string::npos || stored == std::string::npos) return std::nullopt;
  const std::uintmax_t actual = std::strtoull(error.c_str() + eof + 22, nullptr, 10);
  const std::uintmax_t recorded = std::strtoull(error.c_str() + stored + 13, nullptr, 10);
  if (recorded <= actual) return std::nullopt;
  return std::make_pair(actual, recorded);
}

// Read attempts of a metadata block in a snapshot (SWMR read) open; see ArchiveReader::Open.
constexpr unsigned kSnapshotReadAttempts = 24;

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.size() >= prefix.size() && text.compare(0, prefix.size(), prefix) == 0;
}

// Refuses an archive whose layout is not gesweep's: InputError naming the key and why.
[[noreturn]] void RefuseLayout(const std::string& shown, const std::string& key, const std::string& value,
                               const std::string& why) {
  throw InputError(shown, key, value, why + " (a damaged archive, or one not written by gesweep)");
}

// The root attributes of the run counts, consistent with each other; returns run_count.
std::int64_t ReadLayoutCounts(hid_t file, const std::string& shown) {
  auto integer = [&](const char* name) {
    std::optional<std::int64_t> value;
    try {
      value = hdf5::ReadIntegerAttribute(file, name);
    } catch (const ArchiveError&) {
      RefuseLayout(shown, name, "", "expected an integer root attribute");
    }
    if (!value) RefuseLayout(shown, name, "", "missing root attribute");
    return *value;
  };
  const std::int64_t runs = integer("run_count");
  const std::int64_t design_runs = integer("design_runs");
  const std::int64_t first_run = integer("first_run");
  const std::int64_t chunk_runs = integer("chunk_runs");
  if (runs < 0) RefuseLayout(shown, "run_count", std::to_string(runs), "expected a run count >= 0");
  if (chunk_runs < 1)
    RefuseLayout(shown, "chunk_runs", std::to_string(chunk_runs), "expected a batch size >= 1");
  if (first_run < 0 || design_runs < 0 || first_run > design_runs || runs > design_runs - first_run) {
    RefuseLayout(shown, "first_run", std::to_string(first_run),
                 "expected first_run + run_count <= design_runs = " + std::to_string(design_runs));
  }
  return runs;
}

// The groups runs/ and design/ are present, and groups.
void CheckLayoutGroups(hid_t file, const std::string& shown) {
  for (const char* group : {archive::kRunsGroup, archive::kDesignGroup}) {
    H5O_info_t info{};
    if (!hdf5::Exists(file, group) ||
        H5Oget_info_by_name2(file, group, &info, H5O_INFO_BASIC, H5P_DEFAULT) < 0 ||
        info.type != H5O_TYPE_GROUP) {
      H5Eclear2(H5E_DEFAULT);
      RefuseLayout(shown, group, "", "missing group /" + std::string(group));
    }
  }
}

// Checks the dataset `path` if it is a per-run one (under runs/, design/, results/, or a series'
// values): one row per run, of a type its readers convert. Returns whether it was one.
bool CheckRunDataset(hid_t file, const std::string& path, std::int64_t runs, const std::string& shown) {
  const bool runs_group = StartsWith(path, std::string(archive::kRunsGroup) + "/");
  const bool design_group = StartsWith(path, std::string(archive::kDesignGroup) + "/");
  const bool results_group = StartsWith(path, std::string(archive::kResultsGroup) + "/");
  const bool series_group = StartsWith(path, std::string(archive::kSeriesGroup) + "/");
  if (!runs_group && !design_group && !results_group && !series_group) return false;
  const hid_t raw = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (raw < 0) {
    H5Eclear2(H5E_DEFAULT);
    RefuseLayout(shown, path, "", "cannot open the dataset");
  }
  Handle dataset(raw);
  // A series group holds the shared time axes too (one value per sample, not per run).
  if (series_group && H5Aexists(dataset.get(), "time_axis") <= 0) {
    H5Eclear2(H5E_DEFAULT);
    return false;
  }
  const hid_t space_id = H5Dget_space(dataset.get());
  const hid_t type_id = H5Dget_type(dataset.get());
  Handle space(space_id), type(type_id);
  if (space_id < 0 || type_id < 0) {
    H5Eclear2(H5E_DEFAULT);
    RefuseLayout(shown, path, "", "cannot read the dataset's shape or type");
  }
  const int rank = H5Sget_simple_extent_ndims(space.get());
  hsize_t dims[2] = {0, 0};
  if (rank < 1 || rank > 2 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) {
    H5Eclear2(H5E_DEFAULT);
    RefuseLayout(shown, path, "",
                 "expected one row per run (a dataset of rank 1 or 2), found rank " + std::to_string(rank));
  }
  if (static_cast<std::int64_t>(dims[0]) != runs) {
    RefuseLayout(shown, path, std::to_string(dims[0]) + " rows",
                 "expected one row per run: run_count = " + std::to_string(runs) + " (runs/status has " +
                     (runs >= 0 ? std::to_string(runs) : std::string("?")) + ")");
  }
  const H5T_class_t type_class = H5Tget_class(type.get());
  const bool number = type_class == H5T_INTEGER || type_class == H5T_FLOAT;
  bool ok = true;
  std::string wanted;
  if (path == archive::kRunMessage) {
    ok = type_class == H5T_STRING && rank == 1;
    wanted = "one string per run";
  } else if (runs_group) {
    ok = type_class == H5T_INTEGER && rank == 1;
    wanted = "one integer per run";
  } else if (design_group) {
    ok = number && rank == 1;
    wanted = "one number per run";
  } else {
    ok = number || (type_class == H5T_COMPOUND && results_group);
    wanted = "numbers";
  }
  if (!ok) RefuseLayout(shown, path, "", "expected " + wanted + ", found another type or shape");
  return true;
}

// The layout every reader relies on (schemas/archive.md), checked from metadata alone when an archive
// is opened, so that a damaged or foreign file is refused with one line (exit 2) instead of failing
// later in a reader: the root attributes the readers use, runs/ and design/ present, and every
// per-run dataset one row per run, of a type its readers can convert.
void ValidateLayout(hid_t file, const std::string& shown, std::int64_t* run_count) {
  const std::int64_t runs = ReadLayoutCounts(file, shown);
  CheckLayoutGroups(file, shown);
  std::vector<std::string> datasets;
  if (H5Ovisit2(file, H5_INDEX_NAME, H5_ITER_INC, CollectDataset, &datasets, H5O_INFO_BASIC) < 0) {
    H5Eclear2(H5E_DEFAULT);
    RefuseLayout(shown, "", "", "cannot list its datasets");
  }
  bool seen[4] = {false, false, false, false};
  const char* required[4] = {archive::kRunIndex, archive::kRunId, archive::kRunStatus, archive::kRunMessage};
  for (const std::string& path : datasets) {
    if (!CheckRunDataset(file, path, runs, shown)) continue;
    for (int k = 0; k < 4; ++k) seen[k] = seen[k] || path == required[k];
  }
  for (int k = 0; k < 4; ++k) {
    if (!seen[k]) RefuseLayout(shown, required[k], "", "missing dataset /" + std::string(required[k]));
  }
  *run_count = runs;
}

// Reads, and throws away, everything of an open archive that libhdf5 decodes from metadata rather than
// copies from raw chunks: every attribute of every object (the object headers and, for variable-length
// values such as the root's strings or DIMENSION_LIST, the global heap collections) and every
// variable-length dataset (runs/message: the global heap). Run in the child of GuardArchiveDecode, so
// that a crash or hang of libhdf5 on a damaged structure happens there first. Raw numeric chunks are not
// read (the readers' own checks cover them, and they cost the file's size).
void ReadAttributes(hid_t object) {
  const auto read = [](hid_t location, const char* name, const H5A_info_t*, void*) -> herr_t {
    const hid_t attribute = H5Aopen(location, name, H5P_DEFAULT);
    if (attribute < 0) return 0;
    Handle owned(attribute);
    const hid_t file_type = H5Aget_type(attribute);
    const hid_t space_id = H5Aget_space(attribute);
    Handle type(file_type), space(space_id);
    if (file_type < 0 || space_id < 0) return 0;
    Handle memory(H5Tget_native_type(file_type, H5T_DIR_DEFAULT));
    const hssize_t points = H5Sget_simple_extent_npoints(space_id);
    const std::size_t size = memory ? H5Tget_size(memory.get()) : 0;
    constexpr hssize_t kLargest = hssize_t{1} << 26;  // 64 MiB: not an attribute gesweep wrote
    if (!memory || points <= 0 || size == 0 || points > kLargest / static_cast<hssize_t>(size)) return 0;
    std::vector<unsigned char> buffer(static_cast<std::size_t>(points) * size);
    // (Reclaiming frees the variable-length parts; for a fixed-size type it has nothing to do.)
    if (H5Aread(attribute, memory.get(), buffer.data()) >= 0) {
      H5Dvlen_reclaim(memory.get(), space_id, H5P_DEFAULT, buffer.data());
    }
    return 0;
  };
  H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, nullptr, read, nullptr);
  H5Eclear2(H5E_DEFAULT);
}

void ReadVariableLengthRows(hid_t dataset) {
  Handle file_type(H5Dget_type(dataset));
  Handle space(H5Dget_space(dataset));
  if (!file_type || !space) return;
  const bool variable =
      H5Tdetect_class(file_type.get(), H5T_VLEN) > 0 || H5Tis_variable_str(file_type.get()) > 0;
  if (!variable || H5Sget_simple_extent_ndims(space.get()) != 1) return;
  Handle memory(H5Tget_native_type(file_type.get(), H5T_DIR_DEFAULT));
  hsize_t rows = 0;
  if (!memory || H5Sget_simple_extent_dims(space.get(), &rows, nullptr) < 0) return;
  const std::size_t size = H5Tget_size(memory.get());
  constexpr hsize_t kPiece = 65536;
  std::vector<unsigned char> buffer(static_cast<std::size_t>(std::min(rows, kPiece)) * size);
  for (hsize_t first = 0; first < rows; first += kPiece) {
    hsize_t count = std::min(kPiece, rows - first);
    Handle piece(H5Screate_simple(1, &count, nullptr));
    if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, &first, nullptr, &count, nullptr) < 0) return;
    if (H5Dread(dataset, memory.get(), piece.get(), space.get(), H5P_DEFAULT, buffer.data()) < 0) return;
    H5Dvlen_reclaim(memory.get(), piece.get(), H5P_DEFAULT, buffer.data());
  }
}

herr_t DecodeObject(hid_t file, const char* name, const H5O_info_t* info, void*) {
  const hid_t raw = H5Oopen(file, name, H5P_DEFAULT);
  if (raw < 0) return 0;
  Handle object(raw);
  ReadAttributes(raw);
  if (info->type == H5O_TYPE_DATASET) ReadVariableLengthRows(raw);
  H5Eclear2(H5E_DEFAULT);
  return 0;
}

void DecodeMetadata(hid_t file) {
  H5Ovisit2(file, H5_INDEX_NAME, H5_ITER_INC, DecodeObject, nullptr, H5O_INFO_BASIC);
  H5Eclear2(H5E_DEFAULT);
}

// Opens the archive read-only, or else as a snapshot (SWMR read, `snapshot` set): the file, or a
// negative id with HDF5's error of the first attempt in `first_error`.
hid_t OpenReadOnly(const std::filesystem::path& path, hid_t fapl, bool& snapshot, std::string& first_error) {
  hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  if (id < 0) {
    first_error = hdf5::LastError();
    H5Eclear2(H5E_DEFAULT);
    // Being written by a sweep (SWMR mode), or left open by a writer that died: a snapshot. An SWMR
    // reader re-reads a metadata block whose checksum fails (a writer may be rewriting it), sleeping
    // 1 ns, 2 ns, 4 ns, ... between attempts; HDF5's default of 100 attempts sleeps for hours on a
    // damaged file (fuzz_archive: opens that never returned). 24 attempts sleep 17 ms in all, far
    // longer than a writer takes to flush one block.
    Check(H5Pset_metadata_read_attempts(fapl, kSnapshotReadAttempts), "metadata read attempts");
    id = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);
    snapshot = id >= 0;
    H5Eclear2(H5E_DEFAULT);
  }
  return id;
}

// A truncated archive opened through a copy extended to its recorded size (`owner` then owns the
// copy, removed with its last owner), or nullopt when the file is not the size HDF5's error gave.
// Throws InputError when the copy cannot be made, or does not open.
std::optional<ArchiveReader> OpenExtendedCopy(const std::filesystem::path& path,
                                              const std::pair<std::uintmax_t, std::uintmax_t>& truncated,
                                              std::shared_ptr<const std::filesystem::path>& owner) {
  const std::string shown = path.string();
  std::error_code ec;
  const std::filesystem::path copy = path.string() + ".repair";
  if (!(std::filesystem::file_size(path, ec) == truncated.first && !ec)) return std::nullopt;
  std::filesystem::remove(copy, ec);
  std::filesystem::copy_file(path, copy, ec);
  if (!ec) std::filesystem::resize_file(copy, truncated.second, ec);
  if (!ec) {
    std::shared_ptr<const std::filesystem::path> made(new std::filesystem::path(copy),
                                                      [](const std::filesystem::path* p) {
                                                        std::error_code ignored;
                                                        std::filesystem::remove(*p, ignored);
                                                        delete p;
                                                      });
    ArchiveReader repaired = [&] {
      try {
        return ArchiveReader::Open(copy, /*repair_truncated=*/false);
      } catch (const InputError& e) {
        throw InputError(shown, e.key(), e.value(),
                         e.expected() + " (in a copy extended to the size HDF5 recorded, " +
                             std::to_string(truncated.second) + " bytes)");
      }
    }();
    owner = std::move(made);
    return repaired;
  }
  const std::string why = ec.message();
  std::filesystem::remove(copy, ec);
  throw InputError(shown, "", "",
                   "the file is " + std::to_string(truncated.second - truncated.first) +
                       " bytes shorter than HDF5 recorded (a write failed half-way); resuming it reads a "
                       "copy extended to " +
                       std::to_string(truncated.second) + " bytes, " + copy.string() +
                       ", which could not be made: " + why + "; the file is unchanged, free the space");
}

// Refuses an archive HDF5 did not open: RequestError for a truncated one (resume repairs it),
// InputError otherwise.
[[noreturn]] void RefuseUnopened(const std::string& shown,
                                 const std::optional<std::pair<std::uintmax_t, std::uintmax_t>>& truncated,
                                 const std::string& first_error) {
  if (truncated) {
    throw RequestError(
        shown, "", "",
        "the file is " + std::to_string(truncated->second - truncated->first) +
            " bytes shorter than HDF5 recorded: a write failed half-way (disk full?); its complete "
            "batches are kept",
        "resume_repairs", shown);
  }
  throw InputError(shown, "", "",
                   "archive in use or unreadable: cannot open it now (HDF5: " + first_error +
                       "); if no gesweep is writing it, it may be damaged");
}

// The root names gesweep's format, of a version this engine reads. Throws InputError.
void CheckFormat(hid_t id, const std::string& shown) {
  std::optional<std::string> format;
  std::optional<std::int64_t> version;
  try {
    format = hdf5::ReadStringAttribute(id, "format");
    version = hdf5::ReadIntegerAttribute(id, "format_version");
  } catch (const ArchiveError&) {
    H5Eclear2(H5E_DEFAULT);
  }
  if (!format || *format != archive::kFormatName) {
    throw InputError(shown, "format", format.value_or(""),
                     "not a gesweep archive (no format = \"gesweep-archive\")");
  }
  if (!version || *version > archive::kFormatVersion) {
    throw InputError(shown, "format_version", version ? std::to_string(*version) : "",
                     "expected format version <= " + std::to_string(archive::kFormatVersion) +
                         " (this engine is older than the archive)");
  }
}

}  // namespace

ArchiveReader::ArchiveReader(std::filesystem::path path, Handle file, bool snapshot)
    : path_(std::move(path)), file_(std::move(file)), snapshot_(snapshot) {}

ArchiveReader ArchiveReader::Open(const std::filesystem::path& path, bool repair_truncated) {
  hdf5::Quiet();
  const std::string shown = path.string();
  // Before HDF5 sees it: a FIFO or a device would block H5Fis_hdf5 for ever or never end.
  RequireRegularFile(path, "archive");
  // Before HDF5 decodes it in this process: the same open and every metadata read in a child with a
  // deadline, since on some damaged files libhdf5 itself loops for ever or crashes (11.4).
  // What the check refuses is refused in its words without decoding the file here again; a file
  // shorter than recorded goes on to the repair when the caller asked for it.
  archive::GuardArchiveDecode(
      shown,
      [&path] {
        hdf5::Quiet();
        const ArchiveReader reader = Open(path);
        DecodeMetadata(reader.file());
      },
      repair_truncated ? "resume_repairs" : "");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError(shown, "", "", "not an HDF5 file (expected a gesweep archive)");
  }
  Handle fapl = hdf5::FileAccess();
  bool snapshot = false;
  std::string first_error;
  const hid_t id = OpenReadOnly(path, fapl.get(), snapshot, first_error);
  if (id < 0) {
    // A write that failed half-way (disk full, a file-size limit) leaves the file shorter than the
    // size HDF5 recorded for it: "truncated file: eof = A, ..., stored_eof = B".
    const auto truncated = TruncatedSizes(first_error);
    if (truncated && repair_truncated) {
      // The writer resuming it reads only its complete batches (statuses first, metadata checksummed)
      // into a fresh file that replaces it; the missing tail, zeros, belongs to the batch that failed.
      // Extended is a copy: until the resume has found it a resumable archive of its study, the file
      // keeps its bytes (a refused resume leaves it as it was).
      std::shared_ptr<const std::filesystem::path> owner;
      std::optional<ArchiveReader> repaired = OpenExtendedCopy(path, *truncated, owner);
      if (repaired) {
        repaired->path_ = path;
        repaired->repair_copy_ = std::move(owner);
        return std::move(*repaired);
      }
    }
    RefuseUnopened(shown, truncated, first_error);
  }
  ArchiveReader reader(path, Handle(id), snapshot);
  CheckFormat(id, shown);
  ValidateLayout(id, shown, &reader.run_count_);
  reader.is_virtual_ = reader.StringAttribute("merge_kind") == "virtual" || archive::HasVirtualDatasets(id);
  if (reader.is_virtual_) reader.CheckVirtualSources();
  return reader;
}

void ArchiveReader::CheckVirtualSources() {
  // A virtual archive reads its shards in place, where HDF5 finds them, and HDF5 silently gives fill
  // values for a shard it cannot find, another file's runs for a file put in its place, and recurses
  // without end through virtual archives that read each other: each source is checked first.
  archive::SourceCheck check = archive::CheckVirtualSources(file_.get(), path_);
  sources_ = std::move(check.sources);
  files_read_ = std::move(check.files);
  for (std::string& note : check.notes) {
    archive::SendArchiveNote(note);
    notes_.push_back(std::move(note));
  }
}

void ArchiveReader::Close() {
  file_.Reset();
  repair_copy_.reset();
}

std::string ArchiveReader::StringAttribute(const std::string& name) const {
  return hdf5::ReadStringAttribute(file_.get(), name).value_or("");
}

std::int64_t ArchiveReader::IntegerAttribute(const std::string& name) const {
  const auto value = hdf5::ReadIntegerAttribute(file_.get(), name);
  if (!value) throw ArchiveError(path_.string() + ": missing root attribute " + name);
  return *value;
}

std::vector<std::string> ArchiveReader::StringListAttribute(const std::string& name) const {
  return hdf5::ReadStringListAttribute(file_.get(), name);
}

namespace {

// The object at `path`, or an invalid handle when there is none.
Handle OpenObject(hid_t file, const std::string& path) {
  if (!hdf5::Exists(file, path)) return Handle();
  return Handle(H5Oopen(file, path.c_str(), H5P_DEFAULT), "open " + path);
}

// read(object) on the object at `path`; no value (nullopt, an empty list) when there is none.
template <class Read>
auto ReadOf(hid_t file, const std::string& path, Read read) -> decltype(read(hid_t{})) {
  Handle o = OpenObject(file, path);
  if (!o) return {};
  return read(o.get());
}

}  // namespace

std::optional<std::string> ArchiveReader::StringAttributeOf(const std::string& object,
                                                            const std::string& name) const {
  return ReadOf(file_.get(), object, [&](hid_t o) { return hdf5::ReadStringAttribute(o, name); });
}

std::optional<std::int64_t> ArchiveReader::IntegerAttributeOf(const std::string& object,
                                                              const std::string& name) const {
  return ReadOf(file_.get(), object, [&](hid_t o) { return hdf5::ReadIntegerAttribute(o, name); });
}

std::optional<double> ArchiveReader::DoubleAttributeOf(const std::string& object,
                                                       const std::string& name) const {
  return ReadOf(file_.get(), object, [&](hid_t o) { return hdf5::ReadDoubleAttribute(o, name); });
}

std::vector<std::string> ArchiveReader::StringListAttributeOf(const std::string& object,
                                                              const std::string& name) const {
  return ReadOf(file_.get(), object, [&](hid_t o) { return hdf5::ReadStringListAttribute(o, name); });
}

std::vector<double> ArchiveReader::DoubleListAttributeOf(const std::string& object,
                                                         const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o || H5Aexists(o.get(), name.c_str()) <= 0) return {};
  Handle attribute = hdf5::OpenAttribute(o.get(), name);
  Handle type(H5Aget_type(attribute.get()), "type of attribute " + name);
  const H5T_class_t type_class = H5Tget_class(type.get());
  if (type_class != H5T_FLOAT && type_class != H5T_INTEGER) {
    throw ArchiveError(path_.string() + ": attribute " + name + " of " + object + " is not numeric");
  }
  Handle space(H5Aget_space(attribute.get()), "space of attribute " + name);
  const auto count = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
  std::vector<double> values(count);
  if (count > 0) Check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, values.data()), "read attribute " + name);
  return values;
}

bool ArchiveReader::Exists(const std::string& path) const { return hdf5::Exists(file_.get(), path); }

ArchiveReader::DatasetInfo ArchiveReader::Describe(const std::string& path) const {
  Handle dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), "open " + path + " of " + path_.string());
  Handle type(H5Dget_type(dataset.get()), "type of " + path);
  DatasetInfo info;
  switch (H5Tget_class(type.get())) {
    case H5T_FLOAT:
      info.kind = DatasetInfo::Kind::kFloat;
      break;
    case H5T_INTEGER:
      info.kind = DatasetInfo::Kind::kInteger;
      break;
    case H5T_COMPOUND:
      info.kind = DatasetInfo::Kind::kCompound;
      break;
    case H5T_STRING:
      info.kind = DatasetInfo::Kind::kString;
      break;
    default:
      info.kind = DatasetInfo::Kind::kOther;
      break;
  }
  info.dims = hdf5::Dimensions(dataset.get());
  return info;
}

std::vector<std::int64_t> ArchiveReader::ReadIntegers(const std::string& path, std::int64_t first,
                                                      std::int64_t count) const {
  std::vector<std::int64_t> values(static_cast<std::size_t>(count));
  ReadRows(path, first, count, H5T_NATIVE_INT64, values.data());
  return values;
}

std::vector<std::string> ArchiveReader::Datasets() const {
  std::vector<std::string> names;
  Check(H5Ovisit2(file_.get(), H5_INDEX_NAME, H5_ITER_INC, CollectDataset, &names, H5O_INFO_BASIC),
        "list datasets of " + path_.string());
  return names;
}

void ArchiveReader::ReadRows(const std::string& path, std::int64_t first, std::int64_t count,
                             hid_t memory_type, void* out) const {
  Handle dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), "open " + path);
  Handle memory;
  Handle space = hdf5::SelectRows(dataset.get(), first, count, &memory);
  Check(H5Dread(dataset.get(), memory_type, memory.get(), space.get(), H5P_DEFAULT, out),
        "read " + path + " of " + path_.string());
}

std::vector<double> ArchiveReader::ReadDoubles(const std::string& path, std::int64_t first,
                                               std::int64_t count) const {
  Handle dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), "open " + path);
  const auto dims = hdf5::Dimensions(dataset.get());
  const std::int64_t width = dims.size() == 2 ? dims[1] : 1;
  std::vector<double> values(static_cast<std::size_t>(count * width));
  ReadRows(path, first, count, H5T_NATIVE_DOUBLE, values.data());
  return values;
}

std::vector<std::int8_t> ArchiveReader::ReadStatus(std::int64_t first, std::int64_t count) const {
  std::vector<std::int8_t> status(static_cast<std::size_t>(count));
  ReadRows(archive::kRunStatus, first, count, H5T_NATIVE_INT8, status.data());
  return status;
}

std::vector<std::string> ArchiveReader::ReadMessages(std::int64_t first, std::int64_t count) const {
  Handle dataset(H5Dopen2(file_.get(), archive::kRunMessage, H5P_DEFAULT), "open runs/message");
  Handle type(H5Dget_type(dataset.get()), "type of runs/message");
  if (H5Tis_variable_str(type.get()) > 0) {
    // Variable-length strings: HDF5 allocates each one; they are copied and given back.
    Handle memory_type(H5Tcopy(H5T_C_S1), "string type");
    Check(H5Tset_size(memory_type.get(), H5T_VARIABLE), "string size");
    Check(H5Tset_cset(memory_type.get(), H5Tget_cset(type.get())), "string charset");
    std::vector<char*> pointers(static_cast<std::size_t>(count), nullptr);
    Handle memory;
    Handle space = hdf5::SelectRows(dataset.get(), first, count, &memory);
    Check(H5Dread(dataset.get(), memory_type.get(), memory.get(), space.get(), H5P_DEFAULT, pointers.data()),
          "read runs/message of " + path_.string());
    std::vector<std::string> messages;
    messages.reserve(pointers.size());
    for (const char* text : pointers) messages.emplace_back(text != nullptr ? text : "");
    H5Dvlen_reclaim(memory_type.get(), memory.get(), H5P_DEFAULT, pointers.data());
    return messages;
  }
  const std::size_t length = H5Tget_size(type.get());
  std::vector<char> buffer(static_cast<std::size_t>(count) * length);
  ReadRows(archive::kRunMessage, first, count, type.get(), buffer.data());
  std::vector<std::string> messages;
  for (std::int64_t r = 0; r < count; ++r) {
    const char* text = buffer.data() + static_cast<std::size_t>(r) * length;
    messages.emplace_back(text, strnlen(text, length));
  }
  return messages;
}

std::vector<std::int64_t> ArchiveReader::CompleteBlocks(int chunk_runs) const {
  std::vector<std::int64_t> blocks;
  for (std::int64_t first = 0, block = 0; first < run_count_; first += chunk_runs, ++block) {
    const std::int64_t count = std::min<std::int64_t>(chunk_runs, run_count_ - first);
    const auto status = ReadStatus(first, count);
    if (std::all_of(status.begin(), status.end(), [](std::int8_t s) { return s != 0; }))
      blocks.push_back(block);
  }
  return blocks;
}

void ArchiveReader::CheckSameSweep(const SweepPlan& plan, const std::string& shown) const {
  auto refuse = [&](const std::string& what, const std::string& theirs, const std::string& ours) {
    throw RequestError("command line", "output", shown,
                       "cannot resume: the archive has " + what + " " + theirs + " but this run has " + ours,
                       "force_or_other_output");
  };
  if (StringAttribute("study_fingerprint") != archive::FingerprintText(plan.study().fingerprint)) {
    refuse("study fingerprint",
           StringAttribute("study_fingerprint") + " (study " + StringAttribute("study_path") + ")",
           archive::FingerprintText(plan.study().fingerprint) + " (study " + plan.study().path +
               "; a changed study or aircraft file)");
  }
  if (StringAttribute("engine_version") != EngineVersion() ||
      StringAttribute("git_commit") != EngineGitCommit()) {
    refuse("engine", StringAttribute("engine_version") + " " + StringAttribute("git_commit"),
           EngineVersion() + " " + EngineGitCommit());
  }
  const std::string shard = std::to_string(plan.shard().index) + "/" + std::to_string(plan.shard().count);
  if (StringAttribute("shard") != shard) refuse("shard", StringAttribute("shard"), shard);
  if (IntegerAttribute("design_runs") != plan.design_runs() ||
      IntegerAttribute("first_run") != plan.first_run() || run_count_ != plan.run_count()) {
    refuse("design size", std::to_string(IntegerAttribute("design_runs")),
           std::to_string(plan.design_runs()));
  }
}

void ArchiveReader::VerifyRunIds(const SweepPlan& plan, const std::vector<std::int64_t>& blocks,
                                 const std::string& shown) const {
  std::vector<double> row(static_cast<std::size_t>(plan.design().column_count()));
  for (std::int64_t block : blocks) {
    const std::int64_t local = block * plan.chunk_runs();
    std::int64_t index = 0;
    std::uint64_t id = 0;
    ReadRows(archive::kRunIndex, local, 1, H5T_NATIVE_INT64, &index);
    ReadRows(archive::kRunId, local, 1, H5T_NATIVE_UINT64, &id);
    plan.design().Row(plan.first_run() + local, row.data());
    if (index != plan.first_run() + local || id != plan.RunId(row.data())) {
      throw RequestError("command line", "output", shown,
                         "cannot resume: run " + std::to_string(plan.first_run() + local) +
                             " of the archive has other parameters than this study gives it",
                         "force_use");
    }
  }
}

void ArchiveReader::CopyBlocks(ArchiveWriter& writer, const std::vector<std::int64_t>& blocks,
                               int chunk_runs) const {
  // Raw chunk copy (H5Dread_chunk / H5Dwrite_chunk): the complete batches of the crashed file are
  // taken as they are stored, nothing is inflated or deflated again, each target chunk written
  // once. runs/status last, after a flush, as when the batches were first written.
  const archive::ArchiveLayout& layout = writer.layout();
  std::vector<unsigned char> buffer;
  auto copy = [&](int index) {
    const archive::StoredDataset& stored = layout.datasets()[static_cast<std::size_t>(index)];
    Handle source(H5Dopen2(file_.get(), stored.path.c_str(), H5P_DEFAULT), "open " + stored.path);
    const hid_t target = writer.datasets_[static_cast<std::size_t>(index)].get();
    for (std::int64_t block : blocks) {
      const std::int64_t first = block * chunk_runs;
      const std::int64_t end = std::min<std::int64_t>(first + chunk_runs, run_count_);
      for (std::int64_t row = first; row < end; row += stored.chunk_rows) {
        const hsize_t offset[2] = {static_cast<hsize_t>(row), 0};
        unsigned mask = 0;
        haddr_t address = HADDR_UNDEF;
        hsize_t size = 0;
        Check(H5Dget_chunk_info_by_coord(source.get(), offset, &mask, &address, &size),
              "chunk of " + stored.path + " in " + path_.string());
        if (address == HADDR_UNDEF || size == 0) continue;  // never written (e.g. a batch without messages)
        buffer.resize(static_cast<std::size_t>(size));
        std::uint32_t filters = 0;
        Check(H5Dread_chunk(source.get(), H5P_DEFAULT, offset, &filters, buffer.data()),
              "read a chunk of " + stored.path + " of " + path_.string());
        Check(H5Dwrite_chunk(target, H5P_DEFAULT, filters, offset, buffer.size(), buffer.data()),
              "copy a chunk of " + stored.path);
      }
    }
  };
  const int status = layout.status_dataset();
  for (int d = 0; d < static_cast<int>(layout.datasets().size()); ++d) {
    if (d != status) copy(d);
  }
  Check(H5Fflush(writer.file_.get(), H5F_SCOPE_LOCAL), "flush " + writer.path_.string());
  copy(status);
}

}  // namespace gesweep
