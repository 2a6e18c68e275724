// The workers' chunk filters against HDF5's own (the oracle): for every kind of dataset the archive
// stores, HDF5 writes a chunk through its filter pipeline (H5Dwrite), H5Dread_chunk gives the stored
// bytes, and ChunkFilter must produce the same bytes and filter mask from the same raw chunk --
// full chunks and the last, partial chunk (padded with the fill value), levels 0 (Fletcher-32
// only), 1, 4 and 9, and data that does not compress. Then whole archives: every chunk a sweep's
// workers stored equals the chunk HDF5 stores when given the same values (each dataset rewritten
// through H5Dwrite with its own creation properties).
#include "engine/archive/chunk_filters.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "engine/archive/archive_layout.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/archive/hdf5_util.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"

namespace gesweep::archive {
namespace {

using hdf5::Handle;

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

std::filesystem::path TempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() /
             ("gesweep_chunk_filters_" + std::to_string(getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A dataset creation property list with the filters of `pipeline`, in the archive's order.
Handle Creation(const FilterPipeline& pipeline, hsize_t chunk_rows, hsize_t width, hid_t type,
                const void* fill) {
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), "dcpl");
  hsize_t chunk[2] = {chunk_rows, width};
  H5Pset_chunk(dcpl.get(), width > 1 ? 2 : 1, chunk);
  if (pipeline.shuffle) H5Pset_shuffle(dcpl.get());
  if (pipeline.deflate_level > 0) H5Pset_deflate(dcpl.get(), static_cast<unsigned>(pipeline.deflate_level));
  if (pipeline.fletcher32) H5Pset_fletcher32(dcpl.get());
  if (fill) H5Pset_fill_value(dcpl.get(), type, fill);
  H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_IFSET);
  return dcpl;
}

struct Case {
  std::string name;
  hid_t type;
  std::size_t element_size;
  hsize_t width;
  bool shuffle;
};

// Writes `rows` rows of `data` (row_bytes each) with HDF5 into a dataset of chunk `chunk_rows` and
// compares each stored chunk with ChunkFilter's output for the same raw chunk.
void ExpectSameChunks(const Case& c, int level, const std::vector<unsigned char>& data, hsize_t rows,
                      hsize_t chunk_rows, const std::vector<unsigned char>& fill) {
  SCOPED_TRACE(c.name + " level " + std::to_string(level) + " rows " + std::to_string(rows));
  const auto dir = TempDir(c.name + std::to_string(level) + "_" + std::to_string(rows));
  const auto path = dir / "oracle.h5";
  FilterPipeline pipeline;
  pipeline.element_size = c.element_size;
  pipeline.shuffle = level > 0 && c.shuffle && c.element_size > 1;
  pipeline.deflate_level = level;
  pipeline.fletcher32 = true;
  const std::size_t row_bytes = c.element_size * c.width;
  {
    Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create");
    hsize_t dims[2] = {rows, c.width};
    Handle space(H5Screate_simple(c.width > 1 ? 2 : 1, dims, nullptr), "space");
    Handle dcpl = Creation(pipeline, chunk_rows, c.width, c.type, fill.empty() ? nullptr : fill.data());
    Handle dataset(H5Dcreate2(file.get(), "d", c.type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                   "dset");
    ASSERT_GE(H5Dwrite(dataset.get(), c.type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), 0);
  }
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open");
  Handle dataset(H5Dopen2(file.get(), "d", H5P_DEFAULT), "open d");
  ChunkFilter filter;
  for (hsize_t first = 0; first < rows; first += chunk_rows) {
    // The raw chunk: the rows, then the fill value (zeros without one) past the dataset's end.
    std::vector<unsigned char> raw(chunk_rows * row_bytes);
    const hsize_t present = std::min(chunk_rows, rows - first);
    std::memcpy(raw.data(), data.data() + first * row_bytes, present * row_bytes);
    for (std::size_t e = present * c.width; e < chunk_rows * c.width; ++e) {
      if (fill.empty()) {
        std::memset(raw.data() + e * c.element_size, 0, c.element_size);
      } else {
        std::memcpy(raw.data() + e * c.element_size, fill.data(), c.element_size);
      }
    }
    std::vector<unsigned char> ours;
    const std::uint32_t our_mask = filter.Apply(pipeline, raw.data(), raw.size(), ours);

    const hsize_t offset[2] = {first, 0};
    hsize_t stored_size = 0;
    ASSERT_GE(H5Dget_chunk_storage_size(dataset.get(), offset, &stored_size), 0);
    std::vector<unsigned char> theirs(stored_size);
    std::uint32_t their_mask = 0;
    ASSERT_GE(H5Dread_chunk(dataset.get(), H5P_DEFAULT, offset, &their_mask, theirs.data()), 0);
    EXPECT_EQ(our_mask, their_mask) << "chunk at row " << first;
    EXPECT_EQ(ours, theirs) << "chunk at row " << first << ": " << ours.size() << " bytes against "
                            << theirs.size();

    std::vector<unsigned char> back;
    ASSERT_TRUE(filter.Reverse(pipeline, our_mask, ours.data(), ours.size(), raw.size(), back));
    EXPECT_EQ(back, raw);
  }
  std::filesystem::remove_all(dir);
}

TEST(ChunkFilters, Fletcher32OfKnownBytes) {
  // Fletcher-32 over 16-bit big-endian words with sums from 0 (H5checksum.c): for "abcde"
  // (words 0x6162, 0x6364, an odd 0x65 as 0x6500) sum1 = 0x6162 + 0x6364 + 0x6500 = 0x129c6, folded
  // (high 16 bits added to the low) to 0x29c7; sum2 = 0x6162 + 0xc4c6 + 0x129c6 = 0x24fee -> 0x4ff0.
  const unsigned char text[] = {'a', 'b', 'c', 'd', 'e'};
  EXPECT_EQ(Fletcher32(text, 5), (0x4ff0u << 16) | 0x29c7u);
  const unsigned char pair[] = {0x01, 0x02};
  EXPECT_EQ(Fletcher32(pair, 2), (0x0102u << 16) | 0x0102u);
}

TEST(ChunkFilters, ShuffleTransposesBytesAndKeepsTheLeftover) {
  const unsigned char in[] = {0, 1, 2, 3, 10, 11, 12, 13, 99};
  unsigned char out[9];
  Shuffle(in, 9, 4, out);
  const unsigned char expected[] = {0, 10, 1, 11, 2, 12, 3, 13, 99};
  EXPECT_EQ(0, std::memcmp(out, expected, 9));
  unsigned char back[9];
  Unshuffle(out, 9, 4, back);
  EXPECT_EQ(0, std::memcmp(back, in, 9));
}

TEST(ChunkFilters, EqualHdf5sOwnPipelineForEveryKindOfDataset) {
  std::mt19937_64 random(20261123);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  Handle complex_type = hdf5::ComplexType();
  Handle string_type = hdf5::FixedStringType(64);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Case> cases = {
      {"float64", H5T_IEEE_F64LE, 8, 1, true},      {"int64", H5T_STD_I64LE, 8, 1, true},
      {"int32", H5T_STD_I32LE, 4, 1, true},         {"int8", H5T_STD_I8LE, 1, 1, true},
      {"complex", complex_type.get(), 16, 5, true}, {"series", H5T_IEEE_F64LE, 8, 601, true},
      {"string", string_type.get(), 64, 1, false},
  };
  for (const Case& c : cases) {
    for (int level : {0, 1, 4, 9}) {
      for (hsize_t rows : {hsize_t{256}, hsize_t{200}}) {  // whole chunks; a partial last chunk
        const hsize_t chunk_rows = c.width > 100 ? 16 : 64;
        std::vector<unsigned char> data(rows * c.width * c.element_size);
        const std::size_t elements = rows * c.width;
        for (std::size_t e = 0; e < elements; ++e) {
          unsigned char* at = data.data() + e * c.element_size;
          if (c.element_size == 8 || c.element_size == 16) {
            // Smooth values with an occasional NaN: what the sweeps store.
            for (std::size_t k = 0; k < c.element_size / 8; ++k) {
              const double v =
                  e % 37 == 0 ? nan : std::sin(0.01 * static_cast<double>(e)) + 1e-3 * uniform(random);
              if (c.name == "int64") {
                const std::int64_t i = static_cast<std::int64_t>(e) * 3 - 7;
                std::memcpy(at, &i, 8);
              } else {
                std::memcpy(at + 8 * k, &v, 8);
              }
            }
          } else if (c.element_size == 4) {
            const std::int32_t v = static_cast<std::int32_t>(e % 5) - 1;
            std::memcpy(at, &v, 4);
          } else if (c.element_size == 1) {
            *at = static_cast<unsigned char>(e % 3);
          } else {
            std::memset(at, 0, c.element_size);
            if (e % 17 == 3)
              std::snprintf(reinterpret_cast<char*>(at), c.element_size, "run %zu failed: diverged", e);
          }
        }
        std::vector<unsigned char> fill;
        if (c.name == "float64" || c.name == "series") {
          fill.resize(8);
          std::memcpy(fill.data(), &nan, 8);
        } else if (c.name == "complex") {
          const double pair[2] = {nan, nan};
          fill.resize(16);
          std::memcpy(fill.data(), pair, 16);
        } else if (c.name == "int64") {
          const std::int64_t f = -1;
          fill.resize(8);
          std::memcpy(fill.data(), &f, 8);
        } else if (c.name == "int32") {
          const std::int32_t f = -1;
          fill.resize(4);
          std::memcpy(fill.data(), &f, 4);
        } else if (c.name == "int8") {
          fill.assign(1, 0);
        }
        ExpectSameChunks(c, level, data, rows, chunk_rows, fill);
      }
    }
  }
}

TEST(ChunkFilters, DeflateEqualsCompress2WithReusedDirtyBuffers) {
  // The oracle is zlib's own compress2 (what H5Zdeflate.c calls). One ChunkFilter is reused for
  // every input, so its zlib buffers hold what the previous, differently sized chunk left: sizes up
  // to past the 32 KiB window (the window slides), every level, random, sparse, few-valued and
  // run-length data.
  std::mt19937 random(20261124);
  ChunkFilter filter;
  int differing = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const std::size_t n = 1 + random() % 100000;
    const int level = 1 + static_cast<int>(random() % 9);
    std::vector<unsigned char> data(n);
    const int kind = static_cast<int>(random() % 4);
    unsigned char run = 0;
    for (auto& c : data) {
      if (kind == 0)
        c = static_cast<unsigned char>(random());
      else if (kind == 1)
        c = random() % 4 == 0 ? static_cast<unsigned char>(random()) : 0;
      else if (kind == 2)
        c = static_cast<unsigned char>(random() % 3);
      else
        c = run = random() % 8 == 0 ? static_cast<unsigned char>(random()) : run;
    }
    FilterPipeline pipeline;
    pipeline.deflate_level = level;
    pipeline.fletcher32 = false;
    std::vector<unsigned char> ours;
    filter.Apply(pipeline, data.data(), n, ours);
    std::vector<unsigned char> theirs(n + n / 100 + 64);
    uLongf size = theirs.size();
    ASSERT_EQ(compress2(theirs.data(), &size, data.data(), n, level), Z_OK);
    theirs.resize(size);
    differing += ours != theirs;
  }
  EXPECT_EQ(differing, 0);
}

TEST(ChunkFilters, IncompressibleDataEqualsHdf5) {
  // Random bytes: zlib falls back to stored blocks (the output is a few bytes longer than the
  // input, still inside HDF5's 1.001·n + 12 byte buffer); both pipelines must give the same bytes
  // and mask.
  std::mt19937_64 random(7);
  for (hsize_t rows : {hsize_t{3}, hsize_t{64}, hsize_t{4096}}) {
    std::vector<unsigned char> data(rows * 8);
    for (auto& b : data) b = static_cast<unsigned char>(random());
    const Case c{"random", H5T_STD_U64LE, 8, 1, true};
    ExpectSameChunks(c, 9, data, rows, rows, {});
  }
}

// libdeflate's streams ([output] deflate_encoder = "libdeflate") are not zlib's bytes, so the oracle is
// HDF5's own filter reading them back: each chunk is stored with H5Dwrite_chunk (and its mask) in a
// dataset of the same pipeline, and H5Dread must give the raw values, for smooth, few-valued and random
// (incompressible) data at levels 1, 4 and 9.
TEST(ChunkFilters, LibdeflateStreamsReadBackThroughHdf5sOwnFilter) {
  std::mt19937_64 random(20261204);
  const auto dir = TempDir("libdeflate");
  Handle file(H5Fcreate((dir / "ld.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create");
  constexpr hsize_t kRows = 4096, kChunkRows = 1024;
  int skipped = 0, deflated = 0;
  for (int kind = 0; kind < 3; ++kind) {
    std::vector<double> values(kRows);
    for (hsize_t i = 0; i < kRows; ++i) {
      const double smooth = std::sin(0.001 * static_cast<double>(i));
      values[i] = kind == 0   ? smooth
                  : kind == 1 ? static_cast<double>(i % 3)
                              : std::bit_cast<double>(random());
    }
    for (const int level : {1, 4, 9}) {
      SCOPED_TRACE("kind " + std::to_string(kind) + " level " + std::to_string(level));
      FilterPipeline pipeline;
      pipeline.element_size = 8;
      pipeline.shuffle = true;
      pipeline.deflate_level = level;
      pipeline.encoder = DeflateEncoder::kLibdeflate;
      const std::string name = "d" + std::to_string(kind) + "_" + std::to_string(level);
      hsize_t dims[1] = {kRows};
      Handle space(H5Screate_simple(1, dims, nullptr), "space");
      Handle dcpl = Creation(pipeline, kChunkRows, 1, H5T_IEEE_F64LE, nullptr);
      Handle dataset(H5Dcreate2(file.get(), name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                                dcpl.get(), H5P_DEFAULT),
                     "dset");
      ChunkFilter filter;
      for (hsize_t first = 0; first < kRows; first += kChunkRows) {
        const auto* raw = reinterpret_cast<const unsigned char*>(values.data() + first);
        std::vector<unsigned char> stored;
        const std::uint32_t mask = filter.Apply(pipeline, raw, kChunkRows * 8, stored);
        (mask & 2u ? skipped : deflated) += 1;
        std::vector<unsigned char> back;
        ASSERT_TRUE(filter.Reverse(pipeline, mask, stored.data(), stored.size(), kChunkRows * 8, back));
        ASSERT_EQ(std::memcmp(back.data(), raw, kChunkRows * 8), 0);
        const hsize_t offset[1] = {first};
        ASSERT_GE(H5Dwrite_chunk(dataset.get(), H5P_DEFAULT, mask, offset, stored.size(), stored.data()), 0);
      }
      std::vector<double> read(kRows);
      ASSERT_GE(H5Dread(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, read.data()), 0);
      EXPECT_EQ(std::memcmp(read.data(), values.data(), kRows * 8), 0);
    }
  }
  // Every chunk went through deflate: random bytes become stored blocks, which fit HDF5's buffer
  // (1.001 n + 12 bytes) as zlib's do, so the filter is never skipped here.
  EXPECT_EQ(deflated, 3 * 3 * static_cast<int>(kRows / kChunkRows));
  EXPECT_EQ(skipped, 0);
  std::filesystem::remove_all(dir);
}

// A whole sweep: each chunk the workers stored equals what HDF5 stores for the same values.
TEST(ChunkFilters, EveryChunkOfASweepEqualsHdf5sOwn) {
  const auto dir = TempDir("sweep");
  const auto study = dir / "s.toml";
  // Modes and a short open loop with series (2-D chunks of several rows), 7 × 23 = 161 runs in
  // batches of 32: the last batch is partial.
  std::ofstream(study) << "format_version = 1\nname = \"chunks\"\naircraft = \"" << kAircraft
                       << "\"\n[analyses.modes]\n[analyses.open_loop]\nduration_s = 2.0\nstep_s = 0.01\n"
                       << "[output]\nchunk_runs = 32\ntime_series = true\noutput_dt_s = 0.1\n"
                       << "[design]\nkind = \"grid\"\n[[design.parameter]]\nname = \"speed_mps\"\n"
                       << "linspace = [28.0, 40.0, 7]\n[[design.parameter]]\nname = \"height_m\"\n"
                       << "linspace = [0.8, 6.0, 23]\n";
  SweepPlan plan(LoadStudy(study), ShardSpec{});
  const auto archive = dir / "a.h5";
  {
    ArchiveOpenReport opened;
    auto writer =
        ArchiveWriter::Open(archive, plan, RunProvenance{"test", 2}, ArchiveOpenMode::kCreate, &opened);
    RunSweep(plan, opened.pending_blocks, *writer, RunnerOptions{2, nullptr, 2}, nullptr);
    writer->Finish();
  }
  const auto copy_path = dir / "hdf5.h5";
  Handle source_file(H5Fopen(archive.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open archive");
  Handle copy_file(H5Fcreate(copy_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create copy");
  const ArchiveLayout layout(plan);
  int chunks_compared = 0;
  for (const StoredDataset& stored : layout.datasets()) {
    SCOPED_TRACE(stored.path);
    Handle source(H5Dopen2(source_file.get(), stored.path.c_str(), H5P_DEFAULT), "open " + stored.path);
    Handle type(H5Dget_type(source.get()), "type");
    Handle space(H5Dget_space(source.get()), "space");
    Handle dcpl(H5Dget_create_plist(source.get()), "dcpl");
    const std::string name = std::to_string(&stored - layout.datasets().data());
    Handle target(H5Dcreate2(copy_file.get(), name.c_str(), type.get(), space.get(), H5P_DEFAULT, dcpl.get(),
                             H5P_DEFAULT),
                  "create copy");
    const auto dims = hdf5::Dimensions(source.get());
    std::size_t elements = 1;
    for (auto d : dims) elements *= static_cast<std::size_t>(d);
    std::vector<unsigned char> values(elements * H5Tget_size(type.get()));
    ASSERT_GE(H5Dread(source.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    ASSERT_GE(H5Dwrite(target.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    for (hsize_t row = 0; row < static_cast<hsize_t>(dims[0]);
         row += static_cast<hsize_t>(stored.chunk_rows)) {
      const hsize_t offset[2] = {row, 0};
      unsigned mask = 0;
      haddr_t address = HADDR_UNDEF;
      hsize_t size = 0;
      ASSERT_GE(H5Dget_chunk_info_by_coord(source.get(), offset, &mask, &address, &size), 0);
      if (address == HADDR_UNDEF) {
        EXPECT_EQ(stored.path, "runs/message");  // only message chunks without a message are not written
        continue;
      }
      std::vector<unsigned char> ours(size), theirs;
      std::uint32_t our_mask = 0, their_mask = 0;
      ASSERT_GE(H5Dread_chunk(source.get(), H5P_DEFAULT, offset, &our_mask, ours.data()), 0);
      hsize_t their_size = 0;
      ASSERT_GE(H5Dget_chunk_storage_size(target.get(), offset, &their_size), 0);
      theirs.resize(their_size);
      ASSERT_GE(H5Dread_chunk(target.get(), H5P_DEFAULT, offset, &their_mask, theirs.data()), 0);
      EXPECT_EQ(our_mask, their_mask) << "row " << row;
      EXPECT_EQ(ours, theirs) << "chunk at row " << row;
      ++chunks_compared;
    }
  }
  EXPECT_GT(chunks_compared, 100);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace gesweep::archive
