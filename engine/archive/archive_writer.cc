#include "engine/archive/archive_writer.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_identity.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/dimension_scales.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"
#include "engine/common/request_error.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

// A dataset creation property list from the layout: chunked, the layout's filters in the layout's
// order (shuffle, deflate, Fletcher-32 -- the checksum covers the stored bytes, so a damaged chunk is
// detected before it is inflated), a fill value that means "not written".
Handle Creation(const archive::StoredDataset& d, hid_t fill_type) {
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), "dataset creation property list");
  std::vector<hsize_t> chunk{static_cast<hsize_t>(d.chunk_rows)};
  if (d.width > 1) chunk.push_back(static_cast<hsize_t>(d.width));
  Check(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()), "set chunk");
  if (d.filters.shuffle) Check(H5Pset_shuffle(dcpl.get()), "set shuffle");
  if (d.filters.deflate_level > 0)
    Check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(d.filters.deflate_level)), "set deflate");
  if (d.filters.fletcher32) Check(H5Pset_fletcher32(dcpl.get()), "set fletcher32");
  if (!d.fill.empty()) Check(H5Pset_fill_value(dcpl.get(), fill_type, d.fill.data()), "set fill value");
  Check(H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_IFSET), "set fill time");
  return dcpl;
}

Handle CreateDataset(hid_t file, const std::string& path, hid_t type, const std::vector<hsize_t>& dims,
                     hid_t dcpl, hsize_t chunk_rows) {
  // A dataset of exactly one chunk gets an unlimited row dimension: with fixed dimensions HDF5
  // 1.10 gives it its "single chunk" index, after whose direct chunk write H5Dread in the same
  // session returns the stored (filtered) bytes instead of the values.
  std::vector<hsize_t> maxdims = dims;
  if (dims[0] <= chunk_rows) maxdims[0] = H5S_UNLIMITED;
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()), "dataspace");
  return Handle(H5Dcreate2(file, path.c_str(), type, space.get(), H5P_DEFAULT, dcpl, H5P_DEFAULT),
                "create dataset " + path);
}

void Describe(hid_t object, const std::string& units, const std::string& description) {
  hdf5::WriteAttribute(object, "units", units);
  hdf5::WriteAttribute(object, "description", description);
}

std::string ParameterNameOf(const DesignParameter& parameter) {
  return ParameterCatalog()[static_cast<std::size_t>(parameter.id)].name;
}

