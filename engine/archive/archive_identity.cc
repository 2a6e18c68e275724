#include "engine/archive/archive_identity.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <map>
#include <random>
#include <string_view>
#include <utility>

#include "engine/archive/archive_format.h"
#include "engine/archive/hdf5_util.h"
#include "engine/common/output_guard.h"
#include "engine/common/request_error.h"

namespace gesweep::archive {
namespace {

using hdf5::Handle;

constexpr const char* kSources = "virtual_sources";
constexpr const char* kSourceIds = "virtual_source_ids";
constexpr const char* kSourceFingerprints = "virtual_source_fingerprints";
constexpr const char* kSourceFirstRuns = "virtual_source_first_runs";
constexpr const char* kSourceRunCounts = "virtual_source_run_counts";
constexpr const char* kSourceShards = "virtual_source_shards";

// Virtual archives read through virtual archives deeper than this are refused (a merge maps plain
// files; an archive merged before that maps at most a merge of node files).
constexpr std::size_t kMaximumNesting = 16;

// What follows every refusal: the files must be where the merge recorded them.
constexpr const char* kStay =
    ": a virtual archive (gesweep merge) reads its shard files in place, so they must stay where they "
    "were merged (relative to this file); put it back, or merge again";

std::function<void(const std::string&)>& NoteHandler() {
  static std::function<void(const std::string&)> handler;
  return handler;
}

// The device and inode of a file after following symlinks; nullopt when it cannot be stat'ed.
std::optional<std::pair<dev_t, ino_t>> FileKey(const std::filesystem::path& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return std::nullopt;
  return std::make_pair(info.st_dev, info.st_ino);
}

// A source file name as stored by H5Pset_virtual ("%%" for "%") back as the file's name.
std::string FromPattern(const std::string& pattern) {
  std::string name;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    name.push_back(pattern[i]);
    if (pattern[i] == '%' && i + 1 < pattern.size() && pattern[i + 1] == '%') ++i;
  }
  return name;
}

// prefix + "/" + name, as HDF5 builds a candidate (no separator doubled after a prefix ending in one).
std::string Join(std::string prefix, const std::string& name) {
  if (!prefix.empty() && prefix.back() != '/') prefix += '/';
  return prefix + name;
}

// The directory of `archive` as HDF5 records it for a file opened by that name ("extpath"): its
// directory part, from the current directory when relative, ending in '/'.
std::string ExternalPath(const std::filesystem::path& archive) {
  const std::string name = archive.string();
  const auto slash = name.rfind('/');
  std::string directory = slash == std::string::npos ? "" : name.substr(0, slash + 1);
  if (!name.empty() && name[0] == '/') return directory;
  std::error_code ec;
  return Join(std::filesystem::current_path(ec).string(), directory);
}

// The rows of the merged archive that runs/status maps from each source file, and every file any
// virtual dataset of `file` maps (file names as given to H5Pset_virtual, unescaped).
struct Mappings {
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> status_rows;  // name -> first row, rows
  std::vector<std::string> files;
};

herr_t CollectPerRunDataset(hid_t, const char* name, const H5O_info_t* info, void* data) {
  const std::string path = name;
  const bool per_run = path.rfind("runs/", 0) == 0 || path.rfind("design/", 0) == 0 ||
                       path.rfind("results/", 0) == 0 || path.rfind("series/", 0) == 0;
  if (info->type == H5O_TYPE_DATASET && per_run)
    static_cast<std::vector<std::string>*>(data)->push_back(path);
  return 0;
}

std::vector<std::string> PerRunDatasets(hid_t file) {
  std::vector<std::string> paths;
  if (H5Ovisit2(file, H5_INDEX_NAME, H5_ITER_INC, CollectPerRunDataset, &paths, H5O_INFO_BASIC) < 0) {
    H5Eclear2(H5E_DEFAULT);
  }
  return paths;
}

// The creation property list of a virtual dataset at `path`; an invalid handle when it is not one.
Handle VirtualCreation(hid_t file, const std::string& path) {
  const hid_t dataset = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (dataset < 0) {
    H5Eclear2(H5E_DEFAULT);
    return Handle();
  }
  Handle owned(dataset);
  Handle dcpl(H5Dget_create_plist(dataset));
  if (!dcpl || H5Pget_layout(dcpl.get()) != H5D_VIRTUAL) {
    H5Eclear2(H5E_DEFAULT);
    return Handle();
  }
  return dcpl;
}

Mappings ReadMappings(hid_t file) {
  Mappings mappings;
  for (const std::string& path : PerRunDatasets(file)) {
    Handle dcpl = VirtualCreation(file, path);
    if (!dcpl) continue;
    std::size_t count = 0;
    if (H5Pget_virtual_count(dcpl.get(), &count) < 0) count = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const ssize_t length = H5Pget_virtual_filename(dcpl.get(), i, nullptr, 0);
      if (length < 0) continue;
      std::string pattern(static_cast<std::size_t>(length) + 1, '\0');
      H5Pget_virtual_filename(dcpl.get(), i, pattern.data(), pattern.size());
      pattern.resize(static_cast<std::size_t>(length));
      const std::string name = FromPattern(pattern);
      if (std::find(mappings.files.begin(), mappings.files.end(), name) == mappings.files.end())
        mappings.files.push_back(name);
      if (path != kRunStatus) continue;
      Handle space(H5Pget_virtual_vspace(dcpl.get(), i));
      hsize_t start[1] = {0}, end[1] = {0};
      if (space && H5Sget_simple_extent_ndims(space.get()) == 1 &&
          H5Sget_select_bounds(space.get(), start, end) >= 0) {
        mappings.status_rows.emplace(name, std::make_pair(static_cast<std::int64_t>(start[0]),
                                                          static_cast<std::int64_t>(end[0] - start[0] + 1)));
      }
    }
    H5Eclear2(H5E_DEFAULT);
  }
  return mappings;
}

