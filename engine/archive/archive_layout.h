#pragma once
/// The stored datasets of a sweep's archive (schemas/archive.md): for each, its path, element type,
/// chunk shape, fill value and filter pipeline, and how a batch's values become its chunks. One
/// layout serves the writer (which creates the datasets from it and stores the chunks) and the
/// workers of every process (which encode their batches with it): the chunks a worker makes are
/// exactly the chunks of the file. No HDF5 call here.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/archive/chunk_filters.h"
#include "engine/sweep/runner.h"

namespace gesweep::archive {

/// How a dataset's elements are stored.
enum class ElementKind {
  kFloat64,  ///< IEEE little-endian double
  kInt64,
  kUInt64,
  kInt32,
  kInt8,
  kComplex,  ///< compound {re, im} of little-endian doubles (h5py: complex128)
  kString,   ///< fixed-length, NUL-padded UTF-8 (runs/message)
};

/// Where a dataset's values come from in a ResultBlock.
enum class ValueSource { kDesign, kResult, kIndex, kId, kStatus, kMessage };

/// One per-run dataset of the archive.
struct StoredDataset {
  std::string path;
  ElementKind kind = ElementKind::kFloat64;
  ValueSource source = ValueSource::kResult;
  int column = 0;                   ///< design column or result column
  int width = 1;                    ///< elements per run (1: a 1-D dataset, else N × width)
  std::size_t element_size = 8;     ///< bytes per element
  std::int64_t chunk_rows = 1;      ///< runs per chunk (divides the batch size)
  std::vector<unsigned char> fill;  ///< one element's fill value; empty: none set (reads as zeros)
  FilterPipeline filters;
  std::int32_t integer_fill = -1;  ///< NaN of an integer result column is stored as this

  std::size_t row_bytes() const { return element_size * static_cast<std::size_t>(width); }
  std::size_t chunk_bytes() const { return row_bytes() * static_cast<std::size_t>(chunk_rows); }
};

/// Series chunk rows for a series of `samples` values when batches have `chunk_runs` runs: the
/// largest divisor of chunk_runs whose chunk stays within 1 MiB (at least 1).
int SeriesChunkRows(int chunk_runs, int samples);
/// Chunk rows of runs/message: the largest divisor of chunk_runs up to kMessageChunkRows, so that a
/// batch stores only the few small message chunks that hold a message.
int MessageChunkRows(int chunk_runs);
/// At most this many runs per chunk of runs/message (64 × 1024 bytes = 64 KiB before compression).
inline constexpr int kMessageChunkRows = 64;

/// The datasets of an archive of `plan` (its batch size and the study's compression level), in a
/// fixed order: design, results, runs/index, runs/id, runs/message, runs/status. runs/status is
/// last: the writer stores it after the others are flushed (a nonzero status marks a complete run).
class ArchiveLayout {
 public:
  explicit ArchiveLayout(const SweepPlan& plan);

  const std::vector<StoredDataset>& datasets() const { return datasets_; }
  int status_dataset() const { return static_cast<int>(datasets_.size()) - 1; }
  int chunk_runs() const { return chunk_runs_; }

  /// Encodes a computed batch: block.chunks[0 .. chunk_count) become the filtered chunks of every
  /// dataset, runs/status last (message chunks only where a run has a message). Thread-safe (each
  /// thread filters with its own zlib state).
  void Encode(ResultBlock& block) const;

  /// The unfiltered bytes of rows [first, first + count) of dataset `d` of a batch (tests; the
  /// rows of a chunk beyond the batch hold the fill value).
  void RawRows(const ResultBlock& block, int d, std::int64_t first, std::int64_t count,
               std::vector<unsigned char>& out) const;

 private:
  int chunk_runs_ = 1;
  std::vector<StoredDataset> datasets_;
};

}  // namespace gesweep::archive
