#include "engine/archive/chunk_filters.h"

#include <libdeflate.h>
#include <zlib.h>

#include <cmath>
#include <cstring>

namespace gesweep::archive {

// zlib's allocations come from buffers this filter keeps: a fresh deflateInit + deflate + deflateEnd
// per chunk, exactly as compress2 (and so HDF5) does, but without asking the C library for a quarter
// of a megabyte and giving it back every chunk (on a shared VM that costs more than compressing a
// small chunk). The first allocation, zlib's deflate_state, is zeroed as the calloc behind zlib's
// default allocator would; the window, hash chains and pending buffer are not: zlib writes them
// before it reads them (it zeroes the bytes past the data it may scan itself, WIN_INIT), so the
// stream is compress2's bit for bit -- chunk_filters_test checks it against compress2 on thousands
// of inputs with deliberately dirty buffers, and against HDF5's own filter.
struct ChunkFilter::Zlib {
  std::vector<std::vector<unsigned char>> buffers;
  std::size_t next = 0;

  static voidpf Allocate(voidpf opaque, uInt items, uInt size) {
    auto* self = static_cast<Zlib*>(opaque);
    if (self->next == self->buffers.size()) self->buffers.emplace_back();
    std::vector<unsigned char>& buffer = self->buffers[self->next++];
    const std::size_t bytes = static_cast<std::size_t>(items) * size;
    if (buffer.size() < bytes) buffer.resize(bytes);
    if (self->next == 1) std::memset(buffer.data(), 0, bytes);  // the deflate_state
    return buffer.data();
  }
  static void Release(voidpf, voidpf) {}
};

// libdeflate's compressors, one per level, made on first use and kept (a compressor holds its
// tables: about half a megabyte at level 1).
struct ChunkFilter::Libdeflate {
  libdeflate_compressor* by_level[10] = {};
  ~Libdeflate() {
    for (auto* c : by_level) libdeflate_free_compressor(c);  // null is allowed
  }
  libdeflate_compressor* At(int level) {
    auto*& c = by_level[level];
    if (c == nullptr) c = libdeflate_alloc_compressor(level);
    return c;  // null only when out of memory: the chunk is then stored without deflate
  }
};

namespace {

// HDF5's output buffer for deflate (H5Z_DEFLATE_SIZE_ADJUST): a stream that does not fit makes the
// filter fail, and HDF5 then stores the chunk without it (deflate is an optional filter).
std::size_t DeflateCapacity(std::size_t size) {
  return static_cast<std::size_t>(std::ceil(static_cast<double>(size) * 1.001)) + 12;
}

}  // namespace

void Shuffle(const unsigned char* in, std::size_t size, std::size_t element_size, unsigned char* out) {
  const std::size_t elements = element_size ? size / element_size : 0;
  if (element_size <= 1 || elements <= 1) {
    std::memcpy(out, in, size);
    return;
  }
  unsigned char* dst = out;
  for (std::size_t byte = 0; byte < element_size; ++byte) {
    const unsigned char* src = in + byte;
    for (std::size_t e = 0; e < elements; ++e, src += element_size) *dst++ = *src;
  }
  const std::size_t leftover = size % element_size;
  if (leftover) std::memcpy(dst, in + elements * element_size, leftover);
}

void Unshuffle(const unsigned char* in, std::size_t size, std::size_t element_size, unsigned char* out) {
  const std::size_t elements = element_size ? size / element_size : 0;
  if (element_size <= 1 || elements <= 1) {
    std::memcpy(out, in, size);
    return;
  }
  const unsigned char* src = in;
  for (std::size_t byte = 0; byte < element_size; ++byte) {
    unsigned char* dst = out + byte;
    for (std::size_t e = 0; e < elements; ++e, dst += element_size) *dst = *src++;
  }
  const std::size_t leftover = size % element_size;
  if (leftover) std::memcpy(out + elements * element_size, src, leftover);
}

std::uint32_t Fletcher32(const unsigned char* data, std::size_t size) {
  std::size_t words = size / 2;
  std::uint32_t sum1 = 0, sum2 = 0;
  // 360 words is the most that can be summed before the 32-bit sums could overflow.
  while (words) {
    std::size_t block = words > 360 ? 360 : words;
    words -= block;
    do {
      sum1 += (static_cast<std::uint32_t>(data[0]) << 8) | data[1];
      data += 2;
      sum2 += sum1;
    } while (--block);
    sum1 = (sum1 & 0xffff) + (sum1 >> 16);
    sum2 = (sum2 & 0xffff) + (sum2 >> 16);
  }
  if (size % 2) {
    sum1 += static_cast<std::uint32_t>(*data) << 8;
    sum2 += sum1;
    sum1 = (sum1 & 0xffff) + (sum1 >> 16);
    sum2 = (sum2 & 0xffff) + (sum2 >> 16);
  }
  sum1 = (sum1 & 0xffff) + (sum1 >> 16);
  sum2 = (sum2 & 0xffff) + (sum2 >> 16);
  return (sum2 << 16) | sum1;
}

ChunkFilter::ChunkFilter() : zlib_(new Zlib), libdeflate_(new Libdeflate) {}
ChunkFilter::~ChunkFilter() {
  delete zlib_;
  delete libdeflate_;
}

std::uint32_t ChunkFilter::Apply(const FilterPipeline& pipeline, const unsigned char* data, std::size_t size,
                                 std::vector<unsigned char>& out) {
  std::uint32_t mask = 0;
  int filter = 0;
  const unsigned char* current = data;
  std::size_t current_size = size;
  if (pipeline.shuffle) {
    scratch_.resize(size);
    Shuffle(data, size, pipeline.element_size, scratch_.data());
    current = scratch_.data();
    ++filter;
  }
  if (pipeline.deflate_level > 0 && pipeline.encoder == DeflateEncoder::kLibdeflate) {
    // The same rule as zlib's: a stream that does not fit HDF5's buffer skips the filter.
    out.resize(DeflateCapacity(current_size) + 4);
    libdeflate_compressor* compressor = libdeflate_->At(pipeline.deflate_level);
    const std::size_t written = compressor == nullptr
                                    ? 0
                                    : libdeflate_zlib_compress(compressor, current, current_size, out.data(),
                                                               DeflateCapacity(current_size));
    if (written > 0) {
      current_size = written;
      out.resize(current_size);
    } else {
      mask |= 1u << filter;
      out.assign(current, current + current_size);
    }
    ++filter;
  } else if (pipeline.deflate_level > 0) {
    out.resize(DeflateCapacity(current_size) + 4);  // + room for the checksum
    zlib_->next = 0;
    z_stream stream{};
    stream.zalloc = Zlib::Allocate;
    stream.zfree = Zlib::Release;
    stream.opaque = zlib_;
    bool ok = deflateInit(&stream, pipeline.deflate_level) == Z_OK;
    if (ok) {
      stream.next_in = const_cast<Bytef*>(current);
      stream.avail_in = static_cast<uInt>(current_size);
      stream.next_out = out.data();
      stream.avail_out = static_cast<uInt>(DeflateCapacity(current_size));
      ok = deflate(&stream, Z_FINISH) == Z_STREAM_END;
      deflateEnd(&stream);
    }
    if (ok) {
      current_size = stream.total_out;
      out.resize(current_size);
    } else {
      mask |= 1u << filter;  // skipped, as HDF5 skips an optional filter that fails
      out.assign(current, current + current_size);
    }
    ++filter;
  } else {
    out.assign(current, current + current_size);
  }
  if (pipeline.fletcher32) {
    const std::uint32_t sum = Fletcher32(out.data(), out.size());
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<unsigned char>(sum >> (8 * b)));  // little-endian
  }
  return mask;
}

