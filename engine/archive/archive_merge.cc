#include "engine/archive/archive_merge.h"

#include <algorithm>
#include <map>
#include <memory>
#include <optional>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_identity.h"
#include "engine/archive/archive_lock.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/dimension_scales.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"
#include "engine/common/request_error.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

struct Shard {
  std::filesystem::path path;
  std::shared_ptr<ArchiveReader> reader;
  std::int64_t first = 0, count = 0;
  std::string shard;  // "i/N"
};

bool StartsWith(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

// Whether a dataset has one row per run (and so is merged), or is shared (a time axis).
bool PerRun(const std::string& path, const std::vector<std::int64_t>& dims) {
  if (StartsWith(path, "runs/") || StartsWith(path, "design/") || StartsWith(path, "results/")) return true;
  return StartsWith(path, "series/") && dims.size() == 2;
}

std::string Range(std::int64_t first, std::int64_t count) {
  return std::to_string(first) + ".." + std::to_string(first + count - 1);
}

void CopyGroupAttributes(hid_t from_file, hid_t to_file, const std::string& group) {
  if (!hdf5::Exists(from_file, group)) return;
  hdf5::CreateGroups(to_file, group);
  Handle from(H5Gopen2(from_file, group.c_str(), H5P_DEFAULT), "open group " + group);
  Handle to(H5Gopen2(to_file, group.c_str(), H5P_DEFAULT), "open group " + group);
  hdf5::CopyAttributes(from.get(), to.get());
}

// A copied time axis keeps no dimension scale attribute of its shard (they refer to the shard's objects).
void DropDimensionScaleAttributes(hid_t file, const std::string& path) {
  Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), "open " + path);
  for (const char* name : {"CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST"}) {
    if (H5Aexists(d.get(), name) > 0) Check(H5Adelete(d.get(), name), "drop attribute " + std::string(name));
  }
}

// The chunk rows of a chunked dataset (1 when it is not chunked).
std::int64_t ChunkRows(hid_t dataset) {
  Handle dcpl(H5Dget_create_plist(dataset), "creation properties");
  if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED) return 1;
  hsize_t chunk[2] = {1, 1};
  Check(H5Pget_chunk(dcpl.get(), 2, chunk), "chunk dimensions");
  return static_cast<std::int64_t>(chunk[0]);
}

// Where a shard is, as the merged file records it: relative to the merged file's directory (HDF5
// resolves a relative source of a virtual dataset from the directory of the file that holds it),
// absolute when there is no relative path.
std::string SourceName(const std::filesystem::path& shard, const std::filesystem::path& output) {
  std::error_code ec;
  const auto shard_path = std::filesystem::weakly_canonical(std::filesystem::absolute(shard), ec);
  const auto directory =
      std::filesystem::weakly_canonical(std::filesystem::absolute(output), ec).parent_path();
  const auto relative = shard_path.lexically_relative(directory);
  if (relative.empty()) return shard_path.string();
  return relative.string();
}