std::string Abbreviated(const std::string& id) { return id.empty() ? "none" : id; }

// Checks the sources of one virtual archive, and of the virtual archives among them, depth first.
class SourceChecker {
 public:
  explicit SourceChecker(SourceCheck& out) : out_(out) {}

  void Check(hid_t file, const std::filesystem::path& path, bool top) {
    const auto key = FileKey(path);
    if (key) chain_.push_back({*key, path});
    CheckSources(file, path, top);
    if (key) chain_.pop_back();
  }

 private:
  struct Link {
    std::pair<dev_t, ino_t> key;
    std::filesystem::path path;
  };

  void CheckSources(hid_t file, const std::filesystem::path& path, bool top);
  FoundSource Find(const std::filesystem::path& path, const RecordedSource& recorded, Handle* opened,
                   const std::function<void(const std::string&)>& refuse) const;

  SourceCheck& out_;
  std::vector<Link> chain_;
};

FoundSource SourceChecker::Find(const std::filesystem::path& path, const RecordedSource& recorded,
                                Handle* opened, const std::function<void(const std::string&)>& refuse) const {
  const std::vector<std::filesystem::path> candidates = SourceCandidates(path, recorded.name);
  // Where the merge put it, for messages: beside the archive.
  const std::filesystem::path expected = Join(ExternalPath(path), recorded.name);
  std::string unusable;  // why a file that exists where HDF5 looks could not be read
  for (const std::filesystem::path& candidate : candidates) {
    struct stat info {};
    if (::stat(candidate.c_str(), &info) != 0) continue;
    if (S_ISDIR(info.st_mode)) {
      if (unusable.empty()) unusable = "shard file " + candidate.string() + " is a directory";
      continue;
    }
    if (!S_ISREG(info.st_mode)) {
      // HDF5 would open it and wait for ever on a FIFO, or read a device without end.
      refuse("shard file " + candidate.string() + " is " + DescribeFileType(candidate) +
             ", not a regular file");
    }
    const std::pair<dev_t, ino_t> key{info.st_dev, info.st_ino};
    for (std::size_t i = 0; i < chain_.size(); ++i) {
      if (chain_[i].key != key) continue;
      if (i + 1 == chain_.size()) {
        refuse("shard file " + candidate.string() + " is this virtual archive itself (a link to it?): an " +
               "archive cannot be its own shard");
      }
      refuse("shard file " + candidate.string() + " is the virtual archive " + chain_[i].path.string() +
             " again: virtual archives that read each other in a cycle cannot be read");
    }
    Handle fapl = hdf5::FileAccess();
    const hid_t id = H5Fopen(candidate.c_str(), H5F_ACC_RDONLY, fapl.get());
    H5Eclear2(H5E_DEFAULT);
    if (id < 0) {
      // HDF5 goes on to the next place too.
      if (unusable.empty()) {
        unusable = "shard file " + candidate.string() +
                   " cannot be opened (not an HDF5 file, in use by a writer, or damaged)";
      }
      continue;
    }
    *opened = Handle(id);
    FoundSource found;
    found.recorded = recorded;
    found.path = candidate;
    return found;
  }
  refuse(unusable.empty() ? "shard file " + expected.string() + " is missing" : unusable);
  return FoundSource{};  // not reached: refuse throws
}

