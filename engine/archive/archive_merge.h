#pragma once
/// Merging shard archives (`gesweep merge`; docs/sweep.md, "Sharding and merge"): checks that the
/// shards come from the same study and engine, that each is complete, and that together they
/// cover the design exactly once; then makes one archive, equal dataset by dataset to a
/// single-process run's apart from provenance, in one of two ways:
///
///  - virtual (the default): a small file whose per-run datasets are HDF5 virtual datasets mapping
///    each shard's rows to their place in the design (H5Pset_virtual). Nothing is copied, so it
///    takes a fraction of a second whatever the size; HDF5 (gesweep, h5py, h5dump, pandas through
///    h5py) reads it as one archive. It reads the shard files in place: they must stay where they
///    are (their paths are stored relative to the merged file, so moving the whole directory is
///    fine). It records each shard's identity (engine/archive/archive_identity.h), and ArchiveReader
///    refuses it, naming the file, when a shard is missing, replaced, foreign, itself or cyclic. A
///    virtual input is replaced by the files it maps, so a merged archive maps plain archives only.
///  - copy (`--copy`): a self-contained file made by raw chunk copy (H5Dread_chunk /
///    H5Dwrite_chunk): each stored chunk of a shard is copied as it is, nothing is inflated or
///    deflated. Shards start at batch boundaries (ShardRange), so their chunks coincide with the
///    merged file's; a chunk that does not (a shard smaller than one batch, or shards of another
///    split) is read through HDF5 and written again.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace gesweep {

/// How `gesweep merge` makes the merged archive.
enum class MergeKind {
  kVirtual,  ///< virtual datasets over the shard files (nothing copied; the shards must stay)
  kCopy,     ///< a self-contained file, chunks copied raw
};

/// What a merge did.
struct MergeReport {
  MergeKind kind = MergeKind::kVirtual;
  int shards = 0;
  std::int64_t runs = 0;
  std::int64_t runs_ok = 0;
  std::int64_t runs_failed = 0;
  std::int64_t chunks_copied = 0;     ///< copy: chunks copied raw
  std::int64_t chunks_rewritten = 0;  ///< copy: chunks that did not coincide, decoded and written again
  std::int64_t bytes_copied = 0;      ///< copy: stored (compressed) bytes copied raw
  std::vector<std::string> sources;   ///< virtual: the shard paths as stored (relative to the output)
};

/// The part of the design a merge covers: the whole design (the default), or one shard of it (an
/// MPI run of `--shard i/N` merges its nodes' files into shard i/N's archive).
struct MergeScope {
  std::int64_t first_run = 0;
  std::int64_t run_count = -1;  ///< -1: to the design's end
  int shard_index = 0;
  int shard_count = 1;
};

/// Merges `inputs` into `output` (written under OUTPUT.partial, then renamed), holding OUTPUT.lock as
/// `gesweep run` does (ArchiveLock). Throws InputError naming the offending shard (missing,
/// overlapping, incomplete, from another study or engine) and nothing is left under `output`; refuses
/// an existing `output` unless `force`, an `output` that is any file the inputs read (a virtual
/// input's shards included), and one another gesweep process is writing ("archive in use"). With
/// kCopy the result is self-contained also when an input is virtual (its shards' chunks are copied).
MergeReport MergeArchives(const std::vector<std::filesystem::path>& inputs,
                          const std::filesystem::path& output, bool force, const std::string& command_line,
                          MergeKind kind = MergeKind::kVirtual, const MergeScope& scope = MergeScope{});

}  // namespace gesweep
