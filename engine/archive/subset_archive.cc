#include "engine/archive/subset_archive.h"

#include <fstream>
#include <set>

#include "engine/archive/analysis_product.h"
#include "engine/archive/archive_probe.h"
#include "engine/archive/hdf5_util.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"

namespace gesweep::risk {
namespace {

using hdf5::Check;
using hdf5::Handle;

// The layout of the archive (SubsetArchiveLayout), each field described once; the writer and the
// reader below name them through these.
constexpr ProductField kKindAttribute{
    "gesweep_archive_kind", "string", "", "",
    "subset_simulation (a sweep archive has format = gesweep-archive instead)"};
constexpr ProductField kVersionAttribute{"format_version", "int64", "", "",
                                         "2 (version 1 has no repetition column: every repetition 0)"};
constexpr ProductField kStudyPath{"study_path", "string", "", "", "The study file as run"};
constexpr ProductField kStudyText{"study_text", "string", "", "",
                                  "Its text (a replay reads it, not the file)"};
constexpr ProductField kFingerprint{"spec_fingerprint", "string", "", "",
                                    "Hash of the study as the engine read it, 16 hexadecimal digits"};
constexpr ProductField kResultJson{"result_json", "string", "", "",
                                   "The estimates, as `gesweep dispersion` prints them in JSON "
                                   "(less the archive key)"};
constexpr ProductField kCell{"cell", "int32", "1", "evaluation", "Tag: the cell of the study"};
constexpr ProductField kLimit{"limit", "int32", "1", "evaluation", "Tag: the limit's index within its cell"};
constexpr ProductField kRepetition{"repetition", "int32", "1", "evaluation",
                                   "Tag: the independent repetition"};
constexpr ProductField kLevel{"level", "int32", "1", "evaluation", "Tag: the level (1: Monte Carlo)"};
constexpr ProductField kChain{"chain", "int32", "1", "evaluation",
                              "Tag: the chain (the sample index on level 1)"};
constexpr ProductField kStep{"step", "int32", "1", "evaluation", "Tag: the step along the chain"};
constexpr ProductField kStatus{
    "status", "int8", "1", "evaluation",
    "The run status of /runs/status (ok or failed: a pending landing is never stored)"};
constexpr ProductField kG{"g", "float64", "1", "evaluation",
                          "The limit state (failure g <= 0); NaN for a failed landing"};
constexpr ProductField kValues{"values", "float64", "see columns", "evaluation, column",
                               "The landing's scalar result columns (attribute columns)"};
constexpr ProductField kColumns{"columns", "list of string", "", "column",
                                "The archive paths of the columns of values (results/landing/...)"};
constexpr ProductField kMessageRows{"message_rows", "list of int64", "", "message",
                                    "The rows that have a message"};
constexpr ProductField kMessages{"messages", "list of string", "", "message", "Their messages"};
constexpr ProductField kStatusLevels{"status_levels", "list of string", "", "",
                                     "The run statuses by code (RunStatus's names)"};
constexpr ProductField kPointNames{"names", "list of string", "", "", "The design points' groups"};
constexpr ProductField kPointCell{"cell", "int64", "", "", "Its cell"};
constexpr ProductField kPointLimit{"limit", "int64", "", "", "Its limit's index within the cell"};
constexpr ProductField kSampleInterval{"sample_interval_s", "float64", "", "",
                                       "The held noise's interval, s"};
constexpr ProductField kNoiseLayout{"noise_layout", "string", "", "", "Where each noise coordinate goes"};
constexpr ProductField kMeanNoise{"mean_noise", "float64", "1", "noise", "The failing runs' mean point"};
constexpr ProductField kMostLikelyNoise{"most_likely_noise", "float64", "1", "noise",
                                        "The most likely failing point"};
constexpr ProductField kSeriesTime{"time_s", "float64", "s", "sample", "The series' time axis"};
constexpr ProductField kSeriesColumn{"<column>", "float64", "<its units>", "sample",
                                     "A landing series column (attribute units)"};
// The groups.
constexpr const char* kEvaluationsGroup = "subset/evaluations";
constexpr const char* kDesignPointsGroup = "subset/design_points";

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
  hdf5::WriteAttribute(group.get(), NameOf(kPointCell), static_cast<std::int64_t>(point.cell));
  hdf5::WriteAttribute(group.get(), NameOf(kPointLimit), static_cast<std::int64_t>(point.limit));
  hdf5::WriteAttribute(group.get(), NameOf(kSampleInterval), point.sample_interval_s);
  hdf5::WriteAttribute(
      group.get(), NameOf(kNoiseLayout),
      "u[0..2]: initial filter states; u[3 + 2k]: u-stream sample k; u[3 + 2k + 1]: w-stream "
      "sample k, held on [k dt, (k + 1) dt) (engine/disturbance/run_noise.h)");
  WriteVector(group.get(), NameOf(kMeanNoise), point.mean_noise);
  WriteVector(group.get(), NameOf(kMostLikelyNoise), point.most_likely_noise);
  for (const auto& series : point.series) {
    Handle s = CreateGroup(group.get(), series.name);
    WriteVector(s.get(), NameOf(kSeriesTime), series.time_s);
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
  a.study_path = hdf5::ReadStringAttribute(file, NameOf(kStudyPath)).value_or("");
  a.study_text = hdf5::ReadStringAttribute(file, NameOf(kStudyText)).value_or("");
  a.command_line = hdf5::ReadStringAttribute(file, NameOf(kCommandLine)).value_or("");
  a.result_json = hdf5::ReadStringAttribute(file, NameOf(kResultJson)).value_or("");
  const std::string fingerprint = hdf5::ReadStringAttribute(file, NameOf(kFingerprint)).value_or("");
  char* end = nullptr;
  a.fingerprint = std::strtoull(fingerprint.c_str(), &end, 16);
  if (fingerprint.size() != 16 || end != fingerprint.c_str() + 16)
    Refuse(path, "a 16-digit spec_fingerprint");
  if (a.study_text.empty() || a.result_json.empty()) Refuse(path, "its study_text and result_json");

  return a;
}

// /subset/evaluations: every landing's tag, status, g, values and message, checked as read.
void ReadEvaluations(hid_t file, const std::filesystem::path& path, std::int64_t version, RiskArchive& a) {
  Handle evaluations = OpenGroup(file, kEvaluationsGroup);
  const auto cell = ReadVector<std::int32_t>(evaluations.get(), NameOf(kCell));
  const auto limit = ReadVector<std::int32_t>(evaluations.get(), NameOf(kLimit));
  // Version 1 had no repetitions: every landing is repetition 0's.
  const auto repetition = version >= 2 ? ReadVector<std::int32_t>(evaluations.get(), NameOf(kRepetition))
                                       : std::vector<std::int32_t>(cell.size(), 0);
  const auto level = ReadVector<std::int32_t>(evaluations.get(), NameOf(kLevel));
  const auto chain = ReadVector<std::int32_t>(evaluations.get(), NameOf(kChain));
  const auto step = ReadVector<std::int32_t>(evaluations.get(), NameOf(kStep));
  const auto status = ReadVector<std::int8_t>(evaluations.get(), NameOf(kStatus));
  const auto g = ReadVector<double>(evaluations.get(), NameOf(kG));
  std::vector<std::int64_t> dims;
  const auto values = ReadVector<double>(evaluations.get(), NameOf(kValues), &dims);
  a.value_columns = hdf5::ReadStringListAttribute(evaluations.get(), NameOf(kColumns));
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
  const auto message_rows = hdf5::ReadIntegerListAttribute(evaluations.get(), NameOf(kMessageRows));
  const auto messages = hdf5::ReadStringListAttribute(evaluations.get(), NameOf(kMessages));
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
  if (hdf5::Exists(file, kDesignPointsGroup)) {
    Handle points = OpenGroup(file, kDesignPointsGroup);
    const auto names = hdf5::ReadStringListAttribute(points.get(), NameOf(kPointNames));
    for (const auto& name : names) {
      Handle group = OpenGroup(points.get(), name);
      DesignPoint point;
      point.cell = hdf5::ReadIntegerAttribute(group.get(), NameOf(kPointCell)).value_or(-1);
      point.limit =
          static_cast<int>(hdf5::ReadIntegerAttribute(group.get(), NameOf(kPointLimit)).value_or(-1));
      point.sample_interval_s = hdf5::ReadDoubleAttribute(group.get(), NameOf(kSampleInterval)).value_or(0);
      point.mean_noise = ReadVector<double>(group.get(), NameOf(kMeanNoise));
      point.most_likely_noise = ReadVector<double>(group.get(), NameOf(kMostLikelyNoise));
      design_points.push_back(std::move(point));
    }
  }
  return design_points;
}

RiskArchive ReadUnguarded(const std::filesystem::path& path, bool with_design_points) {
  hdf5::Quiet();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, hdf5::FileAccess().get()), "open " + path.string());
  const auto kind = hdf5::ReadStringAttribute(file.get(), NameOf(kKindAttribute));
  if (!kind || *kind != kRiskArchiveKind)
    Refuse(path, "its root has no gesweep_archive_kind = subset_simulation");
  const auto version = hdf5::ReadIntegerAttribute(file.get(), NameOf(kVersionAttribute));
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
    hdf5::WriteAttribute(file.get(), NameOf(kKindAttribute), kRiskArchiveKind);
    hdf5::WriteAttribute(file.get(), NameOf(kVersionAttribute),
                         static_cast<std::int64_t>(kRiskArchiveVersion));
    hdf5::WriteAttribute(file.get(), NameOf(kStudyPath), a.study_path);
    hdf5::WriteAttribute(file.get(), NameOf(kStudyText), a.study_text);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(a.fingerprint));
    hdf5::WriteAttribute(file.get(), NameOf(kFingerprint), std::string(hex));
    hdf5::WriteAttribute(file.get(), NameOf(kCommandLine), a.command_line);
    hdf5::WriteAttribute(file.get(), NameOf(kResultJson), a.result_json);
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
    WriteVector(evaluations.get(), NameOf(kCell), cell);
    WriteVector(evaluations.get(), NameOf(kLimit), limit);
    WriteVector(evaluations.get(), NameOf(kRepetition), repetition);
    WriteVector(evaluations.get(), NameOf(kLevel), level);
    WriteVector(evaluations.get(), NameOf(kChain), chain);
    WriteVector(evaluations.get(), NameOf(kStep), step);
    WriteVector(evaluations.get(), NameOf(kStatus), status);
    WriteVector(evaluations.get(), NameOf(kG), g);
    WriteVector(evaluations.get(), NameOf(kValues), values,
                std::max<std::int64_t>(1, static_cast<std::int64_t>(a.value_columns.size())));
    hdf5::WriteAttribute(evaluations.get(), NameOf(kColumns), a.value_columns);
    hdf5::WriteAttribute(evaluations.get(), NameOf(kMessageRows), message_rows);
    hdf5::WriteAttribute(evaluations.get(), NameOf(kMessages), messages);
    hdf5::WriteAttribute(evaluations.get(), NameOf(kStatusLevels), RunStatusLevels());
    Handle points = CreateGroup(subset.get(), "design_points");
    std::vector<std::string> names;
    for (const auto& point : a.design_points) {
      WriteDesignPoint(points.get(), point);
      names.push_back(DesignPointName(point.cell, point.limit));
    }
    hdf5::WriteAttribute(points.get(), NameOf(kPointNames), names);
    file.Close("close " + partial.string());
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error)
    throw ArchiveError("rename " + partial.string() + " to " + path.string() + ": " + error.message());
}