// A virtual dataset mapping rows [first, first + count) of the merged dataset to every row of
// each shard's dataset `path`.
void WriteVirtual(hid_t file, const std::string& path, const std::vector<Shard>& shards,
                  const std::vector<std::string>& sources, std::int64_t design_runs) {
  Handle source(H5Dopen2(shards.front().reader->file(), path.c_str(), H5P_DEFAULT), "open " + path);
  Handle type(H5Dget_type(source.get()), "type of " + path);
  const auto dims = hdf5::Dimensions(source.get());
  std::vector<hsize_t> out_dims{static_cast<hsize_t>(design_runs)};
  if (dims.size() == 2) out_dims.push_back(static_cast<hsize_t>(dims[1]));
  const int rank = static_cast<int>(out_dims.size());
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), "creation properties of " + path);
  {
    Handle source_dcpl(H5Dget_create_plist(source.get()), "creation properties of " + path);
    H5D_fill_value_t defined = H5D_FILL_VALUE_UNDEFINED;
    Check(H5Pfill_value_defined(source_dcpl.get(), &defined), "fill value of " + path);
    if (defined == H5D_FILL_VALUE_USER_DEFINED) {
      std::vector<unsigned char> fill(H5Tget_size(type.get()));
      Check(H5Pget_fill_value(source_dcpl.get(), type.get(), fill.data()), "fill value of " + path);
      Check(H5Pset_fill_value(dcpl.get(), type.get(), fill.data()), "fill value of " + path);
    }
  }
  for (std::size_t i = 0; i < shards.size(); ++i) {
    const Shard& shard = shards[i];
    Handle virtual_space(H5Screate_simple(rank, out_dims.data(), nullptr), "virtual space");
    hsize_t start[2] = {static_cast<hsize_t>(shard.first), 0};
    hsize_t count[2] = {static_cast<hsize_t>(shard.count), rank == 2 ? out_dims[1] : 1};
    Check(H5Sselect_hyperslab(virtual_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr),
          "select rows of " + path);
    std::vector<hsize_t> shard_dims{static_cast<hsize_t>(shard.count)};
    if (rank == 2) shard_dims.push_back(out_dims[1]);
    Handle source_space(H5Screate_simple(rank, shard_dims.data(), nullptr), "source space");
    Check(H5Pset_virtual(dcpl.get(), virtual_space.get(), archive::VirtualFilePattern(sources[i]).c_str(),
                         path.c_str(), source_space.get()),
          "map " + path + " of " + shard.path.string());
  }
  Handle space(H5Screate_simple(rank, out_dims.data(), nullptr), "dataspace");
  Handle target(H5Dcreate2(file, path.c_str(), type.get(), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                "create " + path);
  hdf5::CopyAttributes(source.get(), target.get());
}

