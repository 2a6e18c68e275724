#include "engine/sweep/sweep_plan.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/sweep/hashing.h"

namespace gesweep {
namespace {

// A write batch should take about this long on one core: long enough that flushing it costs
// little, short enough that a crash loses little (docs/sweep.md, "Batches and chunks").
constexpr double kTargetBatchCost_us = 1e6;
constexpr int kMaximumChunkRuns = 4096;  // 32 KB float64 chunks: a good unit for deflate
constexpr int kMinimumChunkRuns = 16;
// Memory of one batch buffer; a few of them are in flight per thread.
constexpr std::int64_t kMaximumBatchBytes = 16 << 20;
constexpr std::int64_t kDoubleBytes = sizeof(double);
constexpr int kMaximumShards = 100000;

int FloorPowerOfTwo(double x) {
  int p = 1;
  while (p * 2 <= x && p < (1 << 30)) p *= 2;
  return p;
}

}  // namespace

ShardSpec ParseShard(const std::string& text, const std::string& flag) {
  const auto slash = text.find('/');
  ShardSpec shard;
  bool ok = slash != std::string::npos;
  if (ok) {
    const char* begin = text.data();
    auto [p1, e1] = std::from_chars(begin, begin + slash, shard.index);
    auto [p2, e2] = std::from_chars(begin + slash + 1, begin + text.size(), shard.count);
    ok = e1 == std::errc() && e2 == std::errc() && p1 == begin + slash && p2 == begin + text.size();
  }
  if (!ok || shard.count < 1 || shard.count > kMaximumShards || shard.index < 0 ||
      shard.index >= shard.count) {
    throw InputError("command line", flag, "'" + text + "'",
                     "expected i/N with 0 <= i < N <= " + std::to_string(kMaximumShards) +
                         " (shards are numbered from 0)");
  }
  return shard;
}

int ShardBatchRuns(std::int64_t design_runs, int batch_runs, int shards) {
  const std::int64_t per_shard = std::max<std::int64_t>(1, design_runs / std::max(shards, 1));
  return static_cast<int>(
      std::max<std::int64_t>(1, std::min<std::int64_t>({batch_runs, per_shard, design_runs})));
}

void ShardRange(std::int64_t design_runs, int batch_runs, const ShardSpec& shard, std::int64_t* first,
                std::int64_t* count) {
  const std::int64_t b = ShardBatchRuns(design_runs, batch_runs, shard.count);
  const std::int64_t batches = (design_runs + b - 1) / b;
  // floor(i·B/N) without overflow: B = qN + r gives floor(i·B/N) = i·q + floor(i·r/N).
  const std::int64_t q = batches / shard.count, r = batches % shard.count;
  const auto split = [&](std::int64_t i) { return i * q + i * r / shard.count; };
  *first = std::min(design_runs, split(shard.index) * b);
  *count = std::min(design_runs, split(shard.index + 1) * b) - *first;
}

std::int64_t BookkeepingBytesPerRun() { return 8 /* index */ + 8 /* id */ + 1 /* status */; }

std::string FormatBytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int unit = 0;
  while (bytes >= 1000.0 && unit < 6) {
    bytes /= 1000.0;
    ++unit;
  }
  std::ostringstream out;
  out.precision(bytes < 10 && unit > 0 ? 2 : 3);
  out << bytes << " " << units[unit];
  return out.str();
}

