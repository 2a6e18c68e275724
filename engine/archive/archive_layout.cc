#include "engine/archive/archive_layout.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/archive/archive_format.h"
#include "engine/common/errors.h"

namespace gesweep::archive {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the archive stores little-endian values and the workers encode them from memory as they are");

// Series chunks stay within this size: big enough to compress well, small enough for HDF5's
// default 1 MiB chunk cache.
constexpr std::int64_t kMaximumSeriesChunkBytes = 1 << 20;

template <typename T>
std::vector<unsigned char> Bytes(T value) {
  std::vector<unsigned char> out(sizeof(T));
  std::memcpy(out.data(), &value, sizeof(T));
  return out;
}

std::string ParameterNameOf(const DesignParameter& parameter) {
  return ParameterCatalog()[static_cast<std::size_t>(parameter.id)].name;
}

FilterPipeline Filters(std::size_t element_size, int level, bool shuffle) {
  FilterPipeline filters;
  filters.element_size = element_size;
  filters.shuffle = level > 0 && shuffle && element_size > 1;
  filters.deflate_level = level;
  filters.fletcher32 = true;
  return filters;
}

// A dataset of one T per run, chunked like the batches, shuffled and filled with `fill`.
template <typename T>
StoredDataset PerRunDataset(std::string path, ElementKind kind, ValueSource source, T fill, int chunk_runs,
                            int level) {
  StoredDataset d;
  d.path = std::move(path);
  d.kind = kind;
  d.source = source;
  d.element_size = sizeof(T);
  d.chunk_rows = chunk_runs;
  d.fill = Bytes(fill);
  d.filters = Filters(sizeof(T), level, true);
  return d;
}

// One thread's zlib state and scratch buffer.
struct ThreadFilter {
  ChunkFilter filter;
  std::vector<unsigned char> raw;
};

ThreadFilter& LocalFilter() {
  thread_local ThreadFilter local;
  return local;
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

int MessageChunkRows(int chunk_runs) {
  int best = 1;
  for (int d = 1; d <= std::min(chunk_runs, kMessageChunkRows); ++d) {
    if (chunk_runs % d == 0) best = d;
  }
  return best;
}

ArchiveLayout::ArchiveLayout(const SweepPlan& plan) : chunk_runs_(plan.chunk_runs()) {
  const int level = plan.study().compression_level;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto& parameters = plan.design().spec().parameters;
  for (std::size_t c = 0; c < parameters.size(); ++c) {
    StoredDataset d = PerRunDataset(DesignPath(ParameterNameOf(parameters[c])), ElementKind::kFloat64,
                                    ValueSource::kDesign, nan, chunk_runs_, level);
    d.column = static_cast<int>(c);
    datasets_.push_back(std::move(d));
  }
  const auto& columns = plan.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const OutputColumn& column = columns[c];
    StoredDataset d;
    d.path = column.path;
    d.source = ValueSource::kResult;
    d.column = static_cast<int>(c);
    d.width = column.width;
    d.integer_fill = column.integer_fill;
    d.chunk_rows = column.width > 1 && !column.time_axis.empty() ? SeriesChunkRows(chunk_runs_, column.width)
                                                                 : chunk_runs_;
    switch (column.type) {
      case ColumnType::kFloat64:
        d.kind = ElementKind::kFloat64;
        d.element_size = 8;
        d.fill = Bytes(nan);
        break;
      case ColumnType::kInt32:
        d.kind = ElementKind::kInt32;
        d.element_size = 4;
        d.fill = Bytes(static_cast<std::int32_t>(column.integer_fill));
        break;
      case ColumnType::kInt8:
        d.kind = ElementKind::kInt8;
        d.element_size = 1;
        d.fill = Bytes(static_cast<std::int8_t>(column.integer_fill));
        break;
      case ColumnType::kComplex: {
        d.kind = ElementKind::kComplex;
        d.element_size = 16;
        const double pair[2] = {nan, nan};
        d.fill.resize(16);
        std::memcpy(d.fill.data(), pair, 16);
        break;
      }
    }
    d.filters = Filters(d.element_size, level, true);
    datasets_.push_back(std::move(d));
  }
  datasets_.push_back(PerRunDataset(kRunIndex, ElementKind::kInt64, ValueSource::kIndex, std::int64_t{-1},
                                    chunk_runs_, level));
  datasets_.push_back(
      PerRunDataset(kRunId, ElementKind::kUInt64, ValueSource::kId, std::uint64_t{0}, chunk_runs_, level));
  {
    // Sparse: a batch stores only the message chunks that hold a message; no shuffle (strings).
    StoredDataset d;
    d.path = kRunMessage;
    d.kind = ElementKind::kString;
    d.source = ValueSource::kMessage;
    d.element_size = static_cast<std::size_t>(kMessageLength);
    d.chunk_rows = MessageChunkRows(chunk_runs_);
    d.filters = Filters(d.element_size, level, false);
    datasets_.push_back(std::move(d));
  }
  datasets_.push_back(PerRunDataset(kRunStatus, ElementKind::kInt8, ValueSource::kStatus, std::int8_t{0},
                                    chunk_runs_, level));
  // Which library writes the deflate streams: the values read back are the same with either.
  for (StoredDataset& d : datasets_) d.filters.encoder = plan.study().deflate_encoder;
}

void ArchiveLayout::RawRows(const ResultBlock& block, int index, std::int64_t first, std::int64_t count,
                            std::vector<unsigned char>& out) const {
  const StoredDataset& d = datasets_[static_cast<std::size_t>(index)];
  const std::size_t row_bytes = d.row_bytes();
  out.resize(row_bytes * static_cast<std::size_t>(count));
  const std::int64_t present = std::clamp<std::int64_t>(block.rows - first, 0, count);
  unsigned char* at = out.data();
  const auto n = static_cast<std::size_t>(present);
  const auto from = static_cast<std::size_t>(first);
  switch (d.source) {
    case ValueSource::kDesign:
      std::memcpy(at, block.design[static_cast<std::size_t>(d.column)].data() + from, n * 8);
      break;
    case ValueSource::kIndex:
      std::memcpy(at, block.design_index.data() + from, n * 8);
      break;
    case ValueSource::kId:
      std::memcpy(at, block.run_id.data() + from, n * 8);
      break;
    case ValueSource::kStatus:
      std::memcpy(at, block.status.data() + from, n);
      break;
    case ValueSource::kMessage:
      // Fixed-size NULLPAD strings (hdf5::FixedStringType): a row holds the message's first row_bytes
      // bytes and zeros after them; a message that fills the row has no terminator.
      std::memset(at, 0, n * row_bytes);
      for (std::size_t r = 0; r < n; ++r) {
        const std::string& message = block.message[from + r];
        std::copy_n(message.data(), std::min(message.size(), row_bytes), at + r * row_bytes);
      }
      break;
    case ValueSource::kResult: {
      const std::vector<double>& values = block.results[static_cast<std::size_t>(d.column)];
      const std::size_t per_row =
          static_cast<std::size_t>(d.width) * (d.kind == ElementKind::kComplex ? 2 : 1);
      const double* src = values.data() + from * per_row;
      const std::size_t elements = n * static_cast<std::size_t>(d.width);
      switch (d.kind) {
        case ElementKind::kFloat64:
        case ElementKind::kComplex:
          std::memcpy(at, src, n * row_bytes);
          break;
        case ElementKind::kInt32:
          for (std::size_t i = 0; i < elements; ++i) {
            const std::int32_t v = std::isnan(src[i]) ? d.integer_fill : static_cast<std::int32_t>(src[i]);
            std::memcpy(at + 4 * i, &v, 4);
          }
          break;
        case ElementKind::kInt8:
          for (std::size_t i = 0; i < elements; ++i) {
            at[i] = static_cast<unsigned char>(std::isnan(src[i]) ? static_cast<std::int8_t>(d.integer_fill)
                                                                  : static_cast<std::int8_t>(src[i]));
          }
          break;
        default:
          GESWEEP_UNREACHABLE();
      }
      break;
    }
  }
  // Rows past the batch's end (the last, partial chunk of the shard): the fill value, as HDF5 fills
  // a chunk before writing part of it.
  unsigned char* tail = at + n * row_bytes;
  const std::size_t tail_elements =
      static_cast<std::size_t>(count - present) * static_cast<std::size_t>(d.width);
  if (d.fill.empty()) {
    std::memset(tail, 0, tail_elements * d.element_size);
  } else {
    for (std::size_t e = 0; e < tail_elements; ++e)
      std::memcpy(tail + e * d.element_size, d.fill.data(), d.element_size);
  }
}

void ArchiveLayout::Encode(ResultBlock& block) const {
  ThreadFilter& local = LocalFilter();
  int count = 0;
  auto next_chunk = [&]() -> StoredChunk& {
    if (static_cast<std::size_t>(count) == block.chunks.size()) block.chunks.emplace_back();
    return block.chunks[static_cast<std::size_t>(count++)];
  };
  for (int index = 0; index < static_cast<int>(datasets_.size()); ++index) {
    const StoredDataset& d = datasets_[static_cast<std::size_t>(index)];
    for (std::int64_t row = 0; row < block.rows; row += d.chunk_rows) {
      if (d.source == ValueSource::kMessage) {
        const auto end = static_cast<std::size_t>(std::min<std::int64_t>(row + d.chunk_rows, block.rows));
        bool any = false;
        for (auto r = static_cast<std::size_t>(row); r < end && !any; ++r) any = !block.message[r].empty();
        if (!any) continue;  // never written: reads as the fill (empty strings) and costs nothing
      }
      RawRows(block, index, row, d.chunk_rows, local.raw);
      StoredChunk& chunk = next_chunk();
      chunk.dataset = index;
      chunk.row = row;
      chunk.filter_mask = local.filter.Apply(d.filters, local.raw.data(), local.raw.size(), chunk.bytes);
    }
  }
  block.chunk_count = count;
}

}  // namespace gesweep::archive
