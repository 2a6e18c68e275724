#pragma once
/// HDF5's chunk filters, done outside HDF5 so that the worker that computed a batch filters its own
/// chunks (docs/sweep.md, "Workers compress their own chunks"). The output is byte for byte what
/// HDF5's own pipeline writes for the same chunk and filter list (tests/archive/chunk_filters_test.cc
/// compares the two through H5Dread_chunk): the shuffle of H5Zshuffle.c, zlib's compress2 at the
/// dataset's level as in H5Zdeflate.c (the same Debian zlib HDF5 links; or libdeflate's stream of the
/// same format, DeflateEncoder, which HDF5's filter reads back to the same bytes), and the Fletcher-32
/// checksum of H5checksum.c appended little-endian as in H5Zfletcher32.c. The writer then stores the
/// bytes with H5Dwrite_chunk. No HDF5 call here: this runs on any thread, in any process (MPI ranks).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "engine/common/copy_rules.h"
#include "engine/common/deflate_encoder.h"

namespace gesweep::archive {

/// The filter pipeline of a dataset, in HDF5's order: shuffle, deflate, Fletcher-32.
struct FilterPipeline {
  std::size_t element_size = 1;  ///< bytes per element (the shuffle's parameter: the datatype size)
  bool shuffle = false;
  int deflate_level = 0;  ///< 0: no deflate filter; 1..9 zlib level
  DeflateEncoder encoder = DeflateEncoder::kZlib;
  bool fletcher32 = true;

  /// Number of filters in the pipeline (the bit positions of the filter mask).
  int filter_count() const { return (shuffle ? 1 : 0) + (deflate_level > 0 ? 1 : 0) + (fletcher32 ? 1 : 0); }
};

/// H5Zshuffle.c's byte transposition: byte j of every element together, then the leftover bytes
/// (size % element_size) unchanged at the end. A copy when element_size or the element count is 1.
void Shuffle(const unsigned char* in, std::size_t size, std::size_t element_size, unsigned char* out);
/// Its inverse.
void Unshuffle(const unsigned char* in, std::size_t size, std::size_t element_size, unsigned char* out);

/// H5_checksum_fletcher32 (H5checksum.c): Fletcher's checksum over big-endian 16-bit words, sums
/// started at 0, an odd last byte as the high byte of a word.
std::uint32_t Fletcher32(const unsigned char* data, std::size_t size);

/// Filters chunks; one per thread (it keeps zlib's state between chunks: deflateReset gives the
/// same stream as a fresh compress2, without allocating and clearing its tables every time).
class ChunkFilter {
 public:
  ChunkFilter();
  ~ChunkFilter();
  GESWEEP_NO_COPY(ChunkFilter);

  /// Filters `size` bytes into `out` (resized) and returns HDF5's filter mask: bit i set when filter
  /// i was skipped, which HDF5 does for an optional filter that fails (deflate when its output would
  /// not fit in HDF5's buffer of 1.001·size + 12 bytes: then the data is stored unfiltered by it).
  std::uint32_t Apply(const FilterPipeline& pipeline, const unsigned char* data, std::size_t size,
                      std::vector<unsigned char>& out);

  /// Undoes Apply (for tests and for readers that take raw chunks): checks the checksum and returns
  /// false when it does not match or the stream is damaged; `size` is the chunk's unfiltered size.
  bool Reverse(const FilterPipeline& pipeline, std::uint32_t filter_mask, const unsigned char* data,
               std::size_t stored_size, std::size_t size, std::vector<unsigned char>& out);

 private:
  struct Zlib;
  Zlib* zlib_ = nullptr;
  struct Libdeflate;
  Libdeflate* libdeflate_ = nullptr;
  int zlib_level_ = -1;
  std::vector<unsigned char> scratch_;
};

}  // namespace gesweep::archive