SweepPlan::SweepPlan(Study study, ShardSpec shard) : study_(std::move(study)), shard_(shard) {
  for (auto& analysis : study_.analyses) analysis->DeclareOutputs(schema_, study_.storage);
  design_runs_ = CountRuns(study_.design);
  GESWEEP_DEMAND(design_runs_ >= 1);
  CheckStorage();
  // The design takes over the spec (a list's rows or a huge axis are not held twice); the study
  // keeps the kind for those who print it.
  const DesignKind kind = study_.design.kind;
  design_ = MakeDesign(std::move(study_.design));
  study_.design = DesignSpec{};
  study_.design.kind = kind;
  // Batch size: about kTargetBatchCost_us of work on one core, within memory and chunk bounds.
  int batch_runs = study_.chunk_runs;
  if (batch_runs == 0) {
    const double per_run = std::max(nominal_run_cost_us(), 1e-3);
    batch_runs = FloorPowerOfTwo(
        std::clamp(kTargetBatchCost_us / per_run, double{kMinimumChunkRuns}, double{kMaximumChunkRuns}));
    std::int64_t memory_per_run =
        kDoubleBytes * static_cast<std::int64_t>(design_->column_count()) + BookkeepingBytesPerRun();
    for (const auto& column : schema_.columns) memory_per_run += kDoubleBytes * column.doubles_per_run();
    while (batch_runs > 1 && batch_runs * memory_per_run > kMaximumBatchBytes) batch_runs /= 2;
  }
  ShardRange(design_runs_, batch_runs, shard_, &first_run_, &run_count_);
  if (run_count_ < 1) {
    throw InputError("command line", "shard",
                     std::to_string(shard_.index) + "/" + std::to_string(shard_.count),
                     "shard has no runs: the design has only " + std::to_string(design_runs_) +
                         " runs; use at most that many shards");
  }

  // Base parameters: defaults, then the study's fixed values.
  const Aircraft* aircraft = study_.aircraft ? &*study_.aircraft : nullptr;
  base_.assign(static_cast<std::size_t>(ParameterCount()), std::numeric_limits<double>::quiet_NaN());
  for (ParameterId id = 0; id < ParameterCount(); ++id) {
    if (auto value = DefaultValue(id, aircraft)) base_[static_cast<std::size_t>(id)] = *value;
    if (ParameterCatalog()[static_cast<std::size_t>(id)].group == ParameterGroup::kModel) {
      model_parameters_.push_back(id);
    }
  }
  for (const auto& fixed : study_.fixed) base_[static_cast<std::size_t>(fixed.id)] = fixed.value;
  std::vector<bool> read(static_cast<std::size_t>(ParameterCount()), false);
  for (const auto& analysis : study_.analyses) {
    for (ParameterId id : analysis->parameters_used()) read[static_cast<std::size_t>(id)] = true;
    if (analysis->needs_model()) {
      for (ParameterId id : model_parameters_) read[static_cast<std::size_t>(id)] = true;
    }
  }
  for (ParameterId id = 0; id < ParameterCount(); ++id) {
    if (read[static_cast<std::size_t>(id)]) parameters_read_.push_back(id);
  }

  CheckRuns();

  // Every shard of an N-way split has batches of the same size (ShardBatchRuns), so its chunks
  // coincide with those of the merged archive; a shard smaller than a batch (a design's only,
  // partial batch) has one chunk of its own size.
  chunk_runs_ = static_cast<int>(
      std::min<std::int64_t>(ShardBatchRuns(design_runs_, batch_runs, shard_.count), run_count_));
}

void SweepPlan::CheckStorage() {
  // Storage before compression.
  storage_.bytes_per_run = BookkeepingBytesPerRun() +
                           kDoubleBytes * static_cast<std::int64_t>(study_.design.parameters.size()) +
                           schema_.StoredBytesPerRun();
  for (const auto& column : schema_.columns) {
    if (!column.time_axis.empty()) storage_.series_bytes_per_run += column.stored_bytes_per_run();
  }
  const long double total = static_cast<long double>(storage_.bytes_per_run) * design_runs_;
  storage_.design_bytes = total > static_cast<long double>(std::numeric_limits<std::int64_t>::max())
                              ? std::numeric_limits<std::int64_t>::max()
                              : static_cast<std::int64_t>(total);
  if (total > static_cast<long double>(study_.max_archive_gb) * 1e9L) {
    std::ostringstream runs;
    runs << design_runs_;
    throw InputError(study_.path, "design", runs.str() + " runs",
                     "refusing it: the archive would need about " + FormatBytes(static_cast<double>(total)) +
                         " before compression (" + FormatBytes(static_cast<double>(storage_.bytes_per_run)) +
                         " per run" + (storage_.series_bytes_per_run ? ", time series included" : "") +
                         "), above output.max_archive_gb = " + FormatBytes(study_.max_archive_gb * 1e9) +
                         "; shrink the design, turn time series off, or raise max_archive_gb",
                     study_.design_line);
  }
}