void WriteDesignAttributes(hid_t group, const SweepPlan& plan) {
  const DesignSpec& spec = plan.design().spec();
  hdf5::WriteAttribute(
      group, "description",
      "The swept parameters: one float64 dataset per parameter, one value per run (a choice or "
      "boolean as the index of its level)");
  hdf5::WriteAttribute(group, "kind", std::string(ToString(spec.kind)));
  std::vector<std::string> names;
  for (const auto& p : spec.parameters) names.push_back(ParameterNameOf(p));
  hdf5::WriteAttribute(group, "parameters", names);
  hdf5::WriteAttribute(group, "run_count", plan.design_runs());
  switch (spec.kind) {
    case DesignKind::kGrid: {
      std::vector<std::int64_t> shape;
      for (const auto& p : spec.parameters) shape.push_back(static_cast<std::int64_t>(p.values.size()));
      hdf5::WriteAttribute(group, "shape", shape);
      hdf5::WriteAttribute(group, "order", "C: the last parameter varies fastest");
      break;
    }
    case DesignKind::kList:
      hdf5::WriteAttribute(group, "csv", spec.list_csv);
      break;
    case DesignKind::kLhs:
    case DesignKind::kMonteCarlo:
      hdf5::WriteAttribute(group, "samples", spec.samples);
      hdf5::WriteAttribute(group, "seed", static_cast<std::int64_t>(spec.seed));
      break;
    case DesignKind::kSobol:
      hdf5::WriteAttribute(group, "layout", "saltelli");
      hdf5::WriteAttribute(group, "base_samples", spec.base_samples);
      hdf5::WriteAttribute(group, "dimension", static_cast<std::int64_t>(spec.parameters.size()));
      hdf5::WriteAttribute(group, "second_order", static_cast<std::int64_t>(spec.second_order ? 1 : 0));
      hdf5::WriteAttribute(group, "block_rows",
                           SaltelliBlockRows(static_cast<int>(spec.parameters.size()), spec.second_order));
      hdf5::WriteAttribute(group, "block_layout",
                           spec.second_order ? "A, AB_1..AB_D, BA_1..BA_D, B" : "A, AB_1..AB_D, B");
      hdf5::WriteAttribute(group, "sequence",
                           "boost::random::sobol of dimension 2D, points 1..N (origin skipped); A = first D "
                           "coordinates, B = last D");
      break;
    case DesignKind::kMorris:
      hdf5::WriteAttribute(group, "trajectories", spec.trajectories);
      hdf5::WriteAttribute(group, "levels", static_cast<std::int64_t>(spec.levels));
      hdf5::WriteAttribute(group, "delta", spec.levels / (2.0 * (spec.levels - 1)));
      hdf5::WriteAttribute(group, "seed", static_cast<std::int64_t>(spec.seed));
      hdf5::WriteAttribute(group, "trajectory_rows", static_cast<std::int64_t>(spec.parameters.size()) + 1);
      break;
    case DesignKind::kSingle:
      break;
  }
  // The value every run has of each parameter the analyses read but the design does not sweep: the
  // study's fixed values and the defaults.
  std::vector<std::string> fixed_names, base_names, base_units;
  std::vector<double> base_values;
  for (const auto& fixed : plan.study().fixed) {
    fixed_names.push_back(ParameterCatalog()[static_cast<std::size_t>(fixed.id)].name);
  }
  for (ParameterId id : plan.parameters_read()) {
    const auto& info = ParameterCatalog()[static_cast<std::size_t>(id)];
    if (std::find(names.begin(), names.end(), info.name) != names.end()) continue;
    base_names.push_back(info.name);
    base_units.push_back(info.units);
    base_values.push_back(plan.base_parameters()[static_cast<std::size_t>(id)]);
  }
  hdf5::WriteAttribute(group, "fixed_parameters", fixed_names);
  hdf5::WriteAttribute(group, "unswept_parameter_names", base_names);
  hdf5::WriteAttribute(group, "unswept_parameter_values", base_values);
  hdf5::WriteAttribute(group, "unswept_parameter_units", base_units);
}

