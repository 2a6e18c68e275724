#include "engine/archive/archive_writer.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

// Series chunks stay within this size: big enough to compress well, small enough for HDF5's
// default 1 MiB chunk cache.
constexpr std::int64_t kMaximumSeriesChunkBytes = 1 << 20;

std::string Hex(std::uint64_t value) {
  std::ostringstream out;
  out << std::hex;
  out.width(16);
  out.fill('0');
  out << value;
  return out.str();
}

// A dataset creation property list: chunked, shuffle + deflate (+ Fletcher-32 so a damaged chunk
// is detected on read rather than returned), with a fill value that means "not written".
Handle ChunkedCreation(const std::vector<hsize_t>& chunk, int compression_level, hid_t fill_type,
                       const void* fill) {
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), "dataset creation property list");
  Check(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()), "set chunk");
  Check(H5Pset_fletcher32(dcpl.get()), "set fletcher32");
  if (compression_level > 0) {
    Check(H5Pset_shuffle(dcpl.get()), "set shuffle");
    Check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(compression_level)), "set deflate");
  }
  if (fill != nullptr) Check(H5Pset_fill_value(dcpl.get(), fill_type, fill), "set fill value");
  Check(H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_IFSET), "set fill time");
  return dcpl;
}

Handle CreateDataset(hid_t file, const std::string& path, hid_t type, const std::vector<hsize_t>& dims,
                     hid_t dcpl) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), "dataspace");
  return Handle(H5Dcreate2(file, path.c_str(), type, space.get(), H5P_DEFAULT, dcpl, H5P_DEFAULT),
                "create dataset " + path);
}

void Describe(hid_t object, const std::string& units, const std::string& description) {
  hdf5::WriteAttribute(object, "units", units);
  hdf5::WriteAttribute(object, "description", description);
}

hid_t StoredType(ColumnType type, hid_t complex_type) {
  switch (type) {
    case ColumnType::kFloat64:
      return H5T_IEEE_F64LE;
    case ColumnType::kInt32:
      return H5T_STD_I32LE;
    case ColumnType::kInt8:
      return H5T_STD_I8LE;
    case ColumnType::kComplex:
      return complex_type;
  }
  return H5T_IEEE_F64LE;
}

std::string ParameterNameOf(const DesignParameter& parameter) {
  return ParameterCatalog()[static_cast<std::size_t>(parameter.id)].name;
}

void WriteRows(hid_t dataset, std::int64_t first, std::int64_t count, hid_t memory_type, const void* data,
               const std::string& what) {
  Handle memory;
  Handle file_space = hdf5::SelectRows(dataset, first, count, &memory);
  Check(H5Dwrite(dataset, memory_type, memory.get(), file_space.get(), H5P_DEFAULT, data), "write " + what);
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

}  // namespace

int SeriesChunkRows(int chunk_runs, int samples) {
  int best = 1;
  for (int d = 1; d <= chunk_runs; ++d) {
    if (chunk_runs % d == 0 && static_cast<std::int64_t>(d) * samples * 8 <= kMaximumSeriesChunkBytes)
      best = d;
  }
  return best;
}

