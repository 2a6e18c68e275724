// Fuzz target: opening and reading an archive (engine/archive ArchiveReader::Open and every reader
// built on it: the column catalogue, a query of every column, the status counts and attributes,
// the complete batches, the runs' models, the boundary extraction, a Sobol and a Morris analysis).
// The contract under test (docs/reliability.md): whatever the file holds, each of them returns or
// throws InputError (a bad archive: exit 2) or ArchiveError (an I/O failure: exit 1), with a one-line
// message; nothing else may escape, crash, hang, leak or trip a sanitizer.
//
// The input is a file in one of two ways, chosen by its first byte:
//  - even: the rest of the input is the file's bytes (truncated and mutated archives, random bytes);
//  - odd: the rest is a program that builds an HDF5 file through the HDF5 library, as another
//    program would (h5py, a script): a gesweep-like skeleton whose root attributes, groups, datasets
//    (names, types, ranks, shapes, values) and attributes are chosen by the bytes. libFuzzer cannot
//    see inside the (uninstrumented) HDF5 library, so raw bytes alone rarely get past its checks;
//    the builder reaches the engine's readers with well-formed HDF5 and hostile content.
#include <hdf5.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/archive/archive_reader.h"
#include "engine/archive/hdf5_util.h"
#include "engine/common/errors.h"
#include "engine/products/archive_boundary.h"
#include "engine/products/archive_sensitivity.h"
#include "engine/products/run_model.h"
#include "engine/query/query.h"
#include "engine/query/query_output.h"
#include "engine/query/run_columns.h"