// The merged dataset `path` by raw chunk copy where the shards' chunks coincide with the merged
// file's, through HDF5 (decoded, written, filtered again) elsewhere.
void WriteCopy(hid_t file, const std::string& path, const std::vector<Shard>& shards,
               std::int64_t design_runs, MergeReport& report) {
  std::vector<Handle> sources;
  std::vector<std::int64_t> chunk_rows;
  std::size_t widest = 0;
  for (std::size_t i = 0; i < shards.size(); ++i) {
    sources.emplace_back(H5Dopen2(shards[i].reader->file(), path.c_str(), H5P_DEFAULT),
                         "open " + path + " of " + shards[i].path.string());
    chunk_rows.push_back(ChunkRows(sources.back().get()));
    if (chunk_rows[i] > chunk_rows[widest]) widest = i;
  }
  const hid_t reference = sources[widest].get();
  Handle type(H5Dget_type(reference), "type of " + path);
  Handle dcpl(H5Dget_create_plist(reference), "creation properties of " + path);
  const auto dims = hdf5::Dimensions(reference);
  std::vector<hsize_t> out_dims{static_cast<hsize_t>(design_runs)};
  if (dims.size() == 2) out_dims.push_back(static_cast<hsize_t>(dims[1]));
  // One chunk in all: an unlimited row dimension, as the writer does (HDF5 1.10's single-chunk index
  // mishandles direct chunk writes).
  std::vector<hsize_t> max_dims = out_dims;
  if (out_dims[0] <= static_cast<hsize_t>(chunk_rows[widest])) max_dims[0] = H5S_UNLIMITED;
  Handle space(H5Screate_simple(static_cast<int>(out_dims.size()), out_dims.data(), max_dims.data()),
               "dataspace");
  Handle target(H5Dcreate2(file, path.c_str(), type.get(), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                "create " + path);
  hdf5::CopyAttributes(reference, target.get());
  const std::int64_t rows = chunk_rows[widest];
  const std::size_t row_bytes =
      static_cast<std::size_t>(dims.size() == 2 ? dims[1] : 1) * H5Tget_size(type.get());
  std::vector<unsigned char> buffer, piece;
  std::size_t s = 0;  // the shard holding the chunk's first row (shards are sorted and contiguous)
  for (std::int64_t first = 0; first < design_runs; first += rows) {
    const std::int64_t end = std::min(first + rows, design_runs);
    while (shards[s].first + shards[s].count <= first) ++s;
    const Shard& shard = shards[s];
    const std::int64_t local = first - shard.first;
    // Raw copy: the shard's chunk starts here, has the merged chunk's size, and the shard holds
    // every row of the merged chunk (a shard's partial last chunk is copied only at the design's end,
    // where the merged chunk is partial in the same way).
    if (chunk_rows[s] == rows && local % rows == 0 && shard.first + shard.count >= end) {
      const hsize_t source_offset[2] = {static_cast<hsize_t>(local), 0};
      const hsize_t target_offset[2] = {static_cast<hsize_t>(first), 0};
      unsigned mask = 0;
      haddr_t address = HADDR_UNDEF;
      hsize_t size = 0;
      Check(H5Dget_chunk_info_by_coord(sources[s].get(), source_offset, &mask, &address, &size),
            "chunk of " + path + " in " + shard.path.string());
      if (address == HADDR_UNDEF || size == 0) continue;  // never written (a message chunk without a message)
      buffer.resize(static_cast<std::size_t>(size));
      std::uint32_t filters = 0;
      Check(H5Dread_chunk(sources[s].get(), H5P_DEFAULT, source_offset, &filters, buffer.data()),
            "read a chunk of " + path + " of " + shard.path.string());
      Check(H5Dwrite_chunk(target.get(), H5P_DEFAULT, filters, target_offset, buffer.size(), buffer.data()),
            "write a chunk of " + path);
      ++report.chunks_copied;
      report.bytes_copied += static_cast<std::int64_t>(size);
      continue;
    }
    // Gathered from the shards that cover it, then written through HDF5's own filters.
    buffer.resize(static_cast<std::size_t>(end - first) * row_bytes);
    for (std::size_t i = s; i < shards.size() && shards[i].first < end; ++i) {
      const std::int64_t a = std::max(first, shards[i].first);
      const std::int64_t b = std::min(end, shards[i].first + shards[i].count);
      if (a >= b) continue;
      piece.resize(static_cast<std::size_t>(b - a) * row_bytes);
      shards[i].reader->ReadRows(path, a - shards[i].first, b - a, type.get(), piece.data());
      std::copy(piece.begin(), piece.end(),
                buffer.begin() + static_cast<std::ptrdiff_t>((a - first) * row_bytes));
    }
    Handle memory;
    Handle file_space = hdf5::SelectRows(target.get(), first, end - first, &memory);
    Check(H5Dwrite(target.get(), type.get(), memory.get(), file_space.get(), H5P_DEFAULT, buffer.data()),
          "write " + path);
    ++report.chunks_rewritten;
  }
}

// The output's checks, before any shard is read: its directory exists, it is none of the inputs
// (engine/common/output_guard.h), and it does not exist unless `force`.
void CheckMergeOutput(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                      bool force) {
  const std::string shown = output.string();
  if (inputs.empty()) throw InputError("command line", "ARCHIVES", "", "expected one or more shard archives");
  RequireOutputDirectory(output, "output");
  // The one output check of every command (engine/common/output_guard.h): not an input (the same
  // file, a hard link or a symlink to it), and a regular file when it exists.
  std::vector<NamedInput> named;
  named.reserve(inputs.size());
  for (const auto& input : inputs) named.push_back({input, "shard archive"});
  CheckOutputPath(output, OutputKind::kFile, named, "output",
                  {output.string() + ".partial", output.string() + ".lock"});
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && !force) {
    throw RequestError("command line", "output", shown, "already exists", "force");
  }
}

