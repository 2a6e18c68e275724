// The baselines of scripts/bench --python: the engine's own loops, timed from Python.
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- the baselines of scripts/bench --python

/// Discards every batch: the compute-only sweep of tests/bench/sweep_throughput.cc.
class DiscardingSink final : public ResultSink {
 public:
  void Write(const ResultBlock& block) override { runs_ += block.rows; }
  std::int64_t runs() const { return runs_; }

 private:
  std::int64_t runs_ = 0;
};

/// Seconds of a study's whole sweep with its batches discarded (`gesweep run` compute-only), and
/// the runs computed.
py::tuple BenchSweepComputeOnly(const std::string& study_path, int threads) {
  SweepPlan plan(LoadStudy(study_path), ShardSpec{});
  std::vector<std::int64_t> blocks(static_cast<std::size_t>(plan.block_count()));
  for (std::size_t b = 0; b < blocks.size(); ++b) blocks[b] = static_cast<std::int64_t>(b);
  DiscardingSink sink;
  RunnerOptions options;
  options.threads = threads;
  double seconds = 0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    RunSweep(plan, blocks, sink, options, nullptr);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return py::make_tuple(seconds, sink.runs());
}

/// Seconds per call of the engine's boundary search alone (FindBoundary in a C++ loop), the model
/// built once, as gesweep.boundary reuses it.
double BenchBoundarySearch(const PyAircraft& aircraft, double speed_mps, int repetitions) {
  const auto model = aircraft.Model(ModelOptions{});
  py::gil_scoped_release release;
  double sink = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < repetitions; ++i) sink += FindBoundary(*model, speed_mps).height_m.value_or(0.0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  GESWEEP_DEMAND(sink == sink);
  return seconds / repetitions;
}

}  // namespace gesweep::python
