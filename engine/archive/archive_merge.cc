#include "engine/archive/archive_merge.h"

#include <algorithm>
#include <map>
#include <optional>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

struct Shard {
  std::filesystem::path path;
  std::optional<ArchiveReader> reader;
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

}  // namespace

MergeReport MergeArchives(const std::vector<std::filesystem::path>& inputs,
                          const std::filesystem::path& output, bool force, const std::string& command_line) {
  hdf5::Quiet();
  const std::string shown = output.string();
  if (inputs.empty()) throw InputError("command line", "ARCHIVES", "", "expected one or more shard archives");
  std::filesystem::path directory = output.parent_path();
  if (directory.empty()) directory = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec)) {
    throw InputError("command line", "-o", shown, "the directory " + directory.string() + " does not exist");
  }
  // The one output check of every command (engine/common/output_guard.h): not an input (the same
  // file, a hard link or a symlink to it), and a regular file when it exists.
  std::vector<NamedInput> named;
  for (const auto& input : inputs) named.push_back({input, "shard archive"});
  CheckOutputPath(output, OutputKind::kFile, named, "-o", {output.string() + ".partial"});
  if (std::filesystem::exists(output, ec) && !force) {
    throw InputError("command line", "-o", shown, "already exists; pass --force to replace it");
  }

  // Open every shard and check it belongs.
  std::vector<Shard> shards;
  for (const auto& input : inputs) {
    Shard shard;
    shard.path = input;
    shard.reader.emplace(ArchiveReader::Open(input));
    ArchiveReader& reader = *shard.reader;
    if (reader.snapshot()) {
      throw InputError(input.string(), "", "",
                       "shard " + reader.StringAttribute("shard") +
                           " is incomplete: its sweep is still writing it or was killed; finish it with "
                           "`gesweep run ... --shard " +
                           reader.StringAttribute("shard") + " --resume` first");
    }
    shard.first = reader.IntegerAttribute("first_run");
    shard.count = reader.run_count();
    shard.shard = reader.StringAttribute("shard");
    shards.push_back(std::move(shard));
  }
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

  // Coverage: exactly once.
  std::sort(shards.begin(), shards.end(), [](const Shard& a, const Shard& b) { return a.first < b.first; });
  const std::int64_t shard_count = reference.IntegerAttribute("shard_count");
  auto missing = [&](std::int64_t from, std::int64_t to) {
    // Name the shards of an N-way split that would cover the gap.
    std::string names;
    for (std::int64_t i = 0; i < shard_count; ++i) {
      const std::int64_t a = i * (design_runs / shard_count) + i * (design_runs % shard_count) / shard_count;
      const std::int64_t b =
          (i + 1) * (design_runs / shard_count) + (i + 1) * (design_runs % shard_count) / shard_count;
      if (a < to && b > from)
        names += (names.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(shard_count);
    }
    throw InputError("command line", "ARCHIVES", "",
                     "runs " + Range(from, to - from) + " of the design are missing (shard " +
                         (names.empty() ? "?" : names) + " not given)");
  };
  std::int64_t covered = 0;
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
  if (covered < design_runs) missing(covered, design_runs);

  // Complete: no pending run in any shard.
  MergeReport report;
  report.shards = static_cast<int>(shards.size());
  report.runs = design_runs;
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
      throw InputError(
          shard.path.string(), "shard", shard.shard,
          "is incomplete: " + std::to_string(pending) + " of its " + std::to_string(shard.count) +
              " runs are pending; finish it with `gesweep run ... --shard " + shard.shard + " --resume`");
    }
  }

  // Write the merged archive under a temporary name.
  const std::filesystem::path temporary = output.string() + ".partial";
  std::filesystem::remove(temporary, ec);
  Handle fapl = hdf5::FileAccess();
  // Nothing half-written survives a failure: the temporary file goes.
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
    hdf5::CopyAttributes(reference.file(), file.get());
    std::vector<std::string> merged_from, shard_notes;
    std::string start = reference.StringAttribute("start_time"), end = reference.StringAttribute("end_time");
    for (const auto& shard : shards) {
      merged_from.push_back(shard.path.string());
      shard_notes.push_back(
          shard.shard + ": " + shard.path.string() + ", host " + shard.reader->StringAttribute("host") +
          ", threads " + std::to_string(shard.reader->IntegerAttribute("threads")) + ", " +
          shard.reader->StringAttribute("start_time") + " to " + shard.reader->StringAttribute("end_time"));
      start = std::min(start, shard.reader->StringAttribute("start_time"));
      end = std::max(end, shard.reader->StringAttribute("end_time"));
    }
    hdf5::WriteAttribute(file.get(), "merged_from", merged_from);
    hdf5::WriteAttribute(file.get(), "merged_shards", shard_notes);
    hdf5::WriteAttribute(file.get(), "merge_time", UtcTimestamp());
    hdf5::WriteAttribute(file.get(), "merge_command_line", command_line);
    hdf5::WriteAttribute(file.get(), "start_time", start);
    hdf5::WriteAttribute(file.get(), "end_time", end);
    hdf5::WriteAttribute(file.get(), "shard", "0/1");
    hdf5::WriteAttribute(file.get(), "shard_index", std::int64_t{0});
    hdf5::WriteAttribute(file.get(), "shard_count", std::int64_t{1});
    hdf5::WriteAttribute(file.get(), "first_run", std::int64_t{0});
    hdf5::WriteAttribute(file.get(), "run_count", design_runs);
    hdf5::WriteAttribute(file.get(), "complete", std::int64_t{1});
    hdf5::WriteAttribute(file.get(), "runs_ok", report.runs_ok);
    hdf5::WriteAttribute(file.get(), "runs_failed", report.runs_failed);
    hdf5::WriteAttribute(file.get(), "runs_pending", std::int64_t{0});
    for (const char* group : {archive::kRunsGroup, archive::kDesignGroup, archive::kResultsGroup,
                              archive::kSeriesGroup, archive::kAnalysisGroup}) {
      CopyGroupAttributes(reference.file(), file.get(), group);
    }

    std::vector<unsigned char> buffer, piece;
    for (const std::string& path : reference.Datasets()) {
      if (StartsWith(path, std::string(archive::kAnalysisGroup) + "/"))
        continue;  // derived: recompute after merge
      Handle source(H5Dopen2(reference.file(), path.c_str(), H5P_DEFAULT), "open " + path);
      const auto dims = hdf5::Dimensions(source.get());
      hdf5::CreateGroups(file.get(), path.substr(0, path.rfind('/')));
      if (!PerRun(path, dims)) {
        Check(H5Ocopy(reference.file(), path.c_str(), file.get(), path.c_str(), H5P_DEFAULT, H5P_DEFAULT),
              "copy " + path);
        continue;
      }
      Handle type(H5Dget_type(source.get()), "type of " + path);
      Handle dcpl(H5Dget_create_plist(source.get()), "creation properties of " + path);
      hsize_t chunk[2] = {1, 1};
      const int rank = H5Pget_chunk(dcpl.get(), 2, chunk);
      Check(rank, "chunk of " + path);
      std::vector<hsize_t> out_dims{static_cast<hsize_t>(design_runs)};
      if (dims.size() == 2) out_dims.push_back(static_cast<hsize_t>(dims[1]));
      Handle space(H5Screate_simple(static_cast<int>(out_dims.size()), out_dims.data(), nullptr),
                   "dataspace");
      Handle target(
          H5Dcreate2(file.get(), path.c_str(), type.get(), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
          "create " + path);
      hdf5::CopyAttributes(source.get(), target.get());
      const std::int64_t width = dims.size() == 2 ? dims[1] : 1;
      const std::size_t row_bytes = static_cast<std::size_t>(width) * H5Tget_size(type.get());
      const auto chunk_rows = static_cast<std::int64_t>(chunk[0]);
      // One write per output chunk, gathered from the shards that cover it.
      for (std::int64_t first = 0; first < design_runs; first += chunk_rows) {
        const std::int64_t count = std::min(chunk_rows, design_runs - first);
        buffer.resize(static_cast<std::size_t>(count) * row_bytes);
        for (const auto& shard : shards) {
          const std::int64_t a = std::max(first, shard.first);
          const std::int64_t b = std::min(first + count, shard.first + shard.count);
          if (a >= b) continue;
          piece.resize(static_cast<std::size_t>(b - a) * row_bytes);
          shard.reader->ReadRows(path, a - shard.first, b - a, type.get(), piece.data());
          std::copy(piece.begin(), piece.end(),
                    buffer.begin() + static_cast<std::ptrdiff_t>((a - first) * row_bytes));
        }
        Handle memory;
        Handle file_space = hdf5::SelectRows(target.get(), first, count, &memory);
        Check(H5Dwrite(target.get(), type.get(), memory.get(), file_space.get(), H5P_DEFAULT, buffer.data()),
              "write " + path);
      }
    }
    file.Close("close " + temporary.string());
  }
  for (auto& shard : shards) shard.reader->Close();
  std::filesystem::rename(temporary, output, ec);
  if (ec) throw ArchiveError("rename " + temporary.string() + " to " + shown + ": " + ec.message());
  cleanup.armed = false;
  return report;
}

}  // namespace gesweep
