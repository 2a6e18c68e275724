#include "engine/archive/archive_reader.h"

#include <algorithm>
#include <cstring>
#include <sstream>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_writer.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

std::string Hex(std::uint64_t value) {
  std::ostringstream out;
  out << std::hex;
  out.width(16);
  out.fill('0');
  out << value;
  return out.str();
}

herr_t CollectDataset(hid_t, const char* name, const H5O_info_t* info, void* data) {
  if (info->type == H5O_TYPE_DATASET) static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

}  // namespace

ArchiveReader::ArchiveReader(std::filesystem::path path, Handle file, bool snapshot)
    : path_(std::move(path)), file_(std::move(file)), snapshot_(snapshot) {}

ArchiveReader ArchiveReader::Open(const std::filesystem::path& path) {
  hdf5::Quiet();
  const std::string shown = path.string();
  std::error_code ec;
  const bool exists = std::filesystem::exists(path, ec);
  if (ec) throw InputError(shown, "", "", "cannot read the archive: " + ec.message());
  if (!exists) throw InputError(shown, "", "", "no such archive");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(shown, "", "", "is a directory, not an archive");
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw InputError(shown, "", "", "not an HDF5 file (expected a gesweep archive)");
  Handle fapl = hdf5::FileAccess();
  bool snapshot = false;
  hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get());
  std::string first_error;
  if (id < 0) {
    first_error = hdf5::LastError();
    H5Eclear2(H5E_DEFAULT);
    // Being written by a sweep (SWMR mode), or left open by a writer that died: a snapshot.
    id = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl.get());
    snapshot = id >= 0;
    H5Eclear2(H5E_DEFAULT);
  }
  if (id < 0) {
    throw InputError(shown, "", "",
                     "archive in use or unreadable: cannot open it now (HDF5: " + first_error +
                         "); if no gesweep is writing it, it may be damaged");
  }
  ArchiveReader reader(path, Handle(id), snapshot);
  const auto format = hdf5::ReadStringAttribute(id, "format");
  if (!format || *format != archive::kFormatName) {
    throw InputError(shown, "format", format.value_or(""),
                     "not a gesweep archive (no format = \"gesweep-archive\")");
  }
  const auto version = hdf5::ReadIntegerAttribute(id, "format_version");
  if (!version || *version > archive::kFormatVersion) {
    throw InputError(shown, "format_version", version ? std::to_string(*version) : "",
                     "expected format version <= " + std::to_string(archive::kFormatVersion) +
                         " (this engine is older than the archive)");
  }
  reader.run_count_ = reader.IntegerAttribute("run_count");
  if (reader.StringAttribute("merge_kind") == "virtual") reader.CheckVirtualSources();
  return reader;
}

void ArchiveReader::CheckVirtualSources() const {
  // A virtual archive reads its shards in place, and HDF5 silently gives fill values for a shard
  // it cannot find: refuse instead, naming it.
  const std::string shown = path_.string();
  const std::filesystem::path directory = path_.parent_path();
  const std::string fingerprint = StringAttribute("study_fingerprint");
  for (const std::string& source : StringListAttribute("virtual_sources")) {
    const std::filesystem::path shard = std::filesystem::path(source).is_absolute() ? std::filesystem::path(source)
                                                                                    : directory / source;
    std::error_code ec;
    auto refuse = [&](const std::string& why) {
      throw InputError(shown, "virtual_sources", source,
                       why + ": a virtual archive (gesweep merge) reads its shard files in place, so they must "
                             "stay where they were merged (relative to this file); put it back, or merge again "
                             "(gesweep merge --copy makes a self-contained archive)");
    };
    if (!std::filesystem::is_regular_file(shard, ec)) refuse("shard file " + shard.string() + " is missing");
    Handle fapl = hdf5::FileAccess();
    const hid_t id = H5Fopen(shard.c_str(), H5F_ACC_RDONLY, fapl.get());
    H5Eclear2(H5E_DEFAULT);
    if (id < 0) refuse("shard file " + shard.string() + " cannot be opened (in use by a writer, or damaged)");
    Handle file(id);
    if (hdf5::ReadStringAttribute(id, "study_fingerprint").value_or("") != fingerprint ||
        hdf5::ReadIntegerAttribute(id, "complete").value_or(0) != 1) {
      refuse("shard file " + shard.string() + " has changed since the merge (another study, or not complete)");
    }
  }
}

void ArchiveReader::Close() { file_.Reset(); }

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

}  // namespace

std::optional<std::string> ArchiveReader::StringAttributeOf(const std::string& object, const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o) return std::nullopt;
  return hdf5::ReadStringAttribute(o.get(), name);
}

std::optional<std::int64_t> ArchiveReader::IntegerAttributeOf(const std::string& object,
                                                              const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o) return std::nullopt;
  return hdf5::ReadIntegerAttribute(o.get(), name);
}

std::optional<double> ArchiveReader::DoubleAttributeOf(const std::string& object, const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o) return std::nullopt;
  return hdf5::ReadDoubleAttribute(o.get(), name);
}

std::vector<std::string> ArchiveReader::StringListAttributeOf(const std::string& object,
                                                              const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o) return {};
  return hdf5::ReadStringListAttribute(o.get(), name);
}

std::vector<double> ArchiveReader::DoubleListAttributeOf(const std::string& object, const std::string& name) const {
  Handle o = OpenObject(file_.get(), object);
  if (!o || H5Aexists(o.get(), name.c_str()) <= 0) return {};
  Handle attribute(H5Aopen(o.get(), name.c_str(), H5P_DEFAULT), "open attribute " + name);
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
    case H5T_FLOAT: info.kind = DatasetInfo::Kind::kFloat; break;
    case H5T_INTEGER: info.kind = DatasetInfo::Kind::kInteger; break;
    case H5T_COMPOUND: info.kind = DatasetInfo::Kind::kCompound; break;
    case H5T_STRING: info.kind = DatasetInfo::Kind::kString; break;
    default: info.kind = DatasetInfo::Kind::kOther; break;
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
    throw InputError("command line", "-o", shown,
                     "cannot resume: the archive has " + what + " " + theirs + " but this run has " + ours +
                         "; use --force to replace it, or another -o");
  };
  if (StringAttribute("study_fingerprint") != Hex(plan.study().fingerprint)) {
    refuse("study fingerprint",
           StringAttribute("study_fingerprint") + " (study " + StringAttribute("study_path") + ")",
           Hex(plan.study().fingerprint) + " (study " + plan.study().path +
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
      throw InputError(
          "command line", "-o", shown,
          "cannot resume: run " + std::to_string(plan.first_run() + local) +
              " of the archive has other parameters than this study gives it; use --force to replace it");
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
