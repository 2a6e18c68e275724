#pragma once
/// Merging shard archives (`gesweep merge`; docs/sweep.md, "Sharding and merge"): checks that the
/// shards come from the same study and engine, that each is complete, and that together they
/// cover the design exactly once; then writes one archive in design order, chunk by chunk
/// (memory bounded by one chunk per dataset), equal to a single-process run's apart from
/// provenance.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace gesweep {

/// What a merge did.
struct MergeReport {
  int shards = 0;
  std::int64_t runs = 0;
  std::int64_t runs_ok = 0;
  std::int64_t runs_failed = 0;
};

/// Merges `inputs` into `output` (written under OUTPUT.partial, then renamed). Throws InputError
/// naming the offending shard (missing, overlapping, incomplete, from another study or engine) and
/// nothing is left under `output`; refuses an existing `output` unless `force`.
MergeReport MergeArchives(const std::vector<std::filesystem::path>& inputs,
                          const std::filesystem::path& output, bool force, const std::string& command_line);

}  // namespace gesweep