// The root attributes of a new archive of `plan`: provenance and the runs it holds (schemas/archive.md,
// "Root attributes").
void WriteRootAttributes(hid_t file, const SweepPlan& plan, const RunProvenance& provenance) {
  const Study& study = plan.study();
  const std::int64_t n = plan.run_count();
  hdf5::WriteAttribute(file, "format", archive::kFormatName);
  hdf5::WriteAttribute(file, "format_version", static_cast<std::int64_t>(archive::kFormatVersion));
  // The identity (engine/archive/archive_identity.h): a new id for every archive created; the
  // fingerprint, the design runs and the shard below complete it.
  hdf5::WriteAttribute(file, "archive_id", archive::NewArchiveId());
  hdf5::WriteAttribute(file, "study_name", study.name);
  hdf5::WriteAttribute(file, "study_description", study.description);
  hdf5::WriteAttribute(file, "study_path", study.path);
  hdf5::WriteAttribute(file, "study_text", study.text);
  hdf5::WriteAttribute(file, "study_fingerprint", archive::FingerprintText(study.fingerprint));
  hdf5::WriteAttribute(file, "aircraft_path", study.aircraft ? study.aircraft->source_path : std::string());
  hdf5::WriteAttribute(file, "aircraft_text", study.aircraft ? study.aircraft->source_text : std::string());
  hdf5::WriteAttribute(file, "aircraft_name", study.aircraft ? study.aircraft->name : std::string());
  std::vector<std::string> analyses;
  for (const auto& analysis : study.analyses) analyses.emplace_back(analysis->name());
  hdf5::WriteAttribute(file, "analyses", analyses);
  hdf5::WriteAttribute(file, "engine_version", EngineVersion());
  hdf5::WriteAttribute(file, "git_commit", EngineGitCommit());
  hdf5::WriteAttribute(file, "compiler", CompilerDescription());
  char hdf5_version[32];
  unsigned major = 0, minor = 0, release = 0;
  H5get_libversion(&major, &minor, &release);
  std::snprintf(hdf5_version, sizeof(hdf5_version), "%u.%u.%u", major, minor, release);
  hdf5::WriteAttribute(file, "hdf5_version", std::string(hdf5_version));
  hdf5::WriteAttribute(file, "host", HostName());
  hdf5::WriteAttribute(file, "threads", static_cast<std::int64_t>(provenance.threads));
  hdf5::WriteAttribute(file, "command_line", provenance.command_line);
  hdf5::WriteAttribute(file, "shard",
                       std::to_string(plan.shard().index) + "/" + std::to_string(plan.shard().count));
  hdf5::WriteAttribute(file, "shard_index", static_cast<std::int64_t>(plan.shard().index));
  hdf5::WriteAttribute(file, "shard_count", static_cast<std::int64_t>(plan.shard().count));
  hdf5::WriteAttribute(file, "design_runs", plan.design_runs());
  hdf5::WriteAttribute(file, "first_run", plan.first_run());
  hdf5::WriteAttribute(file, "run_count", n);
  hdf5::WriteAttribute(file, "chunk_runs", static_cast<std::int64_t>(plan.chunk_runs()));
  hdf5::WriteAttribute(file, "start_time", UtcTimestamp());
  hdf5::WriteAttribute(file, "end_time", std::string());
  hdf5::WriteAttribute(file, "resumed_at", std::string());
  hdf5::WriteAttribute(file, "complete", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_ok", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_failed", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_pending", n);
  hdf5::WriteAttribute(file, "merged_from", std::vector<std::string>{});
  hdf5::WriteAttribute(file, "mpi_ranks", static_cast<std::int64_t>(provenance.ranks));
  if (provenance.node_index >= 0) {
    // A node's shard of an MPI sweep (docs/cluster.md): merged like any shard.
    hdf5::WriteAttribute(file, "node_index", static_cast<std::int64_t>(provenance.node_index));
    hdf5::WriteAttribute(file, "node_count", static_cast<std::int64_t>(provenance.node_count));
  }
}

// The file type of a layout's element kind: little-endian numbers, or the given compound and string types.
hid_t FileType(archive::ElementKind kind, hid_t complex_type, hid_t message_type) {
  switch (kind) {
    case archive::ElementKind::kFloat64:
      return H5T_IEEE_F64LE;
    case archive::ElementKind::kInt64:
      return H5T_STD_I64LE;
    case archive::ElementKind::kUInt64:
      return H5T_STD_U64LE;
    case archive::ElementKind::kInt32:
      return H5T_STD_I32LE;
    case archive::ElementKind::kInt8:
      return H5T_STD_I8LE;
    case archive::ElementKind::kComplex:
      return complex_type;
    case archive::ElementKind::kString:
      return message_type;
  }
  GESWEEP_UNREACHABLE();
}

// The attributes of the per-run dataset `d` of `stored`: units, description, and what its source adds
// (levels, fill, distribution and bounds, time axis, component names, ...).
void DescribeStored(hid_t d, const archive::StoredDataset& stored, const SweepPlan& plan) {
  const auto& parameters = plan.design().spec().parameters;
  const auto& columns = plan.schema().columns;
  switch (stored.source) {
    case archive::ValueSource::kDesign: {
      const DesignParameter& parameter = parameters[static_cast<std::size_t>(stored.column)];
      const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(parameter.id)];
      Describe(d, info.units, info.description);
      if (!info.levels.empty()) hdf5::WriteAttribute(d, "levels", info.levels);
      const DesignKind kind = plan.design().spec().kind;
      if (kind == DesignKind::kLhs || kind == DesignKind::kSobol || kind == DesignKind::kMorris) {
        hdf5::WriteAttribute(d, "distribution", std::string(ToString(parameter.distribution)));
        hdf5::WriteAttribute(d, "bounds", std::vector<double>{parameter.lower, parameter.upper});
      } else if (kind == DesignKind::kMonteCarlo) {
        hdf5::WriteAttribute(d, "distribution", DescribeDistribution(parameter));
        hdf5::WriteAttribute(d, "bounds", std::vector<double>{parameter.lower, parameter.upper});
      } else if (kind == DesignKind::kGrid) {
        hdf5::WriteAttribute(d, "axis_values", parameter.values);
      }
      break;
    }
    case archive::ValueSource::kResult: {
      const OutputColumn& column = columns[static_cast<std::size_t>(stored.column)];
      Describe(d, column.units, column.description);
      if (!column.levels.empty()) hdf5::WriteAttribute(d, "levels", column.levels);
      if (column.type == ColumnType::kInt8 || column.type == ColumnType::kInt32) {
        hdf5::WriteAttribute(d, "fill", static_cast<std::int64_t>(column.integer_fill));
      }
      if (!column.time_axis.empty()) hdf5::WriteAttribute(d, "time_axis", column.time_axis);
      if (!column.component_names.empty()) hdf5::WriteAttribute(d, "component_names", column.component_names);
      break;
    }
    case archive::ValueSource::kIndex:
      Describe(d, "1", "Index of the run in the design (0-based); -1 where not written yet");
      break;
    case archive::ValueSource::kId:
      Describe(d, "1",
               "Stable id of the run: FNV-1a hash of its design parameters' names and values "
               "(with runs/index, identifies the run across shards and resumes)");
      break;
    case archive::ValueSource::kStatus:
      Describe(d, "1",
               "Run status: 0 pending (not complete), 1 ok, 2 failed; written after the run's "
               "results, so a nonzero status marks a complete run");
      hdf5::WriteAttribute(d, "levels", RunStatusLevels());
      break;
    case archive::ValueSource::kMessage:
      Describe(d, "1",
               "Why a run failed, or a note on an ok run (e.g. no boundary); UTF-8, NUL-padded, at most " +
                   std::to_string(kMessageLength) +
                   " bytes (a longer message ends in '...'); empty for most runs, whose chunks are "
                   "never written");
      hdf5::WriteAttribute(d, "max_bytes", static_cast<std::int64_t>(kMessageLength));
      break;
  }
}

}  // namespace

