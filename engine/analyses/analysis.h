#pragma once
/// The per-run analyses of a sweep and the columns they fill (docs/sweep.md, schemas/archive.md).
///
/// An analysis (modes, boundary, open_loop, landing, the verification models) is one small adapter
/// that (1) validates its settings from the study's [analyses.<name>] table, (2) declares the
/// columns it fills, and (3) fills them for one run from the run's parameters and model. The engine
/// below it (engine/modal, engine/simulation, engine/control) knows nothing of sweeps; the archive
/// knows nothing of analyses, only of columns.

#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/analyses/parameter_catalog.h"
#include "engine/common/describe.h"
#include "engine/common/toml_reader.h"
#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

/// How a column is stored. In memory every value is a double; integer columns hold whole numbers
/// (NaN means "no value" and is stored as the column's integer fill).
enum class ColumnType {
  kFloat64,  ///< IEEE double
  kInt32,    ///< 32-bit signed integer
  kInt8,     ///< 8-bit signed integer (flags, small codes)
  kComplex,  ///< compound {re, im} of doubles; `width` complex numbers per run (2·width doubles)
};

/// One result column of the archive: `width` values per run (1 for a scalar, 5 for the eigenvalues,
/// T for a time series).
struct OutputColumn {
  std::string path;         ///< archive path, e.g. "results/modes/stability_margin_per_s"
  std::string units;        ///< "1/s", "m", "1" for a ratio or flag
  std::string description;  ///< one line
  ColumnType type = ColumnType::kFloat64;
  int width = 1;
  std::string time_axis;                     ///< path of the shared time axis when this is a time series
  std::vector<std::string> levels;           ///< names of the codes of an integer column (0, 1, ...)
  std::vector<std::string> component_names;  ///< names of the `width` components of a non-series column
  int integer_fill = -1;                     ///< stored for NaN in an integer column

  /// A float64 scalar column.
  static OutputColumn Real(std::string path, std::string units, std::string description) {
    OutputColumn c;
    c.path = std::move(path);
    c.units = std::move(units);
    c.description = std::move(description);
    return c;
  }
  /// An integer scalar column (kInt8 or kInt32), with the names of its codes when it has some.
  static OutputColumn Integer(ColumnType type, std::string path, std::string units, std::string description,
                              std::vector<std::string> levels = {}) {
    OutputColumn c = Real(std::move(path), std::move(units), std::move(description));
    c.type = type;
    c.levels = std::move(levels);
    return c;
  }
  /// `width` complex numbers per run.
  static OutputColumn Complex(std::string path, std::string units, std::string description, int width) {
    OutputColumn c = Real(std::move(path), std::move(units), std::move(description));
    c.type = ColumnType::kComplex;
    c.width = width;
    return c;
  }
  /// A float64 time series of `samples` values per run on the shared axis `time_axis`.
  static OutputColumn Series(std::string path, std::string units, std::string description,
                             std::string time_axis, int samples) {
    OutputColumn c = Real(std::move(path), std::move(units), std::move(description));
    c.width = samples;
    c.time_axis = std::move(time_axis);
    return c;
  }

  /// Doubles per run in a block buffer.
  int doubles_per_run() const { return type == ColumnType::kComplex ? 2 * width : width; }
  /// Bytes per run in the archive, before compression.
  int stored_bytes_per_run() const;
};

/// A shared time axis of time-series columns.
struct TimeAxis {
  std::string path;  ///< e.g. "series/open_loop/time_s"
  std::string description;
  std::vector<double> times_s;
};

/// Every column a sweep fills, in a fixed order.
struct OutputSchema {
  std::vector<OutputColumn> columns;
  std::vector<TimeAxis> axes;

  /// Appends a column and returns its index; GESWEEP_DEMAND that the path is new.
  int Add(OutputColumn column);
  /// Appends a time axis; GESWEEP_DEMAND that the path is new.
  void AddAxis(TimeAxis axis);
  /// Bytes per run of all columns, before compression.
  std::int64_t StoredBytesPerRun() const;
};

/// One run's slots in a block of results: Slot(c) points at column c's doubles for this run,
/// pre-filled with NaN.
class OutputRow {
 public:
  OutputRow(std::vector<std::vector<double>>* columns, const OutputSchema* schema, int row)
      : columns_(columns), schema_(schema), row_(row) {}
  /// The doubles_per_run() slots of column `column` for this run.
  double* Slot(int column) {
    return (*columns_)[static_cast<std::size_t>(column)].data() +
           static_cast<std::size_t>(row_) *
               static_cast<std::size_t>(schema_->columns[column].doubles_per_run());
  }
  /// Sets a scalar column.
  void Set(int column, double value) { *Slot(column) = value; }

