#include "engine/products/archive_sensitivity.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include "engine/archive/archive_error.h"
#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/common/toml_reader.h"

namespace gesweep {
namespace {

// Run statuses of runs/status (schemas/archive.md).
constexpr std::int8_t kStatusPending = 0;
constexpr std::int8_t kStatusOk = 1;
constexpr std::int8_t kStatusFailed = 2;

// Rows of the design read at a time when checking a Saltelli layout: bounded memory for any N.
constexpr std::int64_t kDesignPieceRows = 1 << 16;

const std::string kResultsPrefix = std::string(archive::kResultsGroup) + "/";

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.size() >= prefix.size() && text.compare(0, prefix.size(), prefix) == 0;
}

std::string LastName(const std::string& path) { return path.substr(path.rfind('/') + 1); }

std::string Join(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// An integer attribute of a group that the layout needs: an InputError naming it when absent, since
// an archive without it was not made by a sweep of this kind (or by an older engine).
std::int64_t RequireInteger(const ArchiveReader& archive, const std::string& group_name,
                            const std::string& name, const std::string& source) {
  const auto value = archive.IntegerAttributeOf(group_name, name);
  if (!value) {
    throw InputError(
        source, group_name + "/" + name, "",
        "missing design attribute; the archive's layout is unknown (made by another engine version?)");
  }
  return *value;
}

struct DatasetShape {
  bool scalar = false;  // 1-D numeric, one value per run
  bool integer = false;
};

DatasetShape ShapeOf(const ArchiveReader& archive, const std::string& path) {
  const ArchiveReader::DatasetInfo info = archive.Describe(path);
  DatasetShape shape;
  shape.integer = info.kind == ArchiveReader::DatasetInfo::Kind::kInteger;
  shape.scalar = info.dims.size() == 1 && info.dims[0] == archive.run_count() &&
                 (info.kind == ArchiveReader::DatasetInfo::Kind::kFloat || shape.integer);
  return shape;
}

// Reads the output column; an integer column's fill value ("no value") becomes NaN.
std::vector<double> ReadOutput(const ArchiveReader& archive, const ArchiveOutput& output) {
  std::vector<double> values = archive.ReadDoubles(output.path, 0, archive.run_count());
  if (ShapeOf(archive, output.path).integer) {
    if (const auto fill = archive.IntegerAttributeOf(output.path, "fill")) {
      const auto fill_value = static_cast<double>(*fill);
      for (double& v : values) {
        if (v == fill_value) v = std::numeric_limits<double>::quiet_NaN();
      }
    }
  }
  return values;
}

// Throws unless the archive holds the whole design, every run complete, in design order.
void RequireCompleteDesign(const ArchiveReader& archive, const std::vector<std::int8_t>& status,
                           const std::string& source) {
  const std::int64_t design_runs = archive.IntegerAttribute("design_runs");
  const std::int64_t first_run = archive.IntegerAttribute("first_run");
  if (first_run != 0 || archive.run_count() != design_runs) {
    throw InputError(source, "shard", archive.StringAttribute("shard"),
                     "holds runs " + std::to_string(first_run) + ".." +
                         std::to_string(first_run + archive.run_count() - 1) + " of the design's " +
                         std::to_string(design_runs) +
                         " only; merge every shard (gesweep merge) and analyse the merged archive");
  }
  const auto pending = std::count(status.begin(), status.end(), kStatusPending);
  if (pending > 0) {
    throw RequestError(source, "runs/status", std::to_string(pending) + " pending",
                       "expected every run complete: " + std::to_string(pending) + " of " +
                           std::to_string(status.size()) + " runs have not run yet",
                       "finish_sweep", source);
  }
  const std::vector<std::int64_t> index = archive.ReadIntegers(archive::kRunIndex, 0, archive.run_count());
  for (std::size_t r = 0; r < index.size(); ++r) {
    if (index[r] != static_cast<std::int64_t>(r)) {
      throw InputError(source, "runs/index", std::to_string(index[r]),
                       "expected run " + std::to_string(r) + " in row " + std::to_string(r) +
                           " (the rows are not in design order)");
    }
  }
}

// The sampled range of each design parameter, from its dataset's `bounds` and `distribution`.
void ReadRanges(const ArchiveReader& archive, ArchiveSensitivity& result, const std::string& source) {
  for (const auto& name : result.parameters) {
    const std::string path = archive::DesignPath(name);
    if (!archive.Exists(path)) {
      throw InputError(source, path, "",
                       "missing: the design group lists " + name + " but has no dataset for it");
    }
    const std::vector<double> bounds = archive.DoubleListAttributeOf(path, "bounds");
    const std::string distribution = archive.StringAttributeOf(path, "distribution").value_or("");
    if (bounds.size() != 2 || (distribution != "uniform" && distribution != "loguniform")) {
      throw InputError(
          source, path, "",
          "expected the attributes bounds = [lower, upper] and distribution = uniform|loguniform of a "
          "sampled parameter");
    }
    ParameterRange range;
    range.name = name;
    range.lower = bounds[0];
    range.upper = bounds[1];
    range.log_uniform = distribution == "loguniform";
    result.ranges.push_back(range);
    result.parameter_units.push_back(archive.StringAttributeOf(path, "units").value_or(""));
  }
}

// Checks that the design's rows follow the Saltelli layout its attributes declare: in every block,
// AB^(i) is A with column i from B, BA^(i) is B with column i from A. Catches an archive whose
// attributes and rows disagree before any index is computed from mispaired rows.
void CheckSaltelliRows(const ArchiveReader& archive, const ArchiveSensitivity& result,
                       const SaltelliLayout& layout, const std::string& source) {
  const int D = layout.parameter_count;
  const std::int64_t block_rows = layout.BlockSize();
  const std::int64_t blocks_per_piece = std::max<std::int64_t>(1, kDesignPieceRows / block_rows);
  std::vector<std::vector<double>> columns(static_cast<std::size_t>(D));
  for (std::int64_t first_block = 0; first_block < layout.base_samples; first_block += blocks_per_piece) {
    const std::int64_t blocks = std::min<std::int64_t>(blocks_per_piece, layout.base_samples - first_block);
    const std::int64_t first_row = first_block * block_rows;
    for (int i = 0; i < D; ++i) {
      columns[static_cast<std::size_t>(i)] =
          archive.ReadDoubles(archive::DesignPath(result.parameters[static_cast<std::size_t>(i)]), first_row,
                              blocks * block_rows);
    }
    for (std::int64_t b = 0; b < blocks; ++b) {
      const int j = static_cast<int>(first_block + b);
      const auto local = [&](std::size_t row) { return row - static_cast<std::size_t>(first_row); };
      const std::size_t a = local(layout.RowA(j)), bb = local(layout.RowB(j));
      // The A and B rows define the block; every row between takes each column from one of them.
      for (std::int64_t k = 1; k + 1 < block_rows; ++k) {
        const std::size_t row = a + static_cast<std::size_t>(k);
        for (int d = 0; d < D; ++d) {
          const auto& column = columns[static_cast<std::size_t>(d)];
          const double expected = column[SaltelliTakesB(D, layout.second_order, k, d) ? bb : a];
          if (!(column[row] == expected)) {
            throw InputError(
                source, archive::DesignPath(result.parameters[static_cast<std::size_t>(d)]),
                "row " + std::to_string(row + static_cast<std::size_t>(first_row)),
                "the design's rows do not follow the Saltelli layout its attributes declare (N = " +
                    std::to_string(layout.base_samples) + ", D = " + std::to_string(D) + ", second order " +
                    (layout.second_order ? "yes" : "no") + ")");
          }
        }
      }
    }
  }
}

SaltelliLayout ReadSaltelliLayout(const ArchiveReader& archive, const ArchiveSensitivity& result,
                                  const std::string& source) {
  const std::string layout_name = archive.StringAttributeOf(archive::kDesignGroup, "layout").value_or("");
  if (layout_name != "saltelli") {
    throw InputError(source, "design/layout", layout_name,
                     "expected saltelli (the row layout of a sobol design)");
  }
  const std::int64_t N = RequireInteger(archive, archive::kDesignGroup, "base_samples", source);
  const std::int64_t D = RequireInteger(archive, archive::kDesignGroup, "dimension", source);
  const std::int64_t second = RequireInteger(archive, archive::kDesignGroup, "second_order", source);
  const std::int64_t block_rows = RequireInteger(archive, archive::kDesignGroup, "block_rows", source);
  SaltelliLayout layout;
  layout.parameter_count = static_cast<int>(D);
  layout.base_samples = N > 0 && N <= INT_MAX ? static_cast<int>(N) : 0;
  layout.second_order = second != 0;
  const bool consistent = D == static_cast<std::int64_t>(result.parameters.size()) &&
                          layout.base_samples > 0 && block_rows == layout.BlockSize() &&
                          static_cast<std::int64_t>(layout.RowCount()) == archive.run_count();
  if (!consistent) {
    throw InputError(source, "design", "N = " + std::to_string(N) + ", D = " + std::to_string(D),
                     "a Saltelli layout of " + std::to_string(block_rows) +
                         " rows per block that matches neither its " +
                         std::to_string(result.parameters.size()) + " parameters nor its " +
                         std::to_string(archive.run_count()) + " runs");
  }
  CheckSaltelliRows(archive, result, layout, source);
  return layout;
}

Eigen::MatrixXd ReadDesignMatrix(const ArchiveReader& archive, const ArchiveSensitivity& result) {
  Eigen::MatrixXd design(archive.run_count(), static_cast<Eigen::Index>(result.parameters.size()));
  for (std::size_t i = 0; i < result.parameters.size(); ++i) {
    const std::vector<double> column =
        archive.ReadDoubles(archive::DesignPath(result.parameters[i]), 0, archive.run_count());
    design.col(static_cast<Eigen::Index>(i)) =
        Eigen::Map<const Eigen::VectorXd>(column.data(), archive.run_count());
  }
  return design;
}

std::string Plural(std::int64_t count, const std::string& singular, const std::string& plural) {
  return std::to_string(count) + " " + (count == 1 ? singular : plural);
}

}  // namespace

std::optional<SensitivityMethod> ParseSensitivityMethod(std::string_view text) {
  return ParseEnum<SensitivityMethod>(text);
}

std::int64_t ArchiveSensitivity::n() const {
  return method == SensitivityMethod::kSobol ? sobol.layout.base_samples : morris.trajectories;
}

std::int64_t ArchiveSensitivity::blocks_dropped() const {
  if (status == SensitivityStatus::kStoppedOnFailedRuns) return 0;
  return method == SensitivityMethod::kSobol ? sobol.blocks_dropped : morris.trajectories_dropped;
}

std::int64_t ArchiveSensitivity::blocks_used() const {
  if (status == SensitivityStatus::kStoppedOnFailedRuns) return 0;
  return method == SensitivityMethod::kSobol ? sobol.blocks_used : morris.trajectories_used;
}

std::vector<ArchiveOutput> ScalarOutputs(const ArchiveReader& archive) {
  std::vector<ArchiveOutput> outputs;
  for (const std::string& path : archive.Datasets()) {
    if (!StartsWith(path, kResultsPrefix) || !ShapeOf(archive, path).scalar) continue;
    ArchiveOutput output;
    output.path = path;
    output.name = path.substr(kResultsPrefix.size());
    output.units = archive.StringAttributeOf(path, "units").value_or("");
    output.description = archive.StringAttributeOf(path, "description").value_or("");
    outputs.push_back(std::move(output));
  }
  return outputs;
}

ArchiveOutput ResolveOutput(const ArchiveReader& archive, const std::string& name) {
  const std::string source = archive.path().string();
  std::string wanted = name;
  while (!wanted.empty() && wanted.front() == '/') wanted.erase(wanted.begin());
  const std::vector<ArchiveOutput> outputs = ScalarOutputs(archive);
  for (const auto& output : outputs) {
    if (output.path == wanted || output.name == wanted) return output;
  }
  std::vector<const ArchiveOutput*> matches;
  for (const auto& output : outputs) {
    if (LastName(output.path) == wanted) matches.push_back(&output);
  }
  if (matches.size() == 1) return *matches.front();
  if (matches.size() > 1) {
    std::vector<std::string> paths;
    paths.reserve(matches.size());
    for (const auto* m : matches) paths.push_back(m->path);
    throw InputError(source, "output", name,
                     "ambiguous: matches " + Join(paths) + "; give one of these paths");
  }
  // Not a scalar output: say why when the dataset exists, else suggest the nearest name.
  std::vector<std::string> not_scalar;
  for (const std::string& path : archive.Datasets()) {
    if (path == wanted || path == kResultsPrefix + wanted || LastName(path) == wanted)
      not_scalar.push_back(path);
  }
  if (!not_scalar.empty()) {
    throw InputError(
        source, "output", name,
        Join(not_scalar) + (not_scalar.size() == 1 ? " is" : " are") +
            " not a scalar result column (one number per run under results/); sensitivity needs one");
  }
  if (outputs.empty()) {
    throw InputError(source, "output", name,
                     "the archive has no scalar result column (its study ran no analysis "
                     "with scalar results)");
  }
  std::vector<std::string> names;
  names.reserve(2 * outputs.size());
  for (const auto& output : outputs) {
    names.push_back(output.name);
    names.push_back(LastName(output.path));
  }
  const std::string nearest = NearestName(wanted, names);
  std::vector<std::string> listed;
  listed.reserve(outputs.size());
  for (const auto& output : outputs) listed.push_back(output.name);
  throw InputError(source, "output", name,
                   (nearest.empty() ? std::string() : "did you mean " + nearest + "? ") +
                       "expected a scalar result column: " + Join(listed));
}

namespace {

// The estimator the archive's design kind calls for, into result.method (with its parameters and
// design kind). Throws RequestError when options.method asks for another, InputError when the
// design has none or lists no parameter.
void ChooseMethod(const ArchiveReader& archive, const ArchiveSensitivityOptions& options,
                  const std::string& source, ArchiveSensitivity& result) {
  result.design_kind = archive.StringAttributeOf(archive::kDesignGroup, "kind").value_or("");
  result.parameters = archive.StringListAttributeOf(archive::kDesignGroup, "parameters");
  const auto design_method = ParseSensitivityMethod(result.design_kind);
  if (options.method && design_method != options.method) {
    const std::string needed = *options.method == SensitivityMethod::kSobol ? "sobol" : "morris";
    throw RequestError(source, "method", std::string(ToString(*options.method)),
                       "needs a " + needed + " design, but this archive's design is " + result.design_kind,
                       design_method ? "use_method" : "",
                       design_method ? std::string(ToString(*design_method)) : "");
  }
  if (!design_method) {
    throw InputError(source, "design", result.design_kind,
                     "global sensitivity needs a design of kind sobol (Sobol' indices) or morris (elementary "
                     "effects); set [design] kind in the study and run it again");
  }
  result.method = *design_method;
  if (result.parameters.empty()) {
    throw InputError(source, "design/parameters", "", "the design lists no swept parameter");
  }
}

// Each run's flag "succeeded" (status ok); the runs without a value (failed, or ok with a value
// not finite) counted in `result`, with the first one's row and message.
std::vector<bool> MarkMissingRuns(const ArchiveReader& archive, const std::vector<std::int8_t>& status,
                                  const std::vector<double>& outputs, ArchiveSensitivity& result) {
  std::vector<bool> succeeded(status.size());
  for (std::size_t r = 0; r < status.size(); ++r) {
    succeeded[r] = status[r] == kStatusOk;
    const bool missing = status[r] != kStatusOk || !std::isfinite(outputs[r]);
    if (!missing) continue;
    if (status[r] == kStatusFailed) {
      ++result.runs_failed;
    } else {
      ++result.runs_without_value;
    }
    if (result.first_missing_row < 0) result.first_missing_row = static_cast<std::int64_t>(r);
  }
  if (result.first_missing_row >= 0) {
    result.first_missing_message = archive.ReadMessages(result.first_missing_row, 1).front();
  }
  return succeeded;
}

// Sobol' indices of the output over the archive's Saltelli design. Returns the rows of a block.
std::int64_t AnalyzeSobolDesign(const ArchiveReader& archive, const std::vector<double>& outputs,
                                const std::vector<bool>& succeeded, const ArchiveSensitivityOptions& options,
                                const std::string& source, ArchiveSensitivity& result) {
  const SaltelliLayout layout = ReadSaltelliLayout(archive, result, source);
  SobolOptions sobol_options;
  sobol_options.failed_runs = options.failed_runs;
  sobol_options.bootstrap = options.bootstrap;
  sobol_options.source = source;
  result.sobol = AnalyzeSobol(outputs, succeeded, layout, sobol_options);
  result.status = result.sobol.status;
  result.message = result.sobol.message;
  return layout.BlockSize();
}

// Morris elementary effects of the output over the archive's trajectories. Returns the rows of a
// trajectory. Throws InputError when the layout does not match the parameters and runs.
std::int64_t AnalyzeMorrisDesign(const ArchiveReader& archive, const std::vector<double>& outputs,
                                 const std::vector<bool>& succeeded, const ArchiveSensitivityOptions& options,
                                 const std::string& source, ArchiveSensitivity& result) {
  const std::int64_t trajectories = RequireInteger(archive, archive::kDesignGroup, "trajectories", source);
  const std::int64_t trajectory_rows =
      RequireInteger(archive, archive::kDesignGroup, "trajectory_rows", source);
  result.morris_levels = static_cast<int>(RequireInteger(archive, archive::kDesignGroup, "levels", source));
  result.morris_delta = archive.DoubleAttributeOf(archive::kDesignGroup, "delta").value_or(std::nan(""));
  const auto D = static_cast<std::int64_t>(result.parameters.size());
  if (trajectory_rows != D + 1 || trajectories * trajectory_rows != archive.run_count()) {
    throw InputError(source, "design", std::to_string(trajectories) + " trajectories",
                     "a Morris layout of " + std::to_string(trajectory_rows) +
                         " rows per trajectory that matches neither its " + std::to_string(D) +
                         " parameters nor its " + std::to_string(archive.run_count()) + " runs");
  }
  MorrisOptions morris_options;
  morris_options.failed_runs = options.failed_runs;
  morris_options.bootstrap = options.bootstrap;
  morris_options.source = source;
  result.morris =
      AnalyzeMorris(ReadDesignMatrix(archive, result), outputs, succeeded, result.ranges, morris_options);
  result.status = result.morris.status;
  result.message = result.morris.message;
  return trajectory_rows;
}

}  // namespace

ArchiveSensitivity AnalyzeArchiveOutput(const ArchiveReader& archive, const std::string& output_name,
                                        const ArchiveSensitivityOptions& options) {
  const std::string source = archive.path().string();
  ArchiveSensitivity result;
  result.archive_path = source;
  result.study_name = archive.StringAttribute("study_name");
  result.failed_runs = options.failed_runs;
  ValidateBootstrapOptions(options.bootstrap, source);

  result.output = ResolveOutput(archive, output_name);

  // The design: its kind decides which estimator applies.
  ChooseMethod(archive, options, source, result);

  const std::vector<std::int8_t> status = archive.ReadStatus(0, archive.run_count());
  RequireCompleteDesign(archive, status, source);
  result.run_count = archive.run_count();
  ReadRanges(archive, result, source);

  const std::vector<double> outputs = ReadOutput(archive, result.output);
  const std::vector<bool> succeeded = MarkMissingRuns(archive, status, outputs, result);

  std::int64_t block_rows = 0;
  std::string block_word;
  if (result.method == SensitivityMethod::kSobol) {
    block_rows = AnalyzeSobolDesign(archive, outputs, succeeded, options, source, result);
    block_word = "Saltelli blocks";
  } else {
    block_rows = AnalyzeMorrisDesign(archive, outputs, succeeded, options, source, result);
    block_word = "Morris trajectories";
  }

  for (std::int64_t first = 0; first < result.run_count; first += block_rows) {
    for (std::int64_t r = first; r < first + block_rows; ++r) {
      if (!succeeded[static_cast<std::size_t>(r)] || !std::isfinite(outputs[static_cast<std::size_t>(r)])) {
        ++result.blocks_with_missing;
        break;
      }
    }
  }
  if (result.status == SensitivityStatus::kStoppedOnFailedRuns) {
    // Both kinds of missing value; the other remedy, dropping blocks, in failed_runs_remedy.
    const std::int64_t missing = result.runs_failed + result.runs_without_value;
    result.message =
        Plural(missing, "run", "runs") + " of " + std::to_string(result.run_count) + " have no value of " +
        result.output.name + " (" + std::to_string(result.runs_failed) + " failed, " +
        std::to_string(result.runs_without_value) + " ok without a finite value; first: row " +
        std::to_string(result.first_missing_row) +
        (result.first_missing_message.empty() ? "" : ", \"" + result.first_missing_message + "\"") +
        "); rerun them";
    result.failed_runs_remedy = "leave out the " + std::to_string(result.blocks_with_missing) + " of " +
                                std::to_string(result.n()) + " " + block_word + " that hold them";
  }
  return result;
}

}  // namespace gesweep