// The output check again, once the inputs are open, over every file they read: the shards behind
// a virtual input too (a merge onto one of them would replace what its own input reads).
void CheckMergeOutputAgainstSources(const std::vector<Shard>& shards, const std::filesystem::path& output) {
  std::vector<NamedInput> named;
  for (const Shard& shard : shards) {
    for (const auto& file : shard.reader->files_read())
      named.push_back({file, "shard file", shard.path.string()});
  }
  if (named.empty()) return;
  CheckOutputPath(output, OutputKind::kFile, named, "output",
                  {output.string() + ".partial", output.string() + ".lock"});
}

// The plain archives the merged file maps or copies: each input, or for a virtual one the files it
// maps (checked when it was opened), so that a merged archive never reads through another.
std::vector<Shard> Leaves(const std::vector<Shard>& shards) {
  std::vector<Shard> leaves;
  for (const Shard& shard : shards) {
    if (!shard.reader->is_virtual()) {
      leaves.push_back(shard);
      continue;
    }
    std::vector<Shard> sources;
    for (const archive::FoundSource& source : shard.reader->sources()) {
      Shard leaf;
      leaf.path = source.path;
      leaf.reader = std::make_shared<ArchiveReader>(ArchiveReader::Open(source.path));
      leaf.first = source.identity.first_run;
      leaf.count = source.identity.run_count;
      leaf.shard = source.identity.shard;
      sources.push_back(std::move(leaf));
    }
    for (Shard& leaf : Leaves(sources)) leaves.push_back(std::move(leaf));
  }
  std::sort(leaves.begin(), leaves.end(), [](const Shard& a, const Shard& b) { return a.first < b.first; });
  return leaves;
}

// Opens every shard, refusing one whose sweep is still writing it or was killed.
std::vector<Shard> OpenShards(const std::vector<std::filesystem::path>& inputs) {
  std::vector<Shard> shards;
  for (const auto& input : inputs) {
    Shard shard;
    shard.path = input;
    shard.reader = std::make_shared<ArchiveReader>(ArchiveReader::Open(input));
    ArchiveReader& reader = *shard.reader;
    if (reader.snapshot()) {
      throw RequestError(input.string(), "", "",
                         "shard " + reader.StringAttribute("shard") +
                             " is incomplete: its sweep is still writing it or was killed",
                         "resume_shard_first", reader.StringAttribute("shard"));
    }
    shard.first = reader.IntegerAttribute("first_run");
    shard.count = reader.run_count();
    shard.shard = reader.StringAttribute("shard");
    shards.push_back(std::move(shard));
  }
  return shards;
}

// Refuses shards that do not come from the same study and engine as the first, or whose designs differ
// in size.
void CheckSameStudy(const std::vector<Shard>& shards) {
  const ArchiveReader& reference = *shards.front().reader;
  for (const char* key : {"study_fingerprint", "engine_version", "git_commit"}) {
    for (const auto& shard : shards) {
      if (shard.reader->StringAttribute(key) != reference.StringAttribute(key)) {
        throw InputError(shard.path.string(), key, shard.reader->StringAttribute(key),
                         "expected " + reference.StringAttribute(key) + " as in " +
                             shards.front().path.string() +
                             ": shards must come from the same study and engine");
      }
    }
  }
  const std::int64_t design_runs = reference.IntegerAttribute("design_runs");
  for (const auto& shard : shards) {
    if (shard.reader->IntegerAttribute("design_runs") != design_runs) {
      throw InputError(shard.path.string(), "design_runs",
                       std::to_string(shard.reader->IntegerAttribute("design_runs")),
                       "expected " + std::to_string(design_runs) + " as in " + shards.front().path.string());
    }
  }
}