 private:
  std::vector<std::vector<double>>* columns_;
  const OutputSchema* schema_;
  int row_;
};

/// The full parameter values of one run, indexed by ParameterId (catalogue order).
using RunParameters = std::vector<double>;

/// What an analysis sees of one run.
struct RunContext {
  const RunParameters& parameters;
  /// The run's model (its aircraft under its model parameters); null when no analysis of the
  /// study needs one.
  const LongitudinalModel* model = nullptr;
  /// Not null in a sweep: set by SIGINT/SIGTERM or a deadline. An analysis that runs long (a time
  /// response) passes it to its integrator and returns AnalysisOutcome::Cancelled() once it fired.
  const std::atomic<bool>* cancel = nullptr;
  /// The run's global index in the design (0, 1, ...), the same whoever runs it (threads, MPI ranks,
  /// shards): run i's turbulence is RunNoise(seed, i) (docs/disturbance.md).
  std::uint64_t run_index = 0;
  /// Empty in a sweep. A subset simulation (engine/rare/landing_risk.h) sets the run's noise as a
  /// point of the standard-normal space instead of RunNoise(seed, run_index).
  std::span<const double> noise_point = {};
  double value(ParameterId id) const { return parameters[static_cast<std::size_t>(id)]; }
};

/// The outcome of one analysis on one run: numerical failures are data, not exceptions.
struct AnalysisOutcome {
  bool ok = true;
  std::string message;  ///< why it failed, or a note on a successful run (e.g. "no boundary: ...")
  /// Stopped by RunContext::cancel before it finished: no result; the run stays pending.
  bool cancelled = false;
  static AnalysisOutcome Ok(std::string note = "") { return {true, std::move(note), false}; }
  static AnalysisOutcome Failed(std::string message) { return {false, std::move(message), false}; }
  static AnalysisOutcome Cancelled() { return {false, "cancelled", true}; }
};

/// One run of a group that an analysis computes at once (Analysis::RunLanes): its context and row,
/// and what Run would have given for it, an outcome or an exception.
struct LaneRun {
  const RunContext* context = nullptr;
  OutputRow* row = nullptr;
  AnalysisOutcome outcome;   ///< what Run returned for this run
  std::exception_ptr error;  ///< or what it threw (then `outcome` means nothing)
};

/// Analysis::RunLanes of an analysis whose simulation has a batch entry point: `make(context)` is a
/// run's entry of the batch, `fly(batch, lanes, cancel)` flies them all (each result bit for bit its
/// run's one at a time) and `record(result, row)` stores each. A batch that throws (it validates every
/// run before flying any) gives every run to `one_at_a_time` (the base class's RunLanes), so that each
/// gets its own outcome or exception, as without lanes.
template <class Make, class Fly, class Record, class OneAtATime>
void FlyInLanes(std::span<LaneRun> runs, int lanes, const Make& make, const Fly& fly, const Record& record,
                const OneAtATime& one_at_a_time) {
  if (runs.empty()) return;
  const std::atomic<bool>* cancel = runs.front().context->cancel;
  std::vector<decltype(make(*runs.front().context))> batch;
  batch.reserve(runs.size());
  for (const LaneRun& run : runs) {
    GESWEEP_DEMAND(run.context->cancel == cancel);
    batch.push_back(make(*run.context));
  }
  decltype(fly(batch, lanes, cancel)) results;
  try {
    results = fly(batch, lanes, cancel);
  } catch (...) {
    one_at_a_time();
    return;
  }
  for (std::size_t i = 0; i < runs.size(); ++i) runs[i].outcome = record(results[i], *runs[i].row);
}

/// The lane widths a sweep takes (`gesweep run --lanes`, docs/sweep.md): runs computed W at a time in
/// the lanes of SIMD vectors, W = 1 being one at a time: the open loop's and the landing's lanes
/// (kOpenLoopBatchWidths, open_loop_analysis.cc checks it; SimulateLandingBatch takes the same).
inline constexpr int kLaneWidths[] = {1, 2, 4, 8};

/// What a study says about storage that analyses need when declaring their columns.
struct StorageOptions {
  bool time_series = false;   ///< store time series (open_loop, landing)
  double output_dt_s = 0.05;  ///< sample interval of stored series
};