void SweepPlan::CheckRuns() const {
  // The analyses' own checks (e.g. a start speed above stall) on the extreme values of the design:
  // every corner of its box for up to kMaximumCheckedDimensions columns, every row of a list.
  constexpr int kMaximumCheckedDimensions = 12;
  constexpr std::int64_t kMaximumCheckedRows = 1'000'000;
  const Aircraft* aircraft = study_.aircraft ? &*study_.aircraft : nullptr;
  const DesignSpec& spec = design_->spec();
  const int columns = design_->column_count();
  RunParameters parameters = base_;
  auto check = [&](const std::vector<double>& values) {
    for (int c = 0; c < columns; ++c) {
      parameters[static_cast<std::size_t>(spec.parameters[static_cast<std::size_t>(c)].id)] =
          values[static_cast<std::size_t>(c)];
    }
    for (const auto& analysis : study_.analyses) {
      const std::string problem = analysis->CheckRun(parameters, aircraft);
      if (problem.empty()) continue;
      std::string where;
      for (int c = 0; c < columns; ++c) {
        const ParameterId id = spec.parameters[static_cast<std::size_t>(c)].id;
        where += (where.empty() ? "" : ", ") + ParameterCatalog()[static_cast<std::size_t>(id)].name + " = " +
                 FormatParameterValue(id, values[static_cast<std::size_t>(c)]);
      }
      throw InputError(study_.path, columns ? "design" : "parameters", where,
                       "analysis '" + std::string(analysis->name()) + "' cannot run it: " + problem,
                       study_.design_line);
    }
  };
  std::vector<double> values(static_cast<std::size_t>(columns));
  if (spec.kind == DesignKind::kList && spec.list_rows <= kMaximumCheckedRows) {
    for (std::int64_t r = 0; r < spec.list_rows; ++r) {
      design_->Row(r, values.data());
      check(values);
    }
    return;
  }
  // The extreme values of each column.
  std::vector<std::pair<double, double>> extremes;
  for (int c = 0; c < columns; ++c) {
    const DesignParameter& p = spec.parameters[static_cast<std::size_t>(c)];
    if (spec.kind == DesignKind::kGrid) {
      extremes.emplace_back(*std::min_element(p.values.begin(), p.values.end()),
                            *std::max_element(p.values.begin(), p.values.end()));
    } else if (spec.kind == DesignKind::kList) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (std::int64_t r = 0; r < spec.list_rows; ++r) {
        const double v = spec.list_values[static_cast<std::size_t>(r * columns + c)];
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      extremes.emplace_back(lo, hi);
    } else {
      extremes.emplace_back(p.lower, p.upper);
    }
  }
  if (columns <= kMaximumCheckedDimensions) {
    for (std::uint32_t corner = 0; corner < (1u << columns); ++corner) {
      for (int c = 0; c < columns; ++c) {
        values[static_cast<std::size_t>(c)] = (corner >> c) & 1u
                                                  ? extremes[static_cast<std::size_t>(c)].second
                                                  : extremes[static_cast<std::size_t>(c)].first;
      }
      check(values);
    }
  } else {
    for (int c = 0; c < columns; ++c)
      values[static_cast<std::size_t>(c)] = extremes[static_cast<std::size_t>(c)].first;
    check(values);
    for (int c = 0; c < columns; ++c) {
      values[static_cast<std::size_t>(c)] = extremes[static_cast<std::size_t>(c)].second;
      check(values);
      values[static_cast<std::size_t>(c)] = extremes[static_cast<std::size_t>(c)].first;
    }
  }
}

void SweepPlan::RestrictToBatches(std::int64_t first_batch, std::int64_t batch_count) {
  GESWEEP_DEMAND(first_batch >= 0 && batch_count >= 1 && first_batch + batch_count <= block_count());
  const std::int64_t first = first_batch * chunk_runs_;
  const std::int64_t end = std::min(run_count_, (first_batch + batch_count) * chunk_runs_);
  first_run_ += first;
  run_count_ = end - first;
}

void SweepPlan::set_chunk_runs(int chunk_runs) {
  GESWEEP_DEMAND(chunk_runs >= 1);
  chunk_runs_ = chunk_runs;
}

double SweepPlan::nominal_run_cost_us() const {
  double cost = 0;
  for (const auto& analysis : study_.analyses) cost += analysis->nominal_run_cost_us();
  return cost;
}

std::uint64_t SweepPlan::RunId(const double* design_row) const {
  std::uint64_t hash = kFnvOffset;
  for (int c = 0; c < design_->column_count(); ++c) {
    const ParameterId id = design_->spec().parameters[static_cast<std::size_t>(c)].id;
    // A renamed parameter's older name (identity_name): a rename changes no run's id.
    hash = Fnv1a64(ParameterCatalog()[static_cast<std::size_t>(id)].identity_name, hash);
    hash = Fnv1a64(design_row[c], hash);
  }
  return hash;
}

}  // namespace gesweep
