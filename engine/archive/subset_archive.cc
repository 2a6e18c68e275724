#include "engine/archive/subset_archive.h"

#include <fstream>
#include <set>

#include "engine/archive/archive_probe.h"
#include "engine/archive/hdf5_util.h"
#include "engine/archive/product_fields.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"

namespace gesweep::risk {
namespace {

using hdf5::Check;
using hdf5::Handle;

// The layout of the archive (product::subset_archive, generated from schemas/products.json): the
// writer and the reader below name every field through it.
namespace root_attribute = product::subset_archive::attribute;
namespace evaluations_layout = product::subset_archive::evaluations;
namespace design_points_layout = product::subset_archive::design_points;
namespace design_point_layout = product::subset_archive::design_points::design_point;
namespace series_layout = product::subset_archive::design_points::design_point::series;

std::string NameOf(const ProductField& field) { return std::string(field.name); }

template <class T>
hid_t NativeType();
template <>
hid_t NativeType<double>() {
  return H5T_NATIVE_DOUBLE;
}
template <>
hid_t NativeType<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t NativeType<std::int8_t>() {
  return H5T_NATIVE_INT8;
}

template <class T>
void WriteVector(hid_t group, const std::string& name, const std::vector<T>& values,
                 std::int64_t columns = 1) {
  const hsize_t rows =
      static_cast<hsize_t>(columns > 1 ? values.size() / static_cast<std::size_t>(columns) : values.size());
  const hsize_t dims[2] = {rows, static_cast<hsize_t>(columns)};
  Handle space(H5Screate_simple(columns > 1 ? 2 : 1, dims, nullptr), "dataspace " + name);
  Handle properties(H5Pcreate(H5P_DATASET_CREATE), "properties " + name);
  if (rows > 0) {
    const hsize_t chunk[2] = {std::min<hsize_t>(rows, columns > 1 ? 1024 : 65536),
                              static_cast<hsize_t>(columns)};
    Check(H5Pset_chunk(properties.get(), columns > 1 ? 2 : 1, chunk), "chunk " + name);
    Check(H5Pset_deflate(properties.get(), 1), "deflate " + name);
  }
  Handle set(H5Dcreate2(group, name.c_str(), NativeType<T>(), space.get(), H5P_DEFAULT, properties.get(),
                        H5P_DEFAULT),
             "create " + name);
  if (!values.empty()) {
    Check(H5Dwrite(set.get(), NativeType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "write " + name);
  }
  set.Close("close " + name);
}

template <class T>
std::vector<T> ReadVector(hid_t group, const std::string& name, std::vector<std::int64_t>* dims = nullptr) {
  Handle set(H5Dopen2(group, name.c_str(), H5P_DEFAULT), "open " + name);
  const std::vector<std::int64_t> d = hdf5::Dimensions(set.get());
  std::int64_t count = 1;
  for (const auto v : d) count *= v;
  std::vector<T> values(static_cast<std::size_t>(count));
  if (count > 0) {
    Check(H5Dread(set.get(), NativeType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), "read " + name);
  }
  if (dims != nullptr) *dims = d;
  return values;
}

Handle CreateGroup(hid_t parent, const std::string& name) {
  return Handle(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                "create group " + name);
}
Handle OpenGroup(hid_t parent, const std::string& name) {
  return Handle(H5Gopen2(parent, name.c_str(), H5P_DEFAULT), "open group " + name);
}

std::string DesignPointName(std::int64_t cell, int limit) {
  return "cell_" + std::to_string(cell) + "_limit_" + std::to_string(limit);
}

void WriteDesignPoint(hid_t parent, const DesignPoint& point) {
  Handle group = CreateGroup(parent, DesignPointName(point.cell, point.limit));
  hdf5::WriteAttribute(group.get(), NameOf(design_point_layout::attribute::kCell),
                       static_cast<std::int64_t>(point.cell));
  hdf5::WriteAttribute(group.get(), NameOf(design_point_layout::attribute::kLimit),
                       static_cast<std::int64_t>(point.limit));
  hdf5::WriteAttribute(group.get(), NameOf(design_point_layout::attribute::kSampleIntervalS),
                       point.sample_interval_s);
  hdf5::WriteAttribute(
      group.get(), NameOf(design_point_layout::attribute::kNoiseLayout),
      "u[0..2]: initial filter states; u[3 + 2k]: u-stream sample k; u[3 + 2k + 1]: w-stream "
      "sample k, held on [k dt, (k + 1) dt) (engine/disturbance/run_noise.h)");
  WriteVector(group.get(), NameOf(design_point_layout::dataset::kMeanNoise), point.mean_noise);
  WriteVector(group.get(), NameOf(design_point_layout::dataset::kMostLikelyNoise), point.most_likely_noise);
  for (const auto& series : point.series) {
    Handle s = CreateGroup(group.get(), series.name);
    WriteVector(s.get(), NameOf(series_layout::dataset::kTimeS), series.time_s);
    for (std::size_t c = 0; c < series.columns.size(); ++c) {
      WriteVector(s.get(), series.columns[c], series.values[c]);
      Handle set(H5Dopen2(s.get(), series.columns[c].c_str(), H5P_DEFAULT), "open " + series.columns[c]);
      hdf5::WriteAttribute(set.get(), "units", series.units[c]);
    }
  }
}

[[noreturn]] void Refuse(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string(), "", "", "a subset-simulation archive of gesweep: " + what);
}

// The root's study, command line, estimates and spec fingerprint.
RiskArchive ReadRootAttributes(hid_t file, const std::filesystem::path& path) {
  RiskArchive a;
  a.study_path = hdf5::ReadStringAttribute(file, NameOf(root_attribute::kStudyPath)).value_or("");
  a.study_text = hdf5::ReadStringAttribute(file, NameOf(root_attribute::kStudyText)).value_or("");
  a.command_line = hdf5::ReadStringAttribute(file, NameOf(root_attribute::kCommandLine)).value_or("");
  a.result_json = hdf5::ReadStringAttribute(file, NameOf(root_attribute::kResultJson)).value_or("");
  const std::string fingerprint =
      hdf5::ReadStringAttribute(file, NameOf(root_attribute::kSpecFingerprint)).value_or("");
  char* end = nullptr;
  a.fingerprint = std::strtoull(fingerprint.c_str(), &end, 16);
  if (fingerprint.size() != 16 || end != fingerprint.c_str() + 16)
    Refuse(path, "a 16-digit spec_fingerprint");
  if (a.study_text.empty() || a.result_json.empty()) Refuse(path, "its study_text and result_json");

  return a;
}

// /subset/evaluations: every landing's tag, status, g, values and message, checked as read.
void ReadEvaluations(hid_t file, const std::filesystem::path& path, std::int64_t version, RiskArchive& a) {
  Handle evaluations = OpenGroup(file, evaluations_layout::kPath);
  const auto cell = ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kCell));
  const auto limit = ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kLimit));
  // Version 1 had no repetitions: every landing is repetition 0's.
  const auto repetition =
      version >= 2
          ? ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kRepetition))
          : std::vector<std::int32_t>(cell.size(), 0);
  const auto level = ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kLevel));
  const auto chain = ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kChain));
  const auto step = ReadVector<std::int32_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kStep));
  const auto status =
      ReadVector<std::int8_t>(evaluations.get(), NameOf(evaluations_layout::dataset::kStatus));
  const auto g = ReadVector<double>(evaluations.get(), NameOf(evaluations_layout::dataset::kG));
  std::vector<std::int64_t> dims;
  const auto values =
      ReadVector<double>(evaluations.get(), NameOf(evaluations_layout::dataset::kValues), &dims);
  a.value_columns =
      hdf5::ReadStringListAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kColumns));
  const std::size_t n = cell.size();
  for (const std::size_t size :
       {limit.size(), repetition.size(), level.size(), chain.size(), step.size(), status.size(), g.size()}) {
    if (size != n) Refuse(path, "evaluation columns of one length (" + std::to_string(n) + ")");
  }
  const auto k = static_cast<std::int64_t>(a.value_columns.size());
  if (!(dims.size() == 2 && dims[0] == static_cast<std::int64_t>(n) && dims[1] == k) &&
      !(n == 0 && values.empty())) {
    Refuse(path, "a values matrix of " + std::to_string(n) + " rows and " + std::to_string(k) + " columns");
  }
  const auto message_rows =
      hdf5::ReadIntegerListAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kMessageRows));
  const auto messages =
      hdf5::ReadStringListAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kMessages));
  if (message_rows.size() != messages.size()) Refuse(path, "one message per message row");
  std::set<EvaluationKey> seen;
  a.evaluations.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Evaluation& e = a.evaluations[i];
    e.key = EvaluationKey{cell[i], limit[i], repetition[i], level[i], chain[i], step[i]};
    if (cell[i] < 0 || limit[i] < 0 || repetition[i] < 0 || level[i] < 1 || chain[i] < 0 || step[i] < 0) {
      Refuse(path, "tags in range (row " + std::to_string(i) + ")");
    }
    if (status[i] != static_cast<std::int8_t>(RunStatus::kOk) &&
        status[i] != static_cast<std::int8_t>(RunStatus::kFailed)) {
      Refuse(path, "statuses ok or failed (row " + std::to_string(i) + ")");
    }
    if (!seen.insert(e.key).second)
      Refuse(path, "each landing once (row " + std::to_string(i) + " repeats a tag)");
    e.status = status[i];
    e.g = g[i];
    e.values.assign(values.begin() + static_cast<std::ptrdiff_t>(i) * k,
                    values.begin() + static_cast<std::ptrdiff_t>(i + 1) * k);
  }
  for (std::size_t m = 0; m < message_rows.size(); ++m) {
    if (message_rows[m] < 0 || message_rows[m] >= static_cast<std::int64_t>(n))
      Refuse(path, "message rows in range");
    a.evaluations[static_cast<std::size_t>(message_rows[m])].message = messages[m];
  }
}