ArchiveWriter::ArchiveWriter(std::filesystem::path path, const SweepPlan& plan)
    : path_(std::move(path)), plan_(plan) {
  complex_memory_type_ = Handle(H5Tcreate(H5T_COMPOUND, 2 * sizeof(double)), "complex memory type");
  Check(H5Tinsert(complex_memory_type_.get(), "re", 0, H5T_NATIVE_DOUBLE), "complex re");
  Check(H5Tinsert(complex_memory_type_.get(), "im", sizeof(double), H5T_NATIVE_DOUBLE), "complex im");
  message_type_ = hdf5::FixedStringType(kMessageLength);
}

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
  const Study& study = plan_.study();
  const std::int64_t n = plan_.run_count();
  const auto rows = static_cast<hsize_t>(n);
  const auto chunk = static_cast<hsize_t>(plan_.chunk_runs());
  const int level = study.compression_level;

  // Provenance (schemas/archive.md, "Root attributes").
  hdf5::WriteAttribute(file, "format", archive::kFormatName);
  hdf5::WriteAttribute(file, "format_version", static_cast<std::int64_t>(archive::kFormatVersion));
  hdf5::WriteAttribute(file, "study_name", study.name);
  hdf5::WriteAttribute(file, "study_description", study.description);
  hdf5::WriteAttribute(file, "study_path", study.path);
  hdf5::WriteAttribute(file, "study_text", study.text);
  hdf5::WriteAttribute(file, "study_fingerprint", Hex(study.fingerprint));
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
                       std::to_string(plan_.shard().index) + "/" + std::to_string(plan_.shard().count));
  hdf5::WriteAttribute(file, "shard_index", static_cast<std::int64_t>(plan_.shard().index));
  hdf5::WriteAttribute(file, "shard_count", static_cast<std::int64_t>(plan_.shard().count));
  hdf5::WriteAttribute(file, "design_runs", plan_.design_runs());
  hdf5::WriteAttribute(file, "first_run", plan_.first_run());
  hdf5::WriteAttribute(file, "run_count", n);
  hdf5::WriteAttribute(file, "chunk_runs", static_cast<std::int64_t>(plan_.chunk_runs()));
  hdf5::WriteAttribute(file, "start_time", UtcTimestamp());
  hdf5::WriteAttribute(file, "end_time", std::string());
  hdf5::WriteAttribute(file, "resumed_at", std::string());
  hdf5::WriteAttribute(file, "complete", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_ok", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_failed", std::int64_t{0});
  hdf5::WriteAttribute(file, "runs_pending", n);
  hdf5::WriteAttribute(file, "merged_from", std::vector<std::string>{});

  for (const char* group :
       {archive::kRunsGroup, archive::kDesignGroup, archive::kResultsGroup, archive::kAnalysisGroup}) {
    hdf5::CreateGroups(file, group);
  }
  {
    Handle analysis(H5Gopen2(file, archive::kAnalysisGroup, H5P_DEFAULT), "open analysis group");
    hdf5::WriteAttribute(analysis.get(), "description",
                         "Derived products written after the sweep: the stability boundary (gesweep boundary "
                         "--archive) and sensitivity indices (gesweep sensitivity)");
  }

  const double nan = std::numeric_limits<double>::quiet_NaN();
  {
    const std::int64_t fill = -1;
    Handle dcpl = ChunkedCreation({chunk}, level, H5T_NATIVE_INT64, &fill);
    Handle d = CreateDataset(file, archive::kRunIndex, H5T_STD_I64LE, {rows}, dcpl.get());
    Describe(d.get(), "1", "Index of the run in the design (0-based); -1 where not written yet");
  }
  {
    const std::uint64_t fill = 0;
    Handle dcpl = ChunkedCreation({chunk}, level, H5T_NATIVE_UINT64, &fill);
    Handle d = CreateDataset(file, archive::kRunId, H5T_STD_U64LE, {rows}, dcpl.get());
    Describe(d.get(), "1",
             "Stable id of the run: FNV-1a hash of its design parameters' names and values "
             "(with runs/index, identifies the run across shards and resumes)");
  }
  {
    const std::int8_t fill = 0;
    Handle dcpl = ChunkedCreation({chunk}, level, H5T_NATIVE_INT8, &fill);
    Handle d = CreateDataset(file, archive::kRunStatus, H5T_STD_I8LE, {rows}, dcpl.get());
    Describe(d.get(), "1",
             "Run status: 0 pending (not complete), 1 ok, 2 failed; written after the run's "
             "results, so a nonzero status marks a complete run");
    hdf5::WriteAttribute(d.get(), "levels", std::vector<std::string>{"pending", "ok", "failed"});
  }
  {
    Handle dcpl = ChunkedCreation({chunk}, level, H5T_NATIVE_INT8, nullptr);
    Handle d = CreateDataset(file, archive::kRunMessage, message_type_.get(), {rows}, dcpl.get());
    Describe(d.get(), "1",
             "Why a run failed, or a note on an ok run (e.g. no boundary); UTF-8, at most " +
                 std::to_string(kMessageLength) + " bytes");
  }
  for (const auto& parameter : plan_.design().spec().parameters) {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(parameter.id)];
    Handle dcpl = ChunkedCreation({chunk}, level, H5T_NATIVE_DOUBLE, &nan);
    Handle d = CreateDataset(file, archive::DesignPath(info.name), H5T_IEEE_F64LE, {rows}, dcpl.get());
    Describe(d.get(), info.units, info.description);
    if (!info.levels.empty()) hdf5::WriteAttribute(d.get(), "levels", info.levels);
    const DesignKind kind = plan_.design().spec().kind;
    if (kind == DesignKind::kLhs || kind == DesignKind::kSobol || kind == DesignKind::kMorris) {
      hdf5::WriteAttribute(d.get(), "distribution", std::string(ToString(parameter.distribution)));
      hdf5::WriteAttribute(d.get(), "bounds", std::vector<double>{parameter.lower, parameter.upper});
    } else if (kind == DesignKind::kGrid) {
      hdf5::WriteAttribute(d.get(), "axis_values", parameter.values);
    }
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
  for (const auto& column : plan_.schema().columns) {
    hdf5::CreateGroups(file, column.path.substr(0, column.path.rfind('/')));
    std::vector<hsize_t> dims{rows}, chunks{chunk};
    if (column.width > 1) {
      dims.push_back(static_cast<hsize_t>(column.width));
      const int chunk_rows =
          column.time_axis.empty() ? plan_.chunk_runs() : SeriesChunkRows(plan_.chunk_runs(), column.width);
      chunks = {static_cast<hsize_t>(chunk_rows), static_cast<hsize_t>(column.width)};
    }
    Handle dcpl;
    if (column.type == ColumnType::kFloat64) {
      dcpl = ChunkedCreation(chunks, level, H5T_NATIVE_DOUBLE, &nan);
    } else if (column.type == ColumnType::kInt32) {
      const std::int32_t fill = column.integer_fill;
      dcpl = ChunkedCreation(chunks, level, H5T_NATIVE_INT32, &fill);
    } else if (column.type == ColumnType::kInt8) {
      const auto fill = static_cast<std::int8_t>(column.integer_fill);
      dcpl = ChunkedCreation(chunks, level, H5T_NATIVE_INT8, &fill);
    } else {
      const double fill[2] = {nan, nan};
      dcpl = ChunkedCreation(chunks, level, complex_memory_type_.get(), fill);
    }
    Handle d =
        CreateDataset(file, column.path, StoredType(column.type, complex_type.get()), dims, dcpl.get());
    Describe(d.get(), column.units, column.description);
    if (!column.levels.empty()) hdf5::WriteAttribute(d.get(), "levels", column.levels);
    if (column.type == ColumnType::kInt8 || column.type == ColumnType::kInt32) {
      hdf5::WriteAttribute(d.get(), "fill", static_cast<std::int64_t>(column.integer_fill));
    }
    if (!column.time_axis.empty()) hdf5::WriteAttribute(d.get(), "time_axis", column.time_axis);
    if (!column.component_names.empty())
      hdf5::WriteAttribute(d.get(), "component_names", column.component_names);
  }
  Handle design(H5Gopen2(file, archive::kDesignGroup, H5P_DEFAULT), "open design group");
  WriteDesignAttributes(design.get(), plan_);
}

