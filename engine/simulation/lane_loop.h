#pragma once
/// The lockstep loop of a batch's lanes (docs/performance.md, "Batched time responses"), shared by the
/// open loop's (SimulateOpenLoopBatch, open_loop.cc) and the landing's (SimulateLandingBatch,
/// control/landing_simulation.cc) lanes.

#include <array>
#include <atomic>
#include <cstddef>

#include "engine/simulation/integrator.h"

namespace gesweep::lanes {

/// Flies every run of `lanes` (W of them in lockstep): fills each lane (Refill), then, while a lane
/// is active (`active[i]`, `active_count` of them, kept by the lanes), prepares the step of every
/// active lane (PrepareStep) and takes it for all at once (StepAll: the kernels and each lane's
/// completion). A set `cancel` finishes every active lane as cancelled (Finish).
template <int W, class Lanes>
void FlyLanes(Lanes& lanes, const std::array<bool, W>& active, const int& active_count,
              const std::atomic<bool>* cancel) {
  for (int i = 0; i < W; ++i) lanes.Refill(i);
  while (active_count > 0) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) {
      for (int i = 0; i < W; ++i) {
        if (active[i]) lanes.Finish(i, IntegrationStatus::kCancelled);
      }
      continue;
    }
    for (int i = 0; i < W; ++i) {
      if (active[i]) lanes.PrepareStep(i);
    }
    lanes.StepAll();
  }
}

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

}  // namespace gesweep::lanes