// /subset/design_points, when the archive has them.
std::vector<DesignPoint> ReadDesignPoints(hid_t file) {
  std::vector<DesignPoint> design_points;
  if (hdf5::Exists(file, design_points_layout::kPath)) {
    Handle points = OpenGroup(file, design_points_layout::kPath);
    const auto names =
        hdf5::ReadStringListAttribute(points.get(), NameOf(design_points_layout::attribute::kNames));
    for (const auto& name : names) {
      Handle group = OpenGroup(points.get(), name);
      DesignPoint point;
      point.cell =
          hdf5::ReadIntegerAttribute(group.get(), NameOf(design_point_layout::attribute::kCell)).value_or(-1);
      point.limit = static_cast<int>(
          hdf5::ReadIntegerAttribute(group.get(), NameOf(design_point_layout::attribute::kLimit))
              .value_or(-1));
      point.sample_interval_s =
          hdf5::ReadDoubleAttribute(group.get(), NameOf(design_point_layout::attribute::kSampleIntervalS))
              .value_or(0);
      point.mean_noise = ReadVector<double>(group.get(), NameOf(design_point_layout::dataset::kMeanNoise));
      point.most_likely_noise =
          ReadVector<double>(group.get(), NameOf(design_point_layout::dataset::kMostLikelyNoise));
      design_points.push_back(std::move(point));
    }
  }
  return design_points;
}