void SourceChecker::CheckSources(hid_t file, const std::filesystem::path& path, bool top) {
  const std::string shown = path.string();
  auto refuse_name = [&](const std::string& name, const std::string& why) {
    throw RequestError(shown, kSources, name, why + kStay, "merge_copy");
  };
  if (chain_.size() > kMaximumNesting) {
    refuse_name("", "virtual archives nested more than " + std::to_string(kMaximumNesting) + " deep");
  }
  const ArchiveIdentity merged = ReadIdentity(file);
  const std::vector<RecordedSource> recorded = ReadRecordedSources(file);
  const Mappings mappings = ReadMappings(file);
  for (const std::string& name : mappings.files) {
    if (name == ".") refuse_name(name, "a virtual dataset maps this file itself");
    const bool listed = std::any_of(recorded.begin(), recorded.end(),
                                    [&](const RecordedSource& source) { return source.name == name; });
    if (!listed) {
      refuse_name(name,
                  "a virtual dataset maps this file, which virtual_sources does not list (a damaged "
                  "archive, or one not written by gesweep)");
    }
  }
  const bool identities = std::all_of(recorded.begin(), recorded.end(), [](const RecordedSource& source) {
    return source.identity.has_value();
  });
  if (!recorded.empty() && !identities) {
    out_.notes.push_back(
        shown +
        ": a virtual archive merged before shard identities: its shard files are checked for "
        "study, runs and completeness only, not for being the very files merged (merge again "
        "to record them)");
  }
  for (const RecordedSource& source : recorded) {
    auto refuse = [&](const std::string& why) { refuse_name(source.name, why); };
    const auto rows = mappings.status_rows.find(source.name);
    if (rows == mappings.status_rows.end()) refuse("runs/status does not map this listed shard file");
    Handle opened;
    FoundSource found = Find(path, source, &opened, refuse);
    const std::string where = "shard file " + found.path.string();
    if (hdf5::ReadStringAttribute(opened.get(), "format").value_or("") != kFormatName) {
      refuse(where + " is not a gesweep archive");
    }
    found.identity = ReadIdentity(opened.get());
    const ArchiveIdentity& have = found.identity;
    if (have.fingerprint != merged.fingerprint) {
      refuse(where + " is an archive of another study (study_fingerprint " + have.fingerprint +
             ", expected " + merged.fingerprint + ")");
    }
    // What the mapping says it must hold (and, where recorded, which shard it was).
    ArchiveIdentity want = source.identity.value_or(ArchiveIdentity{});
    want.design_runs = merged.design_runs;
    want.first_run = merged.first_run + rows->second.first;
    want.run_count = rows->second.second;
    if (have.design_runs != want.design_runs || have.first_run != want.first_run ||
        have.run_count != want.run_count) {
      refuse(where + " holds " + have.Holds() + ", expected " + want.Holds() +
             ": another shard's file copied or moved over it, or a re-run for another shard");
    }
    if (hdf5::ReadIntegerAttribute(opened.get(), "complete").value_or(0) != 1) {
      refuse(where + " is not complete (a sweep is writing it, or resumed it since the merge)");
    }
    if (source.identity && source.identity->id != have.id) {
      refuse(where + " is not the file that was merged: its archive_id is " + Abbreviated(have.id) +
             ", expected " + Abbreviated(source.identity->id) +
             " (the same runs, written again or replaced since the merge)");
    }
    if (source.identity && source.identity->id.empty()) {
      out_.notes.push_back(
          shown + ": shard file " + found.path.string() +
          " was written before shard identities: checked for study, runs and completeness only");
    }
    found.is_virtual = hdf5::ReadStringAttribute(opened.get(), "merge_kind").value_or("") == "virtual" ||
                       HasVirtualDatasets(opened.get());
    out_.files.push_back(found.path);
    if (found.is_virtual) Check(opened.get(), found.path, false);
    if (top) out_.sources.push_back(std::move(found));
  }
}

}  // namespace