void ArchiveWriter::OpenDatasets() {
  auto open = [&](const std::string& path) {
    return Handle(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), "open dataset " + path);
  };
  index_ = open(archive::kRunIndex);
  id_ = open(archive::kRunId);
  status_ = open(archive::kRunStatus);
  message_ = open(archive::kRunMessage);
  design_.clear();
  results_.clear();
  for (const auto& parameter : plan_.design().spec().parameters) {
    design_.push_back(open(archive::DesignPath(ParameterNameOf(parameter))));
  }
  for (const auto& column : plan_.schema().columns) {
    Handle dataset = open(column.path);
    const auto dims = hdf5::Dimensions(dataset.get());
    const bool shape_ok =
        !dims.empty() && dims[0] == plan_.run_count() &&
        (column.width == 1 ? dims.size() == 1 : dims.size() == 2 && dims[1] == column.width);
    if (!shape_ok) throw ArchiveError(path_.string() + ": dataset " + column.path + " has the wrong shape");
    results_.push_back(std::move(dataset));
  }
}

void ArchiveWriter::Write(const ResultBlock& block) {
  // HDF5's error printing is per thread: keep the writer thread's errors for the exception.
  thread_local const bool quiet = (hdf5::Quiet(), true);
  (void)quiet;
  const std::int64_t first = block.first_row;
  const std::int64_t rows = block.rows;
  const auto n = static_cast<std::size_t>(rows);
  for (std::size_t c = 0; c < design_.size(); ++c) {
    WriteRows(design_[c].get(), first, rows, H5T_NATIVE_DOUBLE, block.design[c].data(), "design");
  }
  const auto& columns = plan_.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const OutputColumn& column = columns[c];
    const std::vector<double>& values = block.results[c];
    switch (column.type) {
      case ColumnType::kFloat64:
        WriteRows(results_[c].get(), first, rows, H5T_NATIVE_DOUBLE, values.data(), column.path);
        break;
      case ColumnType::kComplex:
        WriteRows(results_[c].get(), first, rows, complex_memory_type_.get(), values.data(), column.path);
        break;
      case ColumnType::kInt32: {
        int_buffer_.resize(n * static_cast<std::size_t>(column.width));
        for (std::size_t i = 0; i < int_buffer_.size(); ++i) {
          int_buffer_[i] = std::isnan(values[i]) ? column.integer_fill : static_cast<std::int32_t>(values[i]);
        }
        WriteRows(results_[c].get(), first, rows, H5T_NATIVE_INT32, int_buffer_.data(), column.path);
        break;
      }
      case ColumnType::kInt8: {
        byte_buffer_.resize(n * static_cast<std::size_t>(column.width));
        for (std::size_t i = 0; i < byte_buffer_.size(); ++i) {
          byte_buffer_[i] = std::isnan(values[i]) ? static_cast<std::int8_t>(column.integer_fill)
                                                  : static_cast<std::int8_t>(values[i]);
        }
        WriteRows(results_[c].get(), first, rows, H5T_NATIVE_INT8, byte_buffer_.data(), column.path);
        break;
      }
    }
  }
  WriteRows(index_.get(), first, rows, H5T_NATIVE_INT64, block.design_index.data(), archive::kRunIndex);
  WriteRows(id_.get(), first, rows, H5T_NATIVE_UINT64, block.run_id.data(), archive::kRunId);
  // Most batches have no message at all: their chunk stays unwritten and reads as the fill value
  // (empty strings), which saves compressing kMessageLength zero bytes per run.
  const bool any_message = std::any_of(block.message.begin(), block.message.begin() + rows,
                                       [](const std::string& m) { return !m.empty(); });
  if (any_message) {
    message_buffer_.assign(n * kMessageLength, '\0');
    for (std::size_t r = 0; r < n; ++r) {
      std::memcpy(message_buffer_.data() + r * kMessageLength, block.message[r].data(),
                  std::min<std::size_t>(block.message[r].size(), kMessageLength));
    }
    WriteRows(message_.get(), first, rows, message_type_.get(), message_buffer_.data(), archive::kRunMessage);
  }
  // Results reach the disk before the statuses that declare them complete.
  Check(H5Fflush(file_.get(), H5F_SCOPE_LOCAL), "flush " + path_.string());
  WriteRows(status_.get(), first, rows, H5T_NATIVE_INT8, block.status.data(), archive::kRunStatus);
  Check(H5Fflush(file_.get(), H5F_SCOPE_LOCAL), "flush " + path_.string());
}