ArchiveWriter::ArchiveWriter(std::filesystem::path path, const SweepPlan& plan)
    : path_(std::move(path)), plan_(plan), layout_(plan) {}

ArchiveWriter::~ArchiveWriter() {
  // A sweep that stopped on an error still closes the file cleanly: the statuses tell which runs
  // are complete, so --resume continues it.
  if (!finished_) file_.Reset();
  if (lock_held_) {
    std::error_code ec;
    std::filesystem::remove(path_.string() + ".lock", ec);
  }
  if (lock_fd_ >= 0) close(lock_fd_);
}

void ArchiveWriter::CreateSkeleton(hid_t file, const RunProvenance& provenance) {
  const std::int64_t n = plan_.run_count();
  const auto rows = static_cast<hsize_t>(n);

  WriteRootAttributes(file, plan_, provenance);

  for (const char* group :
       {archive::kRunsGroup, archive::kDesignGroup, archive::kResultsGroup, archive::kAnalysisGroup}) {
    hdf5::CreateGroups(file, group);
  }
  {
    Handle analysis(H5Gopen2(file, archive::kAnalysisGroup, H5P_DEFAULT), "open analysis group");
    hdf5::WriteAttribute(
        analysis.get(), "description",
        "Derived products written after the sweep: the stability boundary (gesweep boundary, "
        "from the archive) and sensitivity indices (gesweep sensitivity)");
  }

  for (const auto& axis : plan_.schema().axes) {
    hdf5::CreateGroups(file, axis.path.substr(0, axis.path.rfind('/')));
    hsize_t dims[1] = {axis.times_s.size()};
    Handle space(H5Screate_simple(1, dims, nullptr), "time axis space");
    Handle d(H5Dcreate2(file, axis.path.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                        H5P_DEFAULT),
             "create " + axis.path);
    Check(H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, axis.times_s.data()),
          "write " + axis.path);
    Describe(d.get(), "s", axis.description);
  }
  Handle complex_type = hdf5::ComplexType();
  Handle message_type = hdf5::FixedStringType(kMessageLength);
  for (const archive::StoredDataset& stored : layout_.datasets()) {
    const hid_t type = FileType(stored.kind, complex_type.get(), message_type.get());
    // The fill value is given in the stored type (little-endian, as the layout holds it).
    Handle dcpl = Creation(stored, type);
    std::vector<hsize_t> dims{rows};
    if (stored.width > 1) dims.push_back(static_cast<hsize_t>(stored.width));
    hdf5::CreateGroups(file, stored.path.substr(0, stored.path.rfind('/')));
    Handle d =
        CreateDataset(file, stored.path, type, dims, dcpl.get(), static_cast<hsize_t>(stored.chunk_rows));
    DescribeStored(d.get(), stored, plan_);
  }
  Handle design(H5Gopen2(file, archive::kDesignGroup, H5P_DEFAULT), "open design group");
  WriteDesignAttributes(design.get(), plan_);
  // The netCDF view: named dimensions, in the layout's order (object references are addresses).
  std::vector<std::string> paths;
  for (const archive::StoredDataset& stored : layout_.datasets()) paths.push_back(stored.path);
  archive::AttachDimensionScales(file, n, paths);
}