bool ChunkFilter::Reverse(const FilterPipeline& pipeline, std::uint32_t filter_mask,
                          const unsigned char* data, std::size_t stored_size, std::size_t size,
                          std::vector<unsigned char>& out) {
  const int fletcher_bit = pipeline.filter_count() - 1;
  std::size_t length = stored_size;
  if (pipeline.fletcher32 && !(filter_mask & (1u << fletcher_bit))) {
    if (length < 4) return false;
    length -= 4;
    std::uint32_t stored = 0;
    for (int b = 0; b < 4; ++b)
      stored |= static_cast<std::uint32_t>(data[length + static_cast<std::size_t>(b)]) << (8 * b);
    if (stored != Fletcher32(data, length)) return false;
  }
  const int deflate_bit = pipeline.shuffle ? 1 : 0;
  std::vector<unsigned char> inflated;
  const unsigned char* current = data;
  if (pipeline.deflate_level > 0 && !(filter_mask & (1u << deflate_bit))) {
    inflated.resize(size);
    uLongf produced = static_cast<uLongf>(size);
    if (uncompress(inflated.data(), &produced, data, static_cast<uLong>(length)) != Z_OK || produced != size)
      return false;
    current = inflated.data();
    length = size;
  }
  if (length != size) return false;
  out.resize(size);
  if (pipeline.shuffle && !(filter_mask & 1u)) {
    Unshuffle(current, size, pipeline.element_size, out.data());
  } else {
    std::memcpy(out.data(), current, size);
  }
  return true;
}

}  // namespace gesweep::archive
