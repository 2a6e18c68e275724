#include "engine/sensitivity/sensitivity_group.h"

#include <cstring>
#include <limits>

#include "engine/archive/archive_format.h"
#include "engine/archive/hdf5_util.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

constexpr const char* kSensitivityGroup = "analysis/sensitivity";

// Estimator names as recorded (docs/sensitivity.md, "Sobol' indices" and "Morris elementary effects").
constexpr const char* kFirstOrderEstimator =
    "Saltelli et al. (2010), Table 2 (b): S_i = mean(f_B (f_ABi - f_A)) / V";
constexpr const char* kTotalEstimator = "Jansen (1999): S_Ti = mean((f_A - f_ABi)^2) / (2V)";
constexpr const char* kSecondOrderEstimator =
    "Saltelli (2002), SALib's form: S_ij = mean(f_BAi f_ABj - f_A f_B) / V - S_i - S_j";
constexpr const char* kMorrisEstimator =
    "Morris (1991) elementary effects EE = dy / (signed unit step); mu = mean EE, mu_star = mean |EE| "
    "(Campolongo et al. 2007), sigma = sample standard deviation (n - 1)";

void WriteDoubles(hid_t group, const std::string& name, const std::vector<hsize_t>& dims, const double* data,
                  const std::string& units, const std::string& description) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), "dataspace of " + name);
  Handle dataset(
      H5Dcreate2(group, name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      "create " + name);
  Check(H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
  hdf5::WriteAttribute(dataset.get(), "units", units);
  hdf5::WriteAttribute(dataset.get(), "description", description);
}

void WriteCounts(hid_t group, const std::string& name, const std::vector<int>& counts,
                 const std::string& description) {
  const std::vector<std::int64_t> values(counts.begin(), counts.end());
  const hsize_t dims[1] = {values.size()};
  Handle space(H5Screate_simple(1, dims, nullptr), "dataspace of " + name);
  Handle dataset(
      H5Dcreate2(group, name.c_str(), H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      "create " + name);
  Check(H5Dwrite(dataset.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
        "write " + name);
  hdf5::WriteAttribute(dataset.get(), "units", "1");
  hdf5::WriteAttribute(dataset.get(), "description", description);
}

void WriteVector(hid_t group, const std::string& name, const std::vector<double>& values,
                 const std::string& units, const std::string& description) {
  WriteDoubles(group, name, {values.size()}, values.data(), units, description);
}

// D × 2 (lower, upper) intervals.
void WriteIntervals(hid_t group, const std::string& name, const std::vector<ConfidenceInterval>& intervals,
                    const std::string& units, const std::string& description) {
  std::vector<double> values;
  for (const auto& ci : intervals) {
    values.push_back(ci.lower);
    values.push_back(ci.upper);
  }
  WriteDoubles(group, name, {intervals.size(), 2}, values.data(), units, description);
}

void WriteSobol(hid_t group, const ArchiveSensitivity& result, const std::string& level) {
  const SobolIndices& s = result.sobol;
  const auto D = static_cast<hsize_t>(s.layout.parameter_count);
  hdf5::WriteAttribute(group, "base_samples", static_cast<std::int64_t>(s.layout.base_samples));
  hdf5::WriteAttribute(group, "dimension", static_cast<std::int64_t>(s.layout.parameter_count));
  hdf5::WriteAttribute(group, "second_order", static_cast<std::int64_t>(s.layout.second_order ? 1 : 0));
  hdf5::WriteAttribute(group, "estimator_first_order", kFirstOrderEstimator);
  hdf5::WriteAttribute(group, "estimator_total", kTotalEstimator);
  if (s.layout.second_order) hdf5::WriteAttribute(group, "estimator_second_order", kSecondOrderEstimator);
  hdf5::WriteAttribute(group, "blocks_used", static_cast<std::int64_t>(s.blocks_used));
  hdf5::WriteAttribute(group, "blocks_dropped", static_cast<std::int64_t>(s.blocks_dropped));
  hdf5::WriteAttribute(group, "bootstrap_unit", "base samples (whole Saltelli blocks), with replacement");
  hdf5::WriteAttribute(group, "output_mean", s.output_mean);
  hdf5::WriteAttribute(group, "output_variance", s.output_variance);

  WriteVector(group, "first_order", s.first_order, "1", "First-order Sobol' index S_i of each parameter");
  WriteIntervals(group, "first_order_ci", s.first_order_ci, "1",
                 level + " bootstrap percentile interval of S_i: columns lower, upper");
  WriteVector(group, "total", s.total, "1", "Total Sobol' index S_Ti of each parameter");
  WriteIntervals(group, "total_ci", s.total_ci, "1",
                 level + " bootstrap percentile interval of S_Ti: columns lower, upper");
  if (!s.layout.second_order) return;
  // Row-major D × D (Eigen is column-major): element (i, j), i < j, is S_ij; NaN elsewhere.
  std::vector<double> second, interval;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(D); ++i) {
    for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(D); ++j) {
      second.push_back(s.second_order(i, j));
      interval.push_back(s.second_order_ci_lower(i, j));
      interval.push_back(s.second_order_ci_upper(i, j));
    }
  }
  WriteDoubles(group, "second_order", {D, D}, second.data(), "1",
               "Second-order Sobol' index S_ij at (i, j) for i < j (parameters in the order of the attribute "
               "parameters); NaN on and below the diagonal");
  WriteDoubles(group, "second_order_ci", {D, D, 2}, interval.data(), "1",
               level + " bootstrap percentile interval of S_ij: [i, j, 0] lower, [i, j, 1] upper");
}

void WriteMorris(hid_t group, const ArchiveSensitivity& result, const std::string& level) {
  const MorrisIndices& m = result.morris;
  const std::string units = result.output.units + " per full range of the parameter";
  hdf5::WriteAttribute(group, "trajectories", static_cast<std::int64_t>(m.trajectories));
  hdf5::WriteAttribute(group, "dimension", static_cast<std::int64_t>(m.parameter_count));
  hdf5::WriteAttribute(group, "levels", static_cast<std::int64_t>(result.morris_levels));
  hdf5::WriteAttribute(group, "delta", result.morris_delta);
  hdf5::WriteAttribute(group, "estimator", kMorrisEstimator);
  hdf5::WriteAttribute(group, "trajectories_used", static_cast<std::int64_t>(m.trajectories_used));
  hdf5::WriteAttribute(group, "trajectories_dropped", static_cast<std::int64_t>(m.trajectories_dropped));
  hdf5::WriteAttribute(group, "blocks_used", static_cast<std::int64_t>(m.trajectories_used));
  hdf5::WriteAttribute(group, "blocks_dropped", static_cast<std::int64_t>(m.trajectories_dropped));
  hdf5::WriteAttribute(group, "bootstrap_unit", "trajectories, with replacement");
  WriteVector(group, "mu", m.mu, units, "Mean elementary effect mu (signed)");
  WriteVector(group, "mu_star", m.mu_star, units,
              "Mean absolute elementary effect mu* (the ranking measure)");
  WriteIntervals(group, "mu_star_ci", m.mu_star_ci, units,
                 level + " bootstrap percentile interval of mu*: columns lower, upper");
  WriteVector(group, "sigma", m.sigma, units, "Sample standard deviation of the elementary effects (n - 1)");
  WriteCounts(group, "effects", m.effects, "Number of elementary effects of each parameter that entered");
}

void WriteGroup(hid_t file, const std::string& path, const ArchiveSensitivity& result,
                const std::string& command_line) {
  Handle group(H5Gcreate2(file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "create group " + path);
  const hid_t g = group.get();
  const BootstrapOptions& bootstrap =
      result.method == SensitivityMethod::kSobol ? result.sobol.bootstrap : result.morris.bootstrap;
  const std::string level = ShortNumber(100.0 * bootstrap.confidence_level) + " %";
  hdf5::WriteAttribute(g, "description",
                       std::string(result.method == SensitivityMethod::kSobol ? "Sobol' indices"
                                                                              : "Morris elementary effects") +
                           " of " + result.output.path + " over the swept parameters (docs/sensitivity.md)");
  hdf5::WriteAttribute(g, "method", std::string(ToString(result.method)));
  hdf5::WriteAttribute(g, "output", result.output.name);
  hdf5::WriteAttribute(g, "output_path", result.output.path);
  hdf5::WriteAttribute(g, "output_units", result.output.units);
  hdf5::WriteAttribute(g, "parameters", result.parameters);
  hdf5::WriteAttribute(g, "parameter_units", result.parameter_units);
  std::vector<double> lower, upper;
  std::vector<std::string> distributions;
  for (const auto& range : result.ranges) {
    lower.push_back(range.lower);
    upper.push_back(range.upper);
    distributions.push_back(range.log_uniform ? "loguniform" : "uniform");
  }
  hdf5::WriteAttribute(g, "parameter_lower", lower);
  hdf5::WriteAttribute(g, "parameter_upper", upper);
  hdf5::WriteAttribute(g, "parameter_distributions", distributions);
  hdf5::WriteAttribute(g, "n", result.n());
  hdf5::WriteAttribute(g, "run_count", result.run_count);
  hdf5::WriteAttribute(g, "failed_runs", std::string(ToString(result.failed_runs)));
  hdf5::WriteAttribute(g, "runs_failed", result.runs_failed);
  hdf5::WriteAttribute(g, "runs_without_value", result.runs_without_value);
  hdf5::WriteAttribute(g, "bootstrap_resamples", static_cast<std::int64_t>(bootstrap.resamples));
  hdf5::WriteAttribute(g, "bootstrap_seed", static_cast<std::int64_t>(bootstrap.seed));
  hdf5::WriteAttribute(g, "confidence_level", bootstrap.confidence_level);
  hdf5::WriteAttribute(g, "engine_version", EngineVersion());
  hdf5::WriteAttribute(g, "git_commit", EngineGitCommit());
  hdf5::WriteAttribute(g, "created", UtcTimestamp());
  hdf5::WriteAttribute(g, "command_line", command_line);
  if (result.method == SensitivityMethod::kSobol) {
    WriteSobol(g, result, level);
  } else {
    WriteMorris(g, result, level);
  }
}

}  // namespace

std::string SensitivityGroupPath(const ArchiveOutput& output) {
  return std::string(kSensitivityGroup) + "/" + output.name;
}

void WriteSensitivityGroup(const std::filesystem::path& archive, const ArchiveSensitivity& result,
                           const std::string& command_line) {
  GESWEEP_DEMAND(result.status == SensitivityStatus::kOk);
  hdf5::Quiet();
  const std::string shown = archive.string();
  Handle fapl = hdf5::FileAccess();
  const hid_t id = H5Fopen(archive.c_str(), H5F_ACC_RDWR, fapl.get());
  if (id < 0) {
    const std::string detail = hdf5::LastError();
    H5Eclear2(H5E_DEFAULT);
    throw InputError(
        shown, "", "",
        "cannot open the archive for writing (HDF5: " + detail +
            "); is another program reading or writing it? pass --no-write to only print the result");
  }
  Handle file(id);
  hdf5::ReplaceGroup(file.get(), SensitivityGroupPath(result.output), [&](const std::string& temporary) {
    WriteGroup(file.get(), temporary, result, command_line);
  });
  file.Close("close " + shown);
}

}  // namespace gesweep