std::string NewArchiveId() {
  std::array<unsigned char, 16> bytes{};
  bool filled = false;
  const int fd = ::open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    filled = ::read(fd, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
    ::close(fd);
  }
  if (!filled) {
    std::random_device device;
    for (std::size_t i = 0; i < bytes.size(); i += 4) {
      const unsigned value = device();
      for (std::size_t k = 0; k < 4; ++k) bytes[i + k] = static_cast<unsigned char>(value >> (8 * k));
    }
  }
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text;
  text.reserve(2 * bytes.size());
  for (unsigned char byte : bytes) {
    text.push_back(kDigits[byte >> 4]);
    text.push_back(kDigits[byte & 0xf]);
  }
  return text;
}

std::string ArchiveIdentity::Holds() const {
  std::string text =
      run_count > 0 ? "runs " + std::to_string(first_run) + ".." + std::to_string(first_run + run_count - 1)
                    : "no runs";
  text += " of " + std::to_string(design_runs);
  if (!shard.empty()) text += " (shard " + shard + ")";
  return text;
}

ArchiveIdentity ReadIdentity(hid_t file) {
  auto text = [&](const char* name) {
    try {
      return hdf5::ReadStringAttribute(file, name).value_or("");
    } catch (const ArchiveError&) {
      H5Eclear2(H5E_DEFAULT);
      return std::string();
    }
  };
  auto integer = [&](const char* name) {
    try {
      return hdf5::ReadIntegerAttribute(file, name).value_or(0);
    } catch (const ArchiveError&) {
      H5Eclear2(H5E_DEFAULT);
      return std::int64_t{0};
    }
  };
  ArchiveIdentity identity;
  identity.id = text("archive_id");
  identity.fingerprint = text("study_fingerprint");
  identity.design_runs = integer("design_runs");
  identity.first_run = integer("first_run");
  identity.run_count = integer("run_count");
  identity.shard = text("shard");
  return identity;
}

void WriteRecordedSources(hid_t file, const std::vector<RecordedSource>& sources) {
  std::vector<std::string> names, ids, fingerprints, shards;
  std::vector<std::int64_t> first_runs, run_counts;
  for (const RecordedSource& source : sources) {
    const ArchiveIdentity identity = source.identity.value_or(ArchiveIdentity{});
    names.push_back(source.name);
    ids.push_back(identity.id);
    fingerprints.push_back(identity.fingerprint);
    shards.push_back(identity.shard);
    first_runs.push_back(identity.first_run);
    run_counts.push_back(identity.run_count);
  }
  hdf5::WriteAttribute(file, kSources, names);
  hdf5::WriteAttribute(file, kSourceIds, ids);
  hdf5::WriteAttribute(file, kSourceFingerprints, fingerprints);
  hdf5::WriteAttribute(file, kSourceFirstRuns, first_runs);
  hdf5::WriteAttribute(file, kSourceRunCounts, run_counts);
  hdf5::WriteAttribute(file, kSourceShards, shards);
}