RiskArchive ReadUnguarded(const std::filesystem::path& path, bool with_design_points) {
  hdf5::Quiet();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, hdf5::FileAccess().get()), "open " + path.string());
  const auto kind = hdf5::ReadStringAttribute(file.get(), NameOf(root_attribute::kGesweepArchiveKind));
  if (!kind || *kind != kRiskArchiveKind)
    Refuse(path, "its root has no gesweep_archive_kind = subset_simulation");
  const auto version = hdf5::ReadIntegerAttribute(file.get(), NameOf(root_attribute::kFormatVersion));
  if (!version || (*version != 1 && *version != kRiskArchiveVersion)) {
    Refuse(path, "format_version 1 or " + std::to_string(kRiskArchiveVersion) + " (this engine's)");
  }
  RiskArchive a = ReadRootAttributes(file.get(), path);
  ReadEvaluations(file.get(), path, *version, a);
  if (with_design_points) a.design_points = ReadDesignPoints(file.get());
  file.Close("close " + path.string());
  return a;
}

}  // namespace

void WriteRiskArchive(const std::filesystem::path& path, const RiskArchive& a) {
  hdf5::Quiet();
  const std::filesystem::path partial(path.string() + ".partial");
  std::filesystem::remove(partial);
  {
    Handle file(H5Fcreate(partial.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, hdf5::FileAccess().get()),
                "create " + partial.string());
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kGesweepArchiveKind), kRiskArchiveKind);
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kFormatVersion),
                         static_cast<std::int64_t>(kRiskArchiveVersion));
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kStudyPath), a.study_path);
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kStudyText), a.study_text);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(a.fingerprint));
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kSpecFingerprint), std::string(hex));
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kCommandLine), a.command_line);
    hdf5::WriteAttribute(file.get(), NameOf(root_attribute::kResultJson), a.result_json);
    Handle subset = CreateGroup(file.get(), "subset");
    Handle evaluations = CreateGroup(subset.get(), "evaluations");
    const std::size_t n = a.evaluations.size();
    std::vector<std::int32_t> cell(n), limit(n), repetition(n), level(n), chain(n), step(n);
    std::vector<std::int8_t> status(n);
    std::vector<double> g(n), values;
    std::vector<std::int64_t> message_rows;
    std::vector<std::string> messages;
    values.reserve(n * a.value_columns.size());
    for (std::size_t i = 0; i < n; ++i) {
      const Evaluation& e = a.evaluations[i];
      cell[i] = e.key.cell;
      limit[i] = e.key.limit;
      repetition[i] = e.key.repetition;
      level[i] = e.key.level;
      chain[i] = e.key.chain;
      step[i] = e.key.step;
      status[i] = e.status;
      g[i] = e.g;
      GESWEEP_DEMAND(e.values.size() == a.value_columns.size());
      values.insert(values.end(), e.values.begin(), e.values.end());
      if (!e.message.empty()) {
        message_rows.push_back(static_cast<std::int64_t>(i));
        messages.push_back(e.message);
      }
    }
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kCell), cell);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kLimit), limit);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kRepetition), repetition);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kLevel), level);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kChain), chain);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kStep), step);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kStatus), status);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kG), g);
    WriteVector(evaluations.get(), NameOf(evaluations_layout::dataset::kValues), values,
                std::max<std::int64_t>(1, static_cast<std::int64_t>(a.value_columns.size())));
    hdf5::WriteAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kColumns), a.value_columns);
    hdf5::WriteAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kMessageRows),
                         message_rows);
    hdf5::WriteAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kMessages), messages);
    hdf5::WriteAttribute(evaluations.get(), NameOf(evaluations_layout::attribute::kStatusLevels),
                         RunStatusLevels());
    Handle points = CreateGroup(subset.get(), "design_points");
    std::vector<std::string> names;
    for (const auto& point : a.design_points) {
      WriteDesignPoint(points.get(), point);
      names.push_back(DesignPointName(point.cell, point.limit));
    }
    hdf5::WriteAttribute(points.get(), NameOf(design_points_layout::attribute::kNames), names);
    file.Close("close " + partial.string());
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error)
    throw ArchiveError("rename " + partial.string() + " to " + path.string() + ": " + error.message());
}