void ArchiveWriter::OpenDatasets() {
  datasets_.clear();
  for (const archive::StoredDataset& stored : layout_.datasets()) {
    Handle dataset(H5Dopen2(file_.get(), stored.path.c_str(), H5P_DEFAULT), "open dataset " + stored.path);
    const auto dims = hdf5::Dimensions(dataset.get());
    const bool shape_ok =
        !dims.empty() && dims[0] == plan_.run_count() &&
        (stored.width == 1 ? dims.size() == 1 : dims.size() == 2 && dims[1] == stored.width);
    if (!shape_ok) throw ArchiveError(path_.string() + ": dataset " + stored.path + " has the wrong shape");
    datasets_.push_back(std::move(dataset));
  }
}

void ArchiveWriter::CloseDatasets() { datasets_.clear(); }

void ArchiveWriter::WriteChunks(const ResultBlock& block) {
  const std::int64_t first = block.first_row - block_row_offset_;
  GESWEEP_DEMAND(first >= 0 && first + block.rows <= plan_.run_count());
  const int status = layout_.status_dataset();
  auto store = [&](const StoredChunk& chunk) {
    const archive::StoredDataset& stored = layout_.datasets()[static_cast<std::size_t>(chunk.dataset)];
    const hsize_t offset[2] = {static_cast<hsize_t>(first + chunk.row), 0};
    Check(H5Dwrite_chunk(datasets_[static_cast<std::size_t>(chunk.dataset)].get(), H5P_DEFAULT,
                         chunk.filter_mask, offset, chunk.bytes.size(), chunk.bytes.data()),
          "write " + stored.path + " of " + path_.string());
  };
  for (int c = 0; c < block.chunk_count; ++c) {
    const StoredChunk& chunk = block.chunks[static_cast<std::size_t>(c)];
    if (chunk.dataset != status) store(chunk);
  }
  // Results reach the disk before the statuses that declare them complete.
  Check(H5Fflush(file_.get(), H5F_SCOPE_LOCAL), "flush " + path_.string());
  for (int c = 0; c < block.chunk_count; ++c) {
    const StoredChunk& chunk = block.chunks[static_cast<std::size_t>(c)];
    if (chunk.dataset == status) store(chunk);
  }
  Check(H5Fflush(file_.get(), H5F_SCOPE_LOCAL), "flush " + path_.string());
}