const ProductLayout& SubsetArchiveLayout() {
  static const ProductLayout layout{
      "subset_archive",
      "",
      "gesweep risk",
      "The archive of a subset simulation: the study, every evaluation and the design points",
      {kKindAttribute, kVersionAttribute, kStudyPath, kStudyText, kFingerprint, kCommandLine, kResultJson},
      {},
      {{"evaluations",
        kEvaluationsGroup,
        "gesweep risk",
        "Every landing: its tag, status, limit state and result columns, in evaluation order",
        {kColumns, kMessageRows, kMessages, kStatusLevels},
        {kCell, kLimit, kRepetition, kLevel, kChain, kStep, kStatus, kG, kValues},
        {}},
       {"design_points",
        kDesignPointsGroup,
        "gesweep risk",
        "The design points of the estimates whose runs failed, one group per (cell, limit)",
        {kPointNames},
        {},
        {{"design_point",
          "cell_<cell>_limit_<limit>",
          "gesweep risk",
          "One estimate's design point: its noise and its landing series",
          {kPointCell, kPointLimit, kSampleInterval, kNoiseLayout},
          {kMeanNoise, kMostLikelyNoise},
          {{"series",
            "<series>",
            "gesweep risk",
            "A landing series: steady (no turbulence), mean_failure, most_likely",
            {},
            {kSeriesTime, kSeriesColumn},
            {}}}}}}}};
  return layout;
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
    if (H5Aexists(file, NameOf(kKindAttribute).c_str()) > 0) {
      try {
        is = hdf5::ReadStringAttribute(file, NameOf(kKindAttribute)).value_or("") == kRiskArchiveKind;
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