// Refuses shards that do not cover runs [origin, origin + total) exactly once (sorted by first run).
void CheckCoverage(const std::vector<Shard>& shards, std::int64_t origin, std::int64_t total) {
  const ArchiveReader& reference = *shards.front().reader;
  const std::int64_t design_runs = reference.IntegerAttribute("design_runs");
  const std::int64_t shard_count = reference.IntegerAttribute("shard_count");
  std::int64_t batch_runs = 1;
  for (const auto& shard : shards)
    batch_runs = std::max(batch_runs, shard.reader->IntegerAttribute("chunk_runs"));
  const bool node_files = hdf5::ReadIntegerAttribute(reference.file(), "node_count").has_value();
  auto missing = [&](std::int64_t from, std::int64_t to) {
    // Name the shards of an N-way split that would cover the gap (the split of ShardRange, whose
    // batch size every full shard records as chunk_runs).
    std::string names;
    for (std::int64_t i = 0; i < shard_count && !node_files; ++i) {
      std::int64_t a = 0, n = 0;
      ShardRange(design_runs, static_cast<int>(batch_runs),
                 ShardSpec{static_cast<int>(i), static_cast<int>(shard_count)}, &a, &n);
      if (a < to && a + n > from)
        names += (names.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(shard_count);
    }
    throw InputError("command line", "ARCHIVES", "",
                     "runs " + Range(from, to - from) + " of the design are missing (" +
                         (node_files ? std::string("a node's shard file of the MPI run not given")
                                     : "shard " + (names.empty() ? std::string("?") : names) + " not given") +
                         ")");
  };
  std::int64_t covered = origin;
  for (std::size_t i = 0; i < shards.size(); ++i) {
    if (shards[i].first > covered) missing(covered, shards[i].first);
    if (shards[i].first < covered) {
      throw InputError(
          shards[i].path.string(), "shard", shards[i].shard,
          "overlaps " + shards[i - 1].path.string() + " (runs " +
              Range(shards[i].first, std::min(covered, shards[i].first + shards[i].count) - shards[i].first) +
              " in both): each run must come from exactly one shard");
    }
    covered = shards[i].first + shards[i].count;
  }
  if (covered < origin + total) missing(covered, origin + total);
  if (covered > origin + total) {
    throw InputError(
        shards.back().path.string(), "shard", shards.back().shard,
        "reaches past run " + std::to_string(origin + total - 1) + ", the end of what is merged");
  }
}

// Counts the ok and failed runs of every shard into `report`; refuses a shard with a pending run.
void CountCompleteRuns(const std::vector<Shard>& shards, MergeReport& report) {
  constexpr std::int64_t kStatusStep = 1 << 16;
  for (const auto& shard : shards) {
    std::int64_t pending = 0;
    for (std::int64_t first = 0; first < shard.count; first += kStatusStep) {
      for (std::int8_t s : shard.reader->ReadStatus(first, std::min(kStatusStep, shard.count - first))) {
        pending += s == 0;
        report.runs_ok += s == 1;
        report.runs_failed += s == 2;
      }
    }
    if (pending > 0) {
      throw RequestError(shard.path.string(), "shard", shard.shard,
                         "is incomplete: " + std::to_string(pending) + " of its " +
                             std::to_string(shard.count) + " runs are pending",
                         "resume_shard", shard.shard);
    }
  }
}

// The merged file's attributes: the first input's, less those of a node, of another merge and of its
// identity, with a new identity, the merge's provenance, the runs merged and how (virtual: the files
// mapped, `leaves`, relative to `output`, into report.sources, each with its identity).
void WriteMergedAttributes(hid_t file, const std::vector<Shard>& shards, const std::vector<Shard>& leaves,
                           const std::filesystem::path& output, const std::string& command_line,
                           MergeKind kind, const MergeScope& scope, std::int64_t origin, std::int64_t total,
                           MergeReport& report) {
  const ArchiveReader& reference = *shards.front().reader;
  hdf5::CopyAttributes(reference.file(), file);
  for (const char* stale : {"node_index", "node_count", "virtual_sources", "virtual_note",
                            "virtual_source_ids", "virtual_source_fingerprints", "virtual_source_first_runs",
                            "virtual_source_run_counts", "virtual_source_shards", "merged_from_ids"}) {
    if (H5Aexists(file, stale) > 0) Check(H5Adelete(file, stale), "drop the attribute " + std::string(stale));
  }
  hdf5::WriteAttribute(file, "archive_id", archive::NewArchiveId());
  std::vector<std::string> merged_from, merged_ids, shard_notes;
  std::string start = reference.StringAttribute("start_time"), end = reference.StringAttribute("end_time");
  for (const auto& shard : shards) {
    merged_from.push_back(shard.path.string());
    merged_ids.push_back(shard.reader->StringAttribute("archive_id"));
    shard_notes.push_back(
        shard.shard + ": " + shard.path.string() + ", host " + shard.reader->StringAttribute("host") +
        ", threads " + std::to_string(shard.reader->IntegerAttribute("threads")) + ", " +
        shard.reader->StringAttribute("start_time") + " to " + shard.reader->StringAttribute("end_time"));
    start = std::min(start, shard.reader->StringAttribute("start_time"));
    end = std::max(end, shard.reader->StringAttribute("end_time"));
  }
  hdf5::WriteAttribute(file, "merged_from", merged_from);
  hdf5::WriteAttribute(file, "merged_from_ids", merged_ids);
  hdf5::WriteAttribute(file, "merged_shards", shard_notes);
  hdf5::WriteAttribute(file, "merge_time", UtcTimestamp());
  hdf5::WriteAttribute(file, "merge_command_line", command_line);
  hdf5::WriteAttribute(file, "start_time", start);
  hdf5::WriteAttribute(file, "end_time", end);
  hdf5::WriteAttribute(file, "shard",
                       std::to_string(scope.shard_index) + "/" + std::to_string(scope.shard_count));
  hdf5::WriteAttribute(file, "shard_index", static_cast<std::int64_t>(scope.shard_index));
  hdf5::WriteAttribute(file, "shard_count", static_cast<std::int64_t>(scope.shard_count));
  hdf5::WriteAttribute(file, "first_run", origin);
  hdf5::WriteAttribute(file, "run_count", total);
  hdf5::WriteAttribute(file, "complete", std::int64_t{1});
  hdf5::WriteAttribute(file, "runs_ok", report.runs_ok);
  hdf5::WriteAttribute(file, "runs_failed", report.runs_failed);
  hdf5::WriteAttribute(file, "runs_pending", std::int64_t{0});
  for (const char* group : {archive::kRunsGroup, archive::kDesignGroup, archive::kResultsGroup,
                            archive::kSeriesGroup, archive::kAnalysisGroup}) {
    CopyGroupAttributes(reference.file(), file, group);
  }
  if (kind == MergeKind::kVirtual) {
    std::vector<archive::RecordedSource> recorded;
    for (const auto& leaf : leaves) {
      report.sources.push_back(SourceName(leaf.path, output));
      recorded.push_back({report.sources.back(), archive::ReadIdentity(leaf.reader->file())});
    }
    hdf5::WriteAttribute(file, "merge_kind", "virtual");
    archive::WriteRecordedSources(file, recorded);
    hdf5::WriteAttribute(
        file, "virtual_note",
        "The per-run datasets of this archive are HDF5 virtual datasets over the shard files listed in "
        "virtual_sources (paths relative to this file's directory): keep them where they are; "
        "a merge that copies (gesweep merge in its copy mode) makes a self-contained archive");
  } else {
    hdf5::WriteAttribute(file, "merge_kind", "copy");
  }
}

// The merged file's datasets (the leaves' `first` are rows of the merged file): the per-run ones
// merged from the leaves (virtual or copied), the shared ones (time axes) copied from the first input,
// /analysis left out (derived: recomputed after a merge); then the dimension scales of the merged rows.
void WriteMergedDatasets(hid_t file, const ArchiveReader& reference, const std::vector<Shard>& leaves,
                         MergeKind kind, std::int64_t total, MergeReport& report) {
  std::vector<std::string> per_run;
  for (const std::string& path : reference.Datasets()) {
    if (StartsWith(path, std::string(archive::kAnalysisGroup) + "/"))
      continue;                                         // derived: recompute after merge
    if (path.find('/') == std::string::npos) continue;  // a root dimension: made again below
    Handle source(H5Dopen2(reference.file(), path.c_str(), H5P_DEFAULT), "open " + path);
    const auto dims = hdf5::Dimensions(source.get());
    hdf5::CreateGroups(file, path.substr(0, path.rfind('/')));
    if (!PerRun(path, dims)) {
      Check(H5Ocopy(reference.file(), path.c_str(), file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT),
            "copy " + path);
      DropDimensionScaleAttributes(file, path);
      continue;
    }
    per_run.push_back(path);
    if (kind == MergeKind::kVirtual) {
      WriteVirtual(file, path, leaves, report.sources, total);
    } else {
      WriteCopy(file, path, leaves, total, report);
    }
  }
  // The netCDF view of the merged rows (the shards' scales refer to the shards' own objects).
  archive::AttachDimensionScales(file, total, per_run);
}

// Writes the merged archive under OUTPUT.partial and renames it into place (nothing half-written
// survives a failure).
void WriteMerged(const std::vector<Shard>& shards, std::vector<Shard>& leaves,
                 const std::filesystem::path& output, const std::string& command_line, MergeKind kind,
                 const MergeScope& scope, std::int64_t origin, std::int64_t total, MergeReport& report) {
  const std::filesystem::path temporary = output.string() + ".partial";
  std::error_code ec;
  std::filesystem::remove(temporary, ec);
  Handle fapl = hdf5::FileAccess();
  struct RemoveOnFailure {
    const std::filesystem::path& path;
    bool armed = true;
    ~RemoveOnFailure() {
      std::error_code ignored;
      if (armed) std::filesystem::remove(path, ignored);
    }
  } cleanup{temporary};
  {
    Handle file(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                "create " + temporary.string());
    WriteMergedAttributes(file.get(), shards, leaves, output, command_line, kind, scope, origin, total,
                          report);
    for (auto& leaf : leaves) leaf.first -= origin;  // rows of the merged archive from here on
    WriteMergedDatasets(file.get(), *shards.front().reader, leaves, kind, total, report);
    file.Close("close " + temporary.string());
  }
  for (auto& leaf : leaves) leaf.reader->Close();
  for (auto& shard : shards) shard.reader->Close();
  std::filesystem::rename(temporary, output, ec);
  if (ec) throw ArchiveError("rename " + temporary.string() + " to " + output.string() + ": " + ec.message());
  cleanup.armed = false;
}

}  // namespace