std::vector<RecordedSource> ReadRecordedSources(hid_t file) {
  std::vector<RecordedSource> sources;
  const std::vector<std::string> names = hdf5::ReadStringListAttribute(file, kSources);
  const bool recorded = H5Aexists(file, kSourceIds) > 0;
  H5Eclear2(H5E_DEFAULT);
  std::vector<std::string> ids, fingerprints, shards;
  std::vector<std::int64_t> first_runs, run_counts;
  if (recorded) {
    ids = hdf5::ReadStringListAttribute(file, kSourceIds);
    fingerprints = hdf5::ReadStringListAttribute(file, kSourceFingerprints);
    shards = hdf5::ReadStringListAttribute(file, kSourceShards);
    first_runs = hdf5::ReadIntegerListAttribute(file, kSourceFirstRuns);
    run_counts = hdf5::ReadIntegerListAttribute(file, kSourceRunCounts);
  }
  const std::int64_t design_runs = hdf5::ReadIntegerAttribute(file, "design_runs").value_or(0);
  const std::size_t n = names.size();
  const bool complete = recorded && ids.size() == n && fingerprints.size() == n && shards.size() == n &&
                        first_runs.size() == n && run_counts.size() == n;
  if (recorded && !complete) {
    throw InputError("", kSourceIds, "",
                     "expected one identity per file of virtual_sources (a damaged archive, or one not "
                     "written by gesweep)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    RecordedSource source;
    source.name = names[i];
    if (complete) {
      source.identity =
          ArchiveIdentity{ids[i], fingerprints[i], design_runs, first_runs[i], run_counts[i], shards[i]};
    }
    sources.push_back(std::move(source));
  }
  return sources;
}

std::string VirtualFilePattern(const std::string& name) {
  std::string pattern;
  pattern.reserve(name.size());
  for (char c : name) {
    pattern.push_back(c);
    if (c == '%') pattern.push_back('%');
  }
  return pattern;
}

std::vector<std::filesystem::path> SourceCandidates(const std::filesystem::path& archive,
                                                    const std::string& name) {
  std::vector<std::filesystem::path> candidates;
  std::string base = name;
  if (!name.empty() && name[0] == '/') {
    candidates.emplace_back(name);
    base = name.substr(name.rfind('/') + 1);
  }
  const std::string external = ExternalPath(archive);
  if (const char* prefixes = std::getenv("HDF5_VDS_PREFIX"); prefixes != nullptr && *prefixes != '\0') {
    const std::string value = prefixes;
    for (std::size_t start = 0; start <= value.size();) {
      const std::size_t end = std::min(value.find(':', start), value.size());
      if (end > start) candidates.emplace_back(Join(value.substr(start, end - start), base));
      start = end + 1;
    }
    // The dataset access's prefix, which HDF5 takes from the same variable, "${ORIGIN}" expanded.
    constexpr std::string_view kOrigin = "${ORIGIN}";
    if (value != ".") {
      candidates.emplace_back(
          Join(value.rfind(kOrigin, 0) == 0 ? external + value.substr(kOrigin.size()) : value, base));
    }
  }
  candidates.emplace_back(Join(external, base));
  candidates.emplace_back(base);
  // HDF5's "actual name" of the archive: the file a symlink points to, else the name as given.
  std::error_code ec;
  std::filesystem::path actual = archive;
  if (std::filesystem::is_symlink(archive, ec)) actual = std::filesystem::canonical(archive, ec);
  const std::string actual_name = ec ? archive.string() : actual.string();
  if (const auto slash = actual_name.rfind('/'); slash != std::string::npos) {
    candidates.emplace_back(Join(actual_name.substr(0, slash + 1), base));
  }
  return candidates;
}

bool HasVirtualDatasets(hid_t file) {
  for (const std::string& path : PerRunDatasets(file)) {
    if (VirtualCreation(file, path)) return true;
  }
  return false;
}

SourceCheck CheckVirtualSources(hid_t file, const std::filesystem::path& path) {
  SourceCheck check;
  SourceChecker checker(check);
  try {
    checker.Check(file, path, true);
  } catch (const RequestError&) {
    throw;
  } catch (const InputError& e) {
    if (!e.source().empty()) throw;
    throw InputError(path.string(), e.key(), e.value(), e.expected());
  }
  return check;
}

void SetArchiveNoteHandler(std::function<void(const std::string&)> handler) {
  NoteHandler() = std::move(handler);
}

void SendArchiveNote(const std::string& note) {
  if (NoteHandler()) NoteHandler()(note);
}

}  // namespace gesweep::archive