void ArchiveWriter::Write(const ResultBlock& block) {
  // HDF5's error printing is per thread: keep the writer thread's errors for the exception.
  thread_local const bool quiet = (hdf5::Quiet(), true);
  (void)quiet;
  if (block.chunk_count > 0 || block.rows == 0) {
    WriteChunks(block);
    return;
  }
  unencoded_ = block;
  layout_.Encode(unencoded_);
  WriteChunks(unencoded_);
}

void ArchiveWriter::CountStatuses() {
  runs_ok_ = runs_failed_ = runs_pending_ = 0;
  const std::int64_t n = plan_.run_count();
  const std::int64_t step = std::max<std::int64_t>(plan_.chunk_runs(), 65536);
  std::vector<std::int8_t> status(static_cast<std::size_t>(std::min(step, n)));
  for (std::int64_t first = 0; first < n; first += step) {
    const std::int64_t count = std::min(step, n - first);
    Handle memory;
    const hid_t status_dataset = datasets_[static_cast<std::size_t>(layout_.status_dataset())].get();
    Handle space = hdf5::SelectRows(status_dataset, first, count, &memory);
    Check(H5Dread(status_dataset, H5T_NATIVE_INT8, memory.get(), space.get(), H5P_DEFAULT, status.data()),
          "read runs/status");
    for (std::int64_t i = 0; i < count; ++i) {
      const auto s = static_cast<RunStatus>(status[static_cast<std::size_t>(i)]);
      runs_ok_ += s == RunStatus::kOk;
      runs_failed_ += s == RunStatus::kFailed;
      runs_pending_ += s == RunStatus::kPending;
    }
  }
}

void ArchiveWriter::Finish() {
  hdf5::Quiet();
  CountStatuses();
  // Still in SWMR mode: existing attributes are rewritten in place (SWMR forbids creating objects,
  // not changing values), so there is no moment at which the file is open for writing outside
  // SWMR mode and a kill would leave it unreadable.
  hdf5::UpdateAttribute(file_.get(), "end_time", UtcTimestamp());
  hdf5::UpdateAttribute(file_.get(), "complete", static_cast<std::int64_t>(runs_pending_ == 0 ? 1 : 0));
  hdf5::UpdateAttribute(file_.get(), "runs_ok", runs_ok_);
  hdf5::UpdateAttribute(file_.get(), "runs_failed", runs_failed_);
  hdf5::UpdateAttribute(file_.get(), "runs_pending", runs_pending_);
  Check(H5Fflush(file_.get(), H5F_SCOPE_LOCAL), "flush " + path_.string());
  CloseDatasets();
  file_.Close("close " + path_.string());
  finished_ = true;
}

namespace {

// The output may be written in `mode`: not a directory, not an existing file unless resumed or
// forced, in a directory this user can write in. Returns whether it exists. Throws InputError (or
// RequestError).
bool CheckOutputPath(const std::filesystem::path& path, ArchiveOpenMode mode) {
  const std::string shown = path.string();
  const std::filesystem::path directory = RequireOutputDirectory(path, "output");
  std::error_code ec;
  const auto status = std::filesystem::symlink_status(path, ec);
  const bool exists = !ec && std::filesystem::exists(status);
  if (exists && std::filesystem::is_directory(std::filesystem::status(path, ec))) {
    throw InputError("command line", "output", shown,
                     "is a directory; expected an archive file name such as out.h5");
  }
  if (exists && mode == ArchiveOpenMode::kCreate) {
    throw RequestError("command line", "output", shown, "already exists", "resume_or_force");
  }
  if (access(directory.c_str(), W_OK) != 0) {
    // Why, in words: a read-only file system or directory is not "not enough space".
    const int error = errno;
    const std::string why = error == EROFS    ? ": it is on a read-only file system"
                            : error == EACCES ? ": it is read-only for this user (permission denied)"
                                              : std::string(": ") + std::strerror(error);
    throw InputError("command line", "output", shown,
                     "cannot write in the directory " + directory.string() + why);
  }
  return exists;
}

// Takes the flock on ARCHIVE.lock, its descriptor into `lock_fd`. Throws ArchiveError when the lock
// file cannot be made, InputError when another process holds the lock.
void LockArchive(const std::filesystem::path& path, int& lock_fd) {
  const std::string lock_path = path.string() + ".lock";
  lock_fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd < 0) throw ArchiveError("cannot create the lock file " + lock_path);
  if (flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
    throw InputError("command line", "output", path.string(),
                     "archive in use: another gesweep process is writing it (" + lock_path + " is locked)");
  }
}