/// One per-run analysis.
class Analysis {
 public:
  virtual ~Analysis() = default;
  /// Its name in study files and archive paths ("modes").
  virtual std::string_view name() const = 0;
  /// Whether it needs the run's LongitudinalModel (and so an aircraft file).
  virtual bool needs_model() const { return true; }
  /// The parameters it reads besides the model parameters (e.g. height_m, speed_mps).
  virtual std::vector<ParameterId> parameters_used() const = 0;
  /// Typical cost of one run on one core, µs: sizes the write batches (docs/sweep.md).
  virtual double nominal_run_cost_us() const = 0;
  /// Adds its columns (and time axes) to the schema and remembers their indices. Called once.
  virtual void DeclareOutputs(OutputSchema& schema, const StorageOptions& storage) = 0;
  /// Checks that a run's parameters suit this analysis beyond each parameter's own range (e.g. a
  /// start speed above the aircraft's stall speed). Returns what was expected, or "" when they do.
  /// Called before the sweep on the extreme values of the design (SweepPlan), so a bad study is
  /// refused before the first run. `aircraft` is null when the study has none.
  virtual std::string CheckRun(const RunParameters& parameters, const Aircraft* aircraft) const {
    (void)parameters;
    (void)aircraft;
    return "";
  }
  /// Its settings as read from [analyses.<name>] (describe.h), defaults included: the study keys of
  /// its description, for the schema check and the column manifest. Empty when it has none described.
  virtual std::vector<FieldRecord> SettingsFields() const { return {}; }
  /// Fills its columns for one run. Thread-safe (const, no shared mutable state). May throw; the
  /// runner turns any exception into a failed run.
  virtual AnalysisOutcome Run(const RunContext& context, OutputRow& row) const = 0;
  /// Whether RunLanes computes several runs at once faster than Run one at a time (a time response
  /// flown in SIMD lanes): the runner then hands it its runs in groups. Default: false.
  virtual bool takes_lanes() const { return false; }
  /// Fills its columns for a group of runs, `lanes` (one of kLaneWidths) at a time where it can. Each
  /// run's columns and its outcome or exception are exactly what Run gives for it, bit for bit,
  /// whatever the width and whichever runs share the group. Thread-safe, as Run. Default: Run for
  /// each run in turn, its exception kept in LaneRun::error.
  virtual void RunLanes(std::span<LaneRun> runs, int lanes) const {
    (void)lanes;
    for (LaneRun& run : runs) {
      try {
        run.outcome = Run(*run.context, *run.row);
      } catch (...) {
        run.error = std::current_exception();
      }
    }
  }
  /// The dimension of the run's noise as a point of the standard-normal space (RunContext::noise_point):
  /// 0 for an analysis that draws no noise (default) or a run without turbulence.
  virtual std::uint64_t NoiseDimension(const RunParameters& parameters, const Aircraft& aircraft) const {
    (void)parameters;
    (void)aircraft;
    return 0;
  }
  /// The interval, s, at which the noise point's streams are held (docs/disturbance.md); 0 for an
  /// analysis that draws no noise (default).
  virtual double NoiseSampleInterval(const RunParameters& parameters) const {
    (void)parameters;
    return 0;
  }
};

/// Builds an analysis from its settings table ([analyses.<name>]); throws InputError on bad or
/// unknown settings. `aircraft` is null when the study has no aircraft.
using AnalysisFactory = std::unique_ptr<Analysis> (*)(const TomlSection& settings, const Aircraft* aircraft);

/// A registered analysis.
struct AnalysisEntry {
  std::string_view name;
  std::string_view description;
  bool needs_model;         ///< the factory is called with a non-null aircraft only when true
  AnalysisFactory factory;  ///< null when not available in this build
  /// Its place in the registry, and so the place of its columns in an archive: the registry lists
  /// the analyses by this key, whatever the order in which their files register (static
  /// initialisation). Keys are unique; a new analysis takes a free key between its neighbours'.
  int order = 0;
  std::string_view unavailable_reason = {};
};

/// Every analysis the engine knows, available or not, by AnalysisEntry::order (each adapter file
/// registers its own with an AnalysisRegistrar).
const std::vector<AnalysisEntry>& AnalysisRegistry();

/// Adds an analysis to the registry at static-initialisation time: one line in its adapter's file,
///
///     const AnalysisRegistrar kRegistrar{{"modes", "eigenvalues ...", true, &MakeModes, 100}};
///
/// GESWEEP_DEMAND that its name and its order key are new. gesweep_analyses is linked whole
/// (engine/analyses/CMakeLists.txt), so an adapter that nothing names is still in every program.
struct AnalysisRegistrar {
  explicit AnalysisRegistrar(const AnalysisEntry& entry);
};

/// The registered analysis `name` built from `settings` (its factory); GESWEEP_DEMAND that it is
/// registered and available. For the engine's own synthetic studies and for tests.
std::unique_ptr<Analysis> MakeAnalysis(std::string_view name, const TomlSection& settings,
                                       const Aircraft* aircraft);

}  // namespace gesweep
