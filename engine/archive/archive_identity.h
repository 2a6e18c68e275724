#pragma once
/// The identity of an archive and the check of a virtual archive's sources (schemas/archive.md,
/// "Identity"; docs/cluster.md, "What a reader checks").
///
/// Every archive carries, in its root attributes, an identity written once when it is created: a
/// random 128-bit `archive_id` beside what it holds (the study fingerprint, the design runs it holds,
/// its shard). A resume keeps it, `--force` and every merge make a new one. A virtual archive records
/// the identity of each source file it maps. Before anything reads a value of a virtual archive,
/// CheckVirtualSources finds each source where HDF5 will find it and compares identities, so that a
/// missing, replaced, moved, foreign or self-referencing shard, or a cycle of virtual archives, is
/// refused with one line instead of read as fill values, as another file's runs, or in an endless
/// recursion inside libhdf5.

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace gesweep::archive {

/// A new archive's id: 128 random bits from the operating system (/dev/urandom, else
/// std::random_device) as 32 lowercase hex digits.
std::string NewArchiveId();

/// What identifies an archive: its id and what it holds (root attributes of schemas/archive.md).
struct ArchiveIdentity {
  std::string id;                ///< archive_id; "" for an archive written before identities
  std::string fingerprint;       ///< study_fingerprint
  std::int64_t design_runs = 0;  ///< runs in the whole design
  std::int64_t first_run = 0;    ///< first design run it holds
  std::int64_t run_count = 0;    ///< design runs it holds, from first_run on
  std::string shard;             ///< "i/N"

  /// What it holds, for messages: "runs 0..47 of 105 (shard 0/2)".
  std::string Holds() const;
};

/// The identity in the root attributes of `file` (an absent attribute reads as "" or 0).
ArchiveIdentity ReadIdentity(hid_t file);

/// One source file of a virtual archive as its merge recorded it.
struct RecordedSource {
  std::string name;  ///< as in virtual_sources: relative to the archive's directory, or absolute
  std::optional<ArchiveIdentity> identity;  ///< none in an archive merged before identities
};

/// Writes virtual_sources and the identity of each source beside it (virtual_source_ids,
/// _fingerprints, _first_runs, _run_counts, _shards); every source must have an identity, an empty
/// id standing for a source written before identities.
void WriteRecordedSources(hid_t file, const std::vector<RecordedSource>& sources);

/// The sources a virtual archive recorded; their identities when it recorded them (merged with
/// identities), none otherwise.
std::vector<RecordedSource> ReadRecordedSources(hid_t file);

/// `name` as H5Pset_virtual takes a source file name: a printf-like pattern in which "%b" stands for
/// a block number and "%%" for "%", so every '%' doubled.
std::string VirtualFilePattern(const std::string& name);

/// The files HDF5 1.10 tries, in its order, for the source file `name` of a virtual dataset of the
/// archive opened as `archive` from the current directory; it reads the first one it can open.
/// An absolute `name` as given first (then its last component stands for it); then each
/// ':'-separated prefix of the environment variable HDF5_VDS_PREFIX, and its whole value with a
/// leading "${ORIGIN}" read as the archive's directory ("." standing for none); the archive's
/// directory; `name` from the current directory; the directory of the file a symlink `archive`
/// points to.
std::vector<std::filesystem::path> SourceCandidates(const std::filesystem::path& archive,
                                                    const std::string& name);

/// A source of a virtual archive, found and checked.
struct FoundSource {
  RecordedSource recorded;
  std::filesystem::path path;  ///< the file HDF5 reads for it
  ArchiveIdentity identity;    ///< the identity in that file
  bool is_virtual = false;     ///< itself a virtual archive (made before merges mapped plain files)
};

/// What checking a virtual archive's sources found.
struct SourceCheck {
  std::vector<FoundSource> sources;          ///< its sources, in virtual_sources order
  std::vector<std::filesystem::path> files;  ///< every file a read of it opens, sources' sources included
  std::vector<std::string> notes;            ///< what could not be checked (merged before identities)
};

/// Whether `file` has a dataset under runs/, design/, results/ or series/ whose layout is virtual.
bool HasVirtualDatasets(hid_t file);

/// Checks every source of the virtual archive `file`, opened from `path`, before anything reads a
/// value of it: each file its virtual datasets map is one virtual_sources lists (`.`, this file,
/// refused); each source is found where HDF5 finds it (SourceCandidates) and must be a regular file
/// that HDF5 opens, a gesweep archive, not this archive (a link to it), of the same study and design,
/// holding the runs its mapping gives it, complete, and, where the merge recorded it, with the
/// recorded archive_id; a source that is itself virtual is checked in turn, and a cycle of virtual
/// archives is refused, never followed. Throws RequestError (source `path`, key virtual_sources, the
/// recorded name; remedy "merge_copy") naming the file and what was expected.
SourceCheck CheckVirtualSources(hid_t file, const std::filesystem::path& path);

/// Where notes about archives go: a reader below engine/cli never prints, so the gesweep command
/// installs a handler that prints each note once (ArchiveReader::Open sends every note it makes to
/// it); without one a note is kept only by the reader (ArchiveReader::notes). Not thread-safe: set
/// once, at start-up.
void SetArchiveNoteHandler(std::function<void(const std::string&)> handler);
/// Sends `note` to the handler, if one is installed.
void SendArchiveNote(const std::string& note);

}  // namespace gesweep::archive