// What a resume takes from the existing archive.
struct ResumePoint {
  std::vector<std::int64_t> complete_blocks;
  std::optional<ArchiveReader> crashed;  // the archive to copy the complete batches from
  std::string original_start;
  std::string original_id;  // a resume keeps the archive's identity
  std::string resumed_at;
};

// Checks that `existing` is a shard of this sweep and reads what a resume keeps of it; the plan
// takes its chunk_runs.
void ReadResumePoint(ArchiveReader& existing, SweepPlan& plan, const std::string& shown,
                     ResumePoint& resume) {
  if (!existing.StringListAttribute("merged_from").empty()) {
    throw InputError("command line", "output", shown,
                     "is a merged archive (gesweep merge), not a shard a sweep writes; resume the shards, "
                     "then merge again");
  }
  existing.CheckSameSweep(plan, shown);
  plan.set_chunk_runs(static_cast<int>(existing.IntegerAttribute("chunk_runs")));
  resume.complete_blocks = existing.CompleteBlocks(plan.chunk_runs());
  existing.VerifyRunIds(plan, resume.complete_blocks, shown);
  resume.original_start = existing.StringAttribute("start_time");
  resume.original_id = existing.StringAttribute("archive_id");
  resume.resumed_at = existing.StringAttribute("resumed_at");
  resume.resumed_at += (resume.resumed_at.empty() ? "" : ", ") + UtcTimestamp();
}

// Opens the existing archive for a resume: continued in place (the file returned, its attributes
// marked resumed), or else an empty handle and resume.crashed the archive to copy from.
Handle OpenForResume(const std::filesystem::path& path, SweepPlan& plan, const RunProvenance& provenance,
                     hid_t fapl, ResumePoint& resume, ArchiveOpenReport& out) {
  const std::string shown = path.string();
  ArchiveReader existing = ArchiveReader::Open(path, /*repair_truncated=*/true);
  ReadResumePoint(existing, plan, shown, resume);
  if (!existing.snapshot() && !existing.repaired()) {
    // Closed cleanly: continue in place, opened straight into SWMR mode. When that is impossible
    // (a reader holds the file's lock, e.g. h5py or gesweep query), resume as after a crash:
    // copy the complete batches into a fresh file and rename it over (the reader keeps its view).
    existing.Close();
    const hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDWR | H5F_ACC_SWMR_WRITE, fapl);
    H5Eclear2(H5E_DEFAULT);
    if (id < 0) {
      resume.crashed.emplace(ArchiveReader::Open(path));
      out.kind = ArchiveOpenReport::Kind::kResumedAfterCrash;
      out.note = "another process holds it open";
      return Handle();
    }
    Handle file(id);
    hdf5::UpdateAttribute(file.get(), "resumed_at", resume.resumed_at);
    hdf5::UpdateAttribute(file.get(), "end_time", std::string());
    hdf5::UpdateAttribute(file.get(), "complete", std::int64_t{0});
    hdf5::UpdateAttribute(file.get(), "threads", static_cast<std::int64_t>(provenance.threads));
    hdf5::UpdateAttribute(file.get(), "host", HostName());
    hdf5::UpdateAttribute(file.get(), "command_line", provenance.command_line);
    Check(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "flush " + shown);
    return file;
  }
  // (A truncated file was read through a repaired copy: its complete batches go into a fresh file,
  // renamed over it only now that it is known to be a resumable archive of this study.)
  const bool repaired = existing.repaired();
  resume.crashed.emplace(std::move(existing));
  out.kind = ArchiveOpenReport::Kind::kResumedAfterCrash;
  out.note =
      repaired ? "it is shorter than HDF5 recorded (a write failed half-way)" : "it was not closed cleanly";
  return Handle();
}