bool IsRiskArchive(const std::filesystem::path& path) {
  // Only a regular file is read: opening a FIFO or a device would block, or read what it streams.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  char signature[8] = {};
  if (!in.read(signature, 8) || std::memcmp(signature, "\x89HDF\r\n\x1a\n", 8) != 0) return false;
  const auto check = [&] {
    hdf5::Quiet();
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, hdf5::FileAccess().get());
    if (file < 0) return false;
    bool is = false;
    if (H5Aexists(file, NameOf(root_attribute::kGesweepArchiveKind).c_str()) > 0) {
      try {
        is = hdf5::ReadStringAttribute(file, NameOf(root_attribute::kGesweepArchiveKind)).value_or("") ==
             kRiskArchiveKind;
      } catch (const std::exception&) {
        is = false;
      }
    }
    H5Fclose(file);
    return is;
  };
  try {
    archive::GuardArchiveDecode(path.string(), [&] { (void)check(); });
  } catch (const std::exception&) {
    return false;  // a damaged file: whoever opens it next says so
  }
  return check();
}

RiskArchive ReadRiskArchive(const std::filesystem::path& path, bool with_design_points) {
  archive::GuardArchiveDecode(path.string(), [&] { (void)ReadUnguarded(path, with_design_points); });
  return ReadUnguarded(path, with_design_points);
}

}  // namespace gesweep::risk
