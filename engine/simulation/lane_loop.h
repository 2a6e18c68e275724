#pragma once
/// What the lanes of a batch share, whatever they fly (docs/performance.md, "Batched time responses"):
/// the lockstep loop and a lane's run bookkeeping (LaneFleet), used by the open loop's
/// (SimulateOpenLoopBatch, open_loop.cc) and the landing's (SimulateLandingBatch,
/// control/landing_simulation.cc) lanes.

#include <array>
#include <atomic>
#include <cstddef>
#include <span>
#include <vector>

#include "engine/simulation/integrator.h"

namespace gesweep::lanes {

/// One lane's step: its ends and the states and derivatives there.
template <class State>
struct LaneStep {
  double t, t_new;
  State x, f, x_new, f_new;
};

/// Lane i of a state held as N rows of W doubles (component c of lane i at v[c][i]), as one run's.
template <class State, std::size_t N, std::size_t W>
State LaneOf(const double (&v)[N][W], int i) {
  State s;
  for (std::size_t c = 0; c < N; ++c) s[c] = v[c][i];
  return s;
}

/// Writes one run's state `s` into lane i of `v` (as LaneOf reads it).
template <class State, std::size_t N, std::size_t W>
void SetLaneOf(double (&v)[N][W], int i, const State& s) {
  for (std::size_t c = 0; c < N; ++c) v[c][i] = s[c];
}

/// What a run flown in a lane keeps of IntegrateWith's bookkeeping for one run with Rk4Method and
/// honoured breakpoints, so that every scalar decision of the lane is the one Integrate takes for
/// that run. Each kind of lane's run derives from it.
template <class P, class Config>
struct LaneRunBase {
  using Problem = P;
  static constexpr int N = P::kDimension;
  using State = typename P::State;
  using Events = std::array<double, P::kEventCount>;

  std::size_t run = 0;  // index in the batch's runs
  const Config* config = nullptr;
  IntegrationResult<N> result;
  double t = 0;
  double end_s = 0;
  long grid_index = 0;
  std::size_t next_breakpoint = 0;
  int segment = 0;
  Events g_previous{};
};

/// W lanes flying the runs of a batch in lockstep, in the batch's `order`, each run's result in
/// `results`. The lanes' states and derivatives are Arrays' x and f, N rows of W doubles. What is
/// here is the same for every kind of lane: the lockstep loop, taking the next run into a lane, a
/// run's finish, the step's end on the lane's RK4 grid and the step's interpolant. Lanes derives from
/// LaneFleet<Lanes, ...> (CRTP) and gives:
///   bool Start(int i, std::size_t run): starts `run` in lane i (IntegrateWith's start up to the
///       derivative at t = 0, written into lane i of x and f); false when the run is complete
///       without flying (its result written);
///   void Idle(int i): a lane left without a run (it flies values that are never read);
///   void PrepareStep(int i): an active lane's next step set up in the arrays;
///   void StepAll(): the step of every active lane at once (the kernels and each lane's completion);
///   void Record(int i): the finished run's result from its lane.
template <class Lanes, int W, class Run, class Result, class Arrays>
class LaneFleet {
 public:
  using State = typename Run::State;
  static constexpr int N = Run::N;

  /// Flies every run: fills each lane, then, while a lane is active, prepares the step of every
  /// active lane and takes it for all at once. A set `cancel` finishes every active lane as cancelled.
  void FlyAll() {
    for (int i = 0; i < W; ++i) Refill(i);
    while (active_count_ > 0) {
      if (cancel_ != nullptr && cancel_->load(std::memory_order_relaxed)) {
        for (int i = 0; i < W; ++i) {
          if (active_[i]) Finish(i, IntegrationStatus::kCancelled);
        }
        continue;
      }
      for (int i = 0; i < W; ++i) {
        if (active_[i]) self().PrepareStep(i);
      }
      self().StepAll();
    }
  }

 protected:
  using Step = LaneStep<State>;

  LaneFleet(std::span<const std::size_t> order, std::vector<Result>& results, const std::atomic<bool>* cancel)
      : order_(order), results_(results), cancel_(cancel) {}

  // The lane's state as one run's, and back.
  static State Lane(const auto& v, int i) { return LaneOf<State>(v, i); }
  static void SetLane(auto& v, int i, const State& s) { SetLaneOf(v, i, s); }

  // Starts the next run of the order in lane i, or leaves the lane idle when none is left. A run whose
  // start is not finite finishes at once (and the lane takes the next).
  void Refill(int i) {
    while (next_ < order_.size()) {
      const std::size_t run = order_[next_++];
      if (!self().Start(i, run)) continue;
      active_[i] = true;
      ++active_count_;
      if (!integrator_detail::AllFinite<N>(Lane(a_.f, i)) ||
          !integrator_detail::AllFinite<N>(Lane(a_.x, i))) {
        Finish(i, IntegrationStatus::kNonFinite);
      }
      return;
    }
    self().Idle(i);
  }

  // IntegrateWith's finish of lane i's run, its result (Record), and the lane's next run.
  void Finish(int i, IntegrationStatus status) {
    Run& lane = lane_[i];
    lane.result.status = status;
    lane.result.end_time_s = lane.t;
    lane.result.final_state = Lane(a_.x, i);
    lane.result.final_segment = lane.segment;
    self().Record(i);
    active_[i] = false;
    --active_count_;
    Refill(i);
  }

  // Rk4Method::Advance's end of lane i's next step: on its grid n·step_s, or its limit (the next of
  // `breakpoints`, or the run's end).
  double StepEnd(int i, const std::vector<double>& breakpoints, double step_s) {
    Run& lane = lane_[i];
    double t_limit = lane.end_s;
    if (lane.next_breakpoint < breakpoints.size() && breakpoints[lane.next_breakpoint] < lane.end_s) {
      t_limit = breakpoints[lane.next_breakpoint];
    }
    return integrator_detail::Rk4Method<N>::StepEnd(0.0, step_s, lane.grid_index, lane.t, t_limit);
  }

  // The state at tau in [t, t_new]: exactly the step's end states at its ends, the cubic Hermite
  // interpolant (Rk4Method's) between them.
  static void Interpolate(const Step& step, double tau, State& out) {
    if (tau == step.t_new) {
      out = step.x_new;
    } else if (tau == step.t) {
      out = step.x;
    } else {
      integrator_detail::Rk4Method<N>::Interpolate(tau, step.t, step.x, step.f, step.t_new, step.x_new,
                                                   step.f_new, out);
    }
  }

  std::span<const std::size_t> order_;
  std::vector<Result>& results_;
  const std::atomic<bool>* cancel_;
  std::size_t next_ = 0;
  int active_count_ = 0;
  std::array<Run, W> lane_;
  std::array<bool, W> active_{};
  Arrays a_;

 private:
  Lanes& self() { return static_cast<Lanes&>(*this); }
};

}  // namespace gesweep::lanes