// The runs of the complete batches into out.runs_complete; the other batches into out.pending_blocks.
void TallyBlocks(const SweepPlan& plan, const std::vector<std::int64_t>& complete_blocks,
                 ArchiveOpenReport& out) {
  std::size_t next_complete = 0;
  for (std::int64_t block = 0; block < plan.block_count(); ++block) {
    if (next_complete < complete_blocks.size() && complete_blocks[next_complete] == block) {
      ++next_complete;
      const std::int64_t first = block * plan.chunk_runs();
      out.runs_complete += std::min<std::int64_t>(plan.chunk_runs(), plan.run_count() - first);
    } else {
      out.pending_blocks.push_back(block);
    }
  }
}

}  // namespace

std::unique_ptr<ArchiveWriter> ArchiveWriter::Open(const std::filesystem::path& path, SweepPlan& plan,
                                                   const RunProvenance& provenance, ArchiveOpenMode mode,
                                                   ArchiveOpenReport* report) {
  hdf5::Quiet();
  const std::string shown = path.string();
  const bool exists = CheckOutputPath(path, mode);

  std::unique_ptr<ArchiveWriter> writer(new ArchiveWriter(path, plan));
  // One writer per archive: a second `gesweep run` on the same -o (e.g. a requeued cluster task
  // while the first still runs) must not take it over.
  LockArchive(path, writer->lock_fd_);
  writer->lock_held_ = true;
  const std::filesystem::path temporary = path.string() + ".partial";
  Handle fapl = hdf5::FileAccess();
  ArchiveOpenReport local;
  ArchiveOpenReport& out = report ? *report : local;
  out = ArchiveOpenReport{};

  ResumePoint resume;
  if (exists && mode == ArchiveOpenMode::kResume) {
    writer->file_ = OpenForResume(path, plan, provenance, fapl.get(), resume, out);
    if (writer->file_) {
      writer->OpenDatasets();
      out.kind = ArchiveOpenReport::Kind::kResumedClean;
    }
  }

  if (!writer->file_) {
    // A new file, set up completely under a temporary name, then renamed into place: a person's
    // mistake or a crash before this point leaves no half-made archive under the requested name.
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    {
      Handle file(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                  "create " + temporary.string());
      writer->CreateSkeleton(file.get(), provenance);
      if (resume.crashed) {
        hdf5::WriteAttribute(file.get(), "start_time", resume.original_start);
        hdf5::WriteAttribute(file.get(), "resumed_at", resume.resumed_at);
        // The same archive continued (an archive from before identities gets its first one).
        if (!resume.original_id.empty()) hdf5::WriteAttribute(file.get(), "archive_id", resume.original_id);
        // Copy the complete batches of the crashed file, each chunk once.
        writer->file_ = std::move(file);
        writer->OpenDatasets();
        resume.crashed->CopyBlocks(*writer, resume.complete_blocks, plan.chunk_runs());
        Check(H5Fflush(writer->file_.get(), H5F_SCOPE_LOCAL), "flush " + temporary.string());
        writer->CloseDatasets();
        file = std::move(writer->file_);
      }
      file.Close("close " + temporary.string());
    }
    if (resume.crashed) resume.crashed->Close();
    // Reopened straight into SWMR mode, then renamed into place while open: under the requested name
    // the file is only ever absent, or consistent on disk (a kill at any moment leaves it readable).
    writer->file_ = Handle(H5Fopen(temporary.c_str(), H5F_ACC_RDWR | H5F_ACC_SWMR_WRITE, fapl.get()),
                           "open " + temporary.string() + " for writing");
    writer->OpenDatasets();
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
      writer->CloseDatasets();
      writer->file_.Reset();
      std::filesystem::remove(temporary);
      throw ArchiveError("rename " + temporary.string() + " to " + shown + ": " + ec.message());
    }
  }

  TallyBlocks(plan, resume.complete_blocks, out);
  return writer;
}

}  // namespace gesweep