MergeReport MergeArchives(const std::vector<std::filesystem::path>& inputs,
                          const std::filesystem::path& output, bool force, const std::string& command_line,
                          MergeKind kind, const MergeScope& scope) {
  hdf5::Quiet();
  CheckMergeOutput(inputs, output, force);
  // Each input opened checks its own sources (a virtual input's shards), before anything is read.
  std::vector<Shard> shards = OpenShards(inputs);
  CheckMergeOutputAgainstSources(shards, output);
  // A writer like `gesweep run`: the output's lock, held until the merged file is in place.
  const ArchiveLock lock = ArchiveLock::AcquireOutput(output, "output");
  CheckSameStudy(shards);
  const std::int64_t design_runs = shards.front().reader->IntegerAttribute("design_runs");

  // Coverage: exactly once, by the inputs and by the files they read.
  std::sort(shards.begin(), shards.end(), [](const Shard& a, const Shard& b) { return a.first < b.first; });
  const std::int64_t origin = scope.first_run;
  const std::int64_t total = scope.run_count >= 0 ? scope.run_count : design_runs - origin;
  CheckCoverage(shards, origin, total);
  std::vector<Shard> leaves = Leaves(shards);
  CheckCoverage(leaves, origin, total);

  // Complete: no pending run in any shard.
  MergeReport report;
  report.kind = kind;
  report.shards = static_cast<int>(shards.size());
  report.runs = total;
  CountCompleteRuns(shards, report);
  WriteMerged(shards, leaves, output, command_line, kind, scope, origin, total, report);
  return report;
}

}  // namespace gesweep