void ArchiveWriter::CountStatuses() {
  runs_ok_ = runs_failed_ = runs_pending_ = 0;
  const std::int64_t n = plan_.run_count();
  const std::int64_t step = std::max<std::int64_t>(plan_.chunk_runs(), 65536);
  std::vector<std::int8_t> status(static_cast<std::size_t>(std::min(step, n)));
  for (std::int64_t first = 0; first < n; first += step) {
    const std::int64_t count = std::min(step, n - first);
    Handle memory;
    Handle space = hdf5::SelectRows(status_.get(), first, count, &memory);
    Check(H5Dread(status_.get(), H5T_NATIVE_INT8, memory.get(), space.get(), H5P_DEFAULT, status.data()),
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
  index_.Reset();
  id_.Reset();
  status_.Reset();
  message_.Reset();
  design_.clear();
  results_.clear();
  file_.Close("close " + path_.string());
  finished_ = true;
}

std::unique_ptr<ArchiveWriter> ArchiveWriter::Open(const std::filesystem::path& path, SweepPlan& plan,
                                                   const RunProvenance& provenance, ArchiveOpenMode mode,
                                                   ArchiveOpenReport* report) {
  hdf5::Quiet();
  const std::string shown = path.string();
  std::filesystem::path directory = path.parent_path();
  if (directory.empty()) directory = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec)) {
    throw InputError("command line", "-o", shown, "the directory " + directory.string() + " does not exist");
  }
  const auto status = std::filesystem::symlink_status(path, ec);
  const bool exists = !ec && std::filesystem::exists(status);
  if (exists && std::filesystem::is_directory(std::filesystem::status(path, ec))) {
    throw InputError("command line", "-o", shown,
                     "is a directory; expected an archive file name such as out.h5");
  }
  if (exists && mode == ArchiveOpenMode::kCreate) {
    throw InputError("command line", "-o", shown,
                     "already exists; pass --resume to continue it or --force to replace it");
  }
  if (access(directory.c_str(), W_OK) != 0) {
    throw InputError("command line", "-o", shown, "cannot write in the directory " + directory.string());
  }

  std::unique_ptr<ArchiveWriter> writer(new ArchiveWriter(path, plan));
  // One writer per archive: a second `gesweep run` on the same -o (e.g. a requeued cluster task
  // while the first still runs) must not take it over.
  const std::string lock_path = path.string() + ".lock";
  writer->lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (writer->lock_fd_ < 0) throw ArchiveError("cannot create the lock file " + lock_path);
  if (flock(writer->lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    throw InputError("command line", "-o", shown,
                     "archive in use: another gesweep process is writing it (" + lock_path + " is locked)");
  }
  writer->lock_held_ = true;
  const std::filesystem::path temporary = path.string() + ".partial";
  Handle fapl = hdf5::FileAccess();
  ArchiveOpenReport local;
  ArchiveOpenReport& out = report ? *report : local;
  out = ArchiveOpenReport{};

  std::vector<std::int64_t> complete_blocks;
  std::optional<ArchiveReader> crashed;
  std::string original_start;
  std::string resumed_at;
  if (exists && mode == ArchiveOpenMode::kResume) {
    ArchiveReader existing = ArchiveReader::Open(path, /*repair_truncated=*/true);
    existing.CheckSameSweep(plan, shown);
    plan.set_chunk_runs(static_cast<int>(existing.IntegerAttribute("chunk_runs")));
    complete_blocks = existing.CompleteBlocks(plan.chunk_runs());
    existing.VerifyRunIds(plan, complete_blocks, shown);
    original_start = existing.StringAttribute("start_time");
    resumed_at = existing.StringAttribute("resumed_at");
    resumed_at += (resumed_at.empty() ? "" : ", ") + UtcTimestamp();
    if (!existing.snapshot()) {
      // Closed cleanly: continue in place, opened straight into SWMR mode. When that is impossible
      // (a reader holds the file's lock, e.g. h5py or gesweep query), resume as after a crash:
      // copy the complete batches into a fresh file and rename it over (the reader keeps its view).
      existing.Close();
      const hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDWR | H5F_ACC_SWMR_WRITE, fapl.get());
      H5Eclear2(H5E_DEFAULT);
      if (id < 0) {
        crashed.emplace(ArchiveReader::Open(path));
        out.kind = ArchiveOpenReport::Kind::kResumedAfterCrash;
        out.note = "another process holds it open";
      }
      if (id >= 0) {
        writer->file_ = Handle(id);
        hdf5::UpdateAttribute(writer->file_.get(), "resumed_at", resumed_at);
        hdf5::UpdateAttribute(writer->file_.get(), "end_time", std::string());
        hdf5::UpdateAttribute(writer->file_.get(), "complete", std::int64_t{0});
        hdf5::UpdateAttribute(writer->file_.get(), "threads", static_cast<std::int64_t>(provenance.threads));
        hdf5::UpdateAttribute(writer->file_.get(), "host", HostName());
        hdf5::UpdateAttribute(writer->file_.get(), "command_line", provenance.command_line);
        Check(H5Fflush(writer->file_.get(), H5F_SCOPE_LOCAL), "flush " + shown);
        writer->OpenDatasets();
        out.kind = ArchiveOpenReport::Kind::kResumedClean;
      }
    } else {
      crashed.emplace(std::move(existing));
      out.kind = ArchiveOpenReport::Kind::kResumedAfterCrash;
      out.note = "it was not closed cleanly";
    }
  }

  if (!writer->file_) {
    // A new file, set up completely under a temporary name, then renamed into place: a person's
    // mistake or a crash before this point leaves no half-made archive under the requested name.
    std::filesystem::remove(temporary, ec);
    {
      Handle file(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                  "create " + temporary.string());
      writer->CreateSkeleton(file.get(), provenance);
      if (crashed) {
        hdf5::WriteAttribute(file.get(), "start_time", original_start);
        hdf5::WriteAttribute(file.get(), "resumed_at", resumed_at);
        // Copy the complete batches of the crashed file, each chunk once.
        writer->file_ = std::move(file);
        writer->OpenDatasets();
        crashed->CopyBlocks(*writer, complete_blocks, plan.chunk_runs());
        Check(H5Fflush(writer->file_.get(), H5F_SCOPE_LOCAL), "flush " + temporary.string());
        writer->index_.Reset();
        writer->id_.Reset();
        writer->status_.Reset();
        writer->message_.Reset();
        writer->design_.clear();
        writer->results_.clear();
        file = std::move(writer->file_);
      }
      file.Close("close " + temporary.string());
    }
    if (crashed) crashed->Close();
    // Reopened straight into SWMR mode, then renamed into place while open: under the requested name
    // the file is only ever absent, or consistent on disk (a kill at any moment leaves it readable).
    writer->file_ = Handle(H5Fopen(temporary.c_str(), H5F_ACC_RDWR | H5F_ACC_SWMR_WRITE, fapl.get()),
                           "open " + temporary.string() + " for writing");
    writer->OpenDatasets();
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
      writer->index_.Reset();
      writer->id_.Reset();
      writer->status_.Reset();
      writer->message_.Reset();
      writer->design_.clear();
      writer->results_.clear();
      writer->file_.Reset();
      std::filesystem::remove(temporary);
      throw ArchiveError("rename " + temporary.string() + " to " + shown + ": " + ec.message());
    }
  }

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
  return writer;
}

}  // namespace gesweep