namespace {

using gesweep::hdf5::Handle;

[[noreturn]] void Defect(const char* what, const std::string& detail) {
  std::fprintf(stderr, "archive fuzz defect: %s: %s\n", what, detail.c_str());
  std::abort();
}

void RequireOneLine(const char* kind, const std::string& message) {
  if (message.find('\n') != std::string::npos || message.find('\r') != std::string::npos) {
    Defect("multi-line message", std::string(kind) + ": " + message);
  }
}

// Reads the input front to back; past its end every read gives 0.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t Next() { return at_ < size_ ? data_[at_++] : 0; }
  bool Done() const { return at_ >= size_; }
  std::uint32_t Below(std::uint32_t n) { return n == 0 ? 0 : Next() % n; }
  std::string Text(std::size_t max_length) {
    std::string s;
    const std::size_t length = Below(static_cast<std::uint32_t>(max_length + 1));
    for (std::size_t i = 0; i < length; ++i) s.push_back(static_cast<char>(Next()));
    return s;
  }
  double Number() {
    static const double kInteresting[] = {0.0,     1.0,   -1.0, 0.5,   2.0,  1e-300, 1e300, -1e300,
                                          32.0208, 0.788, 5.0,  1e308, -0.0, 1e-9,   42.0,  3.0};
    const std::uint8_t kind = Next();
    if (kind < 128) return kInteresting[kind % (sizeof(kInteresting) / sizeof(double))];
    if (kind < 160) return std::nan("");
    if (kind < 176) return kind % 2 ? HUGE_VAL : -HUGE_VAL;
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits = bits << 8 | Next();
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

const char* const kNames[] = {"runs",
                              "design",
                              "results",
                              "series",
                              "analysis",
                              "modes",
                              "boundary",
                              "index",
                              "id",
                              "status",
                              "message",
                              "height_m",
                              "speed_mps",
                              "stability_margin_per_s",
                              "eigenvalues_per_s",
                              "open_loop",
                              "time_s",
                              "height_over_span",
                              "x1",
                              "x2",
                              "x3",
                              "value",
                              "sensitivity",
                              "landing",
                              "h_derivatives",
                              "scale.CLh",
                              "found",
                              "gain",
                              ".partial",
                              "a b",
                              "\xce\xb1"};

std::string Name(Bytes& in) {
  if (in.Below(16) == 0) {
    std::string raw = in.Text(8);
    for (char& c : raw) {
      if (c == '/' || c == '\0' || c == '.') c = '_';
    }
    return raw.empty() ? "x" : raw;
  }
  return kNames[in.Below(sizeof(kNames) / sizeof(kNames[0]))];
}

std::string Path(Bytes& in) {
  const int depth = 1 + static_cast<int>(in.Below(3));
  std::string path;
  for (int i = 0; i < depth; ++i) path += (i ? "/" : "") + Name(in);
  return path;
}

// Creates the groups above `path`; false when one of them is not a group.
bool Parents(hid_t file, const std::string& path) {
  std::size_t slash = 0;
  while ((slash = path.find('/', slash + 1)) != std::string::npos) {
    const std::string parent = path.substr(0, slash);
    const htri_t exists = H5Lexists(file, parent.c_str(), H5P_DEFAULT);
    if (exists < 0) return false;
    if (exists == 0) {
      Handle group(H5Gcreate2(file, parent.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      if (!group) return false;
    } else {
      H5O_info_t info{};
      if (H5Oget_info_by_name2(file, parent.c_str(), &info, H5O_INFO_BASIC, H5P_DEFAULT) < 0 ||
          info.type != H5O_TYPE_GROUP) {
        return false;
      }
    }
  }
  return true;
}

// A datatype of the kinds archives (and other programs) use.
Handle Type(Bytes& in) {
  switch (in.Below(9)) {
    case 0:
      return Handle(H5Tcopy(H5T_NATIVE_INT8));
    case 1:
      return Handle(H5Tcopy(H5T_NATIVE_INT32));
    case 2:
      return Handle(H5Tcopy(H5T_NATIVE_INT64));
    case 3:
      return Handle(H5Tcopy(H5T_NATIVE_UINT64));
    case 4:
      return Handle(H5Tcopy(H5T_NATIVE_FLOAT));
    case 5: {
      Handle type(H5Tcopy(H5T_C_S1));
      H5Tset_size(type.get(), 1 + in.Below(200));
      return type;
    }
    case 6: {
      Handle type(H5Tcopy(H5T_C_S1));
      H5Tset_size(type.get(), H5T_VARIABLE);
      return type;
    }
    case 7: {
      Handle type(H5Tcreate(H5T_COMPOUND, 2 * sizeof(double)));
      H5Tinsert(type.get(), in.Below(4) ? "re" : "real", 0, H5T_NATIVE_DOUBLE);
      H5Tinsert(type.get(), "im", sizeof(double), H5T_NATIVE_DOUBLE);
      return type;
    }
    default:
      return Handle(H5Tcopy(H5T_NATIVE_DOUBLE));
  }
}

// Fills a buffer for `count` elements of `type` from the input (variable-length strings: pointers
// to texts kept in `texts`).
std::vector<unsigned char> Values(Bytes& in, hid_t type, std::size_t count, std::vector<std::string>& texts) {
  const std::size_t size = H5Tget_size(type);
  std::vector<unsigned char> buffer(size * count);
  if (H5Tis_variable_str(type) > 0) {
    texts.clear();
    texts.reserve(count);
    for (std::size_t i = 0; i < count; ++i) texts.push_back(in.Text(40));
    auto* pointers = reinterpret_cast<const char**>(buffer.data());
    for (std::size_t i = 0; i < count; ++i) pointers[i] = texts[i].c_str();
    return buffer;
  }
  if (H5Tget_class(type) == H5T_FLOAT && size == sizeof(double)) {
    for (std::size_t i = 0; i < count; ++i) {
      const double v = in.Number();
      std::memcpy(buffer.data() + i * size, &v, size);
    }
    return buffer;
  }
  if (H5Tget_class(type) == H5T_COMPOUND) {
    for (std::size_t i = 0; i < 2 * count; ++i) {
      const double v = in.Number();
      std::memcpy(buffer.data() + i * sizeof(double), &v, sizeof(double));
    }
    return buffer;
  }
  for (auto& b : buffer) b = in.Next();
  return buffer;
}

void Attribute(Bytes& in, hid_t object) {
  static const char* const kAttributes[] = {
      "units",           "description",  "levels",       "fill",         "time_axis",   "parameters",
      "component_names", "method",       "keys",         "wingspan_m",   "tolerance_m", "block_rows",
      "block_layout",    "base_samples", "second_order", "levels_count", "run_count",   "format"};
  const std::string name = kAttributes[in.Below(sizeof(kAttributes) / sizeof(kAttributes[0]))];
  Handle type = Type(in);
  const bool scalar = in.Below(2) == 0;
  hsize_t dims[1] = {scalar ? 1 : in.Below(6)};
  Handle space(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, dims, nullptr));
  if (H5Aexists(object, name.c_str()) > 0) H5Adelete(object, name.c_str());
  Handle attribute(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute) return;
  std::vector<std::string> texts;
  const auto values = Values(in, type.get(), static_cast<std::size_t>(dims[0]), texts);
  if (!values.empty()) H5Awrite(attribute.get(), type.get(), values.data());
}

void StringAttribute(hid_t object, const char* name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  Handle space(H5Screate(H5S_SCALAR));
  Handle attribute(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  const char* pointer = value.c_str();
  if (attribute) H5Awrite(attribute.get(), type.get(), &pointer);
}

void IntegerAttribute(hid_t object, const char* name, std::int64_t value) {
  Handle space(H5Screate(H5S_SCALAR));
  Handle attribute(H5Acreate2(object, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (attribute) H5Awrite(attribute.get(), H5T_NATIVE_INT64, &value);
}

const char* kStudyTexts[] = {
    "format_version = 1\nname = \"f\"\naircraft = \"ance.toml\"\n[analyses.modes]\n[parameters]\nspeed_mps = "
    "32.0\n",
    "format_version = 1\n[analyses.ishigami]\n[design]\nkind = \"sobol\"\nbase_samples = "
    "4\n[[design.parameter]]\n"
    "name = \"x1\"\nuniform = [0.0, 1.0]\n",
    "not toml [[[",
    "",
};

// The odd mode: builds the file at `path` from the input as a program.
void BuildFile(Bytes& in, const std::string& path) {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS));
  H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
  Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
  if (!file) return;
  const std::uint8_t skeleton = in.Next();
  const std::int64_t runs = in.Below(10);
  if (skeleton & 1) StringAttribute(file.get(), "format", "gesweep-archive");
  if (skeleton & 2) IntegerAttribute(file.get(), "format_version", 1 + (skeleton & 64 ? 1 : 0));
  if (skeleton & 4) {
    IntegerAttribute(file.get(), "run_count", runs);
    IntegerAttribute(file.get(), "design_runs", runs + in.Below(3));
    IntegerAttribute(file.get(), "first_run", in.Below(2));
    IntegerAttribute(file.get(), "chunk_runs", static_cast<std::int64_t>(in.Below(5)) - 1);
  }
  if (skeleton & 8) {
    StringAttribute(file.get(), "study_text", kStudyTexts[in.Below(4)]);
    std::ifstream aircraft(std::string(GESWEEP_FUZZ_SOURCE_DIR) + "/studies/aircraft/ance.toml");
    std::stringstream text;
    text << aircraft.rdbuf();
    StringAttribute(file.get(), "aircraft_text", in.Below(4) ? text.str() : in.Text(30));
    StringAttribute(file.get(), "shard", in.Below(2) ? "0/1" : in.Text(5));
  }
  if (skeleton & 16) {
    // The usual per-run datasets, with run_count rows (or one more or one less).
    const char* const kRuns[] = {"runs/index", "runs/id", "runs/status", "runs/message"};
    const hid_t kTypes[] = {H5T_NATIVE_INT64, H5T_NATIVE_UINT64, H5T_NATIVE_INT8, H5T_NATIVE_DOUBLE};
    for (int k = 0; k < 4; ++k) {
      if (!Parents(file.get(), kRuns[k])) continue;
      hsize_t dims[1] = {static_cast<hsize_t>(runs + (in.Below(8) == 0 ? 1 : 0))};
      Handle space(H5Screate_simple(1, dims, nullptr));
      Handle type = k == 3 ? Handle(H5Tcopy(H5T_C_S1)) : Handle(H5Tcopy(kTypes[k]));
      if (k == 3) H5Tset_size(type.get(), 1 + in.Below(160));
      Handle dataset(
          H5Dcreate2(file.get(), kRuns[k], type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      std::vector<std::string> texts;
      const auto values = Values(in, type.get(), static_cast<std::size_t>(dims[0]), texts);
      if (dataset && !values.empty()) {
        H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
      }
    }
    Handle design(H5Gcreate2(file.get(), "design", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  }
  // Then any number of operations.
  int operations = 0;
  while (!in.Done() && operations++ < 48) {
    const std::uint8_t op = in.Below(4);
    const std::string target = Path(in);
    if (op == 0) {
      if (Parents(file.get(), target + "/x")) {
        Handle group(H5Oopen(file.get(), target.c_str(), H5P_DEFAULT));
        if (group) Attribute(in, group.get());
      }
      continue;
    }
    if (op == 1) {  // an attribute on the root
      Attribute(in, file.get());
      continue;
    }
    if (!Parents(file.get(), target) || H5Lexists(file.get(), target.c_str(), H5P_DEFAULT) != 0) {
      H5Eclear2(H5E_DEFAULT);
      continue;
    }
    Handle type = Type(in);
    const int rank = static_cast<int>(in.Below(4));
    hsize_t dims[3];
    std::size_t count = 1;
    for (int d = 0; d < rank; ++d) {
      dims[d] = in.Below(3) == 0 ? static_cast<hsize_t>(runs) : in.Below(9);
      count *= static_cast<std::size_t>(dims[d]);
    }
    Handle space(rank == 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(rank, dims, nullptr));
    Handle dataset(H5Dcreate2(file.get(), target.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT,
                              H5P_DEFAULT));
    if (!dataset) continue;
    std::vector<std::string> texts;
    const auto values = Values(in, type.get(), count, texts);
    if (!values.empty()) H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    while (!in.Done() && in.Below(3) == 0) Attribute(in, dataset.get());
  }
  H5Eclear2(H5E_DEFAULT);
}

// Everything the CLI does with an archive it reads (and nothing that writes).
void Exercise(const std::string& path) {
  using namespace gesweep;
  ArchiveReader archive = ArchiveReader::Open(path);
  (void)CountStatuses(archive, 4);
  (void)ReadAttributes(archive, "/");
  const ColumnCatalog catalog = ColumnCatalog::Of(archive);
  std::ostringstream out;
  {
    QueryRequest request;
    for (const RunColumn& column : catalog.columns()) request.columns.push_back(column.path);
    request.chunk_rows = 3;  // several chunks even of a small archive
    const auto writer = MakeQueryWriter(QueryFormat::kJson, out, path);
    (void)RunQuery(archive, catalog, request, *writer);
  }
  for (int chunk : {1, 3, 64}) (void)archive.CompleteBlocks(chunk);
  try {
    ArchiveRunModels models = ArchiveRunModels::Of(archive);
    BoundaryExtractionOptions options;
    (void)ExtractBoundary(archive, catalog, models, options);
  } catch (const InputError& e) {
    RequireOneLine("InputError", e.what());
  }
  for (const char* output : {"value", "results/ishigami/value", "stability_margin_per_s"}) {
    try {
      ArchiveSensitivityOptions options;
      options.bootstrap.resamples = 20;
      (void)AnalyzeArchiveOutput(archive, output, options);
    } catch (const InputError& e) {
      RequireOneLine("InputError", e.what());
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  gesweep::hdf5::Quiet();
  // libhdf5 keeps freed blocks on free lists and hands them out again: a block it leaks (see
  // tests/fuzz/hdf5_lsan.supp) would then be reported with the stack of whatever input first
  // allocated it, and only when a later input mallocs more than it frees -- leaks no input
  // reproduces alone (fuzz_archive's first runs: 19 of them). Limits of zero give every freed block
  // back at once, so a leak shows its own input and its own stack.
  static const bool no_free_lists = (H5set_free_list_limits(0, 0, 0, 0, 0, 0), true);
  (void)no_free_lists;
  // GESWEEP_FUZZ_ARCHIVE_OUT keeps the file an input made (a builder program's HDF5 file), to turn a
  // crash into a regression case the real binary can read (tests/bad_inputs/archive_fuzz_regressions);
  // otherwise the file is removed after each input (one per fork-mode worker would fill /dev/shm).
  static const char* const kept = std::getenv("GESWEEP_FUZZ_ARCHIVE_OUT");
  static const std::string path = kept != nullptr
                                      ? std::string(kept)
                                      : "/dev/shm/gesweep_fuzz_archive_" + std::to_string(::getpid()) + ".h5";
  if (size == 0) return 0;
  struct Remove {
    bool keep;
    ~Remove() {
      if (!keep) std::remove(path.c_str());
    }
  } remove_after{kept != nullptr};
  if (data[0] % 2 == 0) {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  } else {
    Bytes in(data + 1, size - 1);
    BuildFile(in, path);
  }
  try {
    Exercise(path);
  } catch (const gesweep::InputError& e) {
    RequireOneLine("InputError", e.what());
  } catch (const gesweep::ArchiveError& e) {
    RequireOneLine("ArchiveError", e.what());
  } catch (const std::exception& e) {
    Defect("unexpected exception", e.what());
  }
  H5Eclear2(H5E_DEFAULT);
  return 0;
}
