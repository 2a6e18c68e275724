#pragma once
/// SIGINT and SIGTERM as a cancellation flag (docs/sweep.md, "Stopping a sweep"): while a
/// SignalCancellation lives, either signal sets its flag instead of killing the process. The engine
/// reads the flag between integration steps (simulation, landing) and between runs, so a sweep,
/// `simulate` or `land` stops within a step, keeps what is complete, and the command exits with
/// 128 + the signal (130 for SIGINT, 143 for SIGTERM).

#include <atomic>

#include "engine/common/copy_rules.h"

namespace gesweep::cli {

/// Installs the handlers on construction (the flag starts cleared) and restores the previous ones
/// on destruction. One at a time (GESWEEP_DEMAND).
class SignalCancellation {
 public:
  SignalCancellation();
  ~SignalCancellation();
  GESWEEP_NO_COPY(SignalCancellation);

  /// The flag to hand to the engine (RunnerOptions::cancel, SimulateOpenLoop, SimulateLanding).
  const std::atomic<bool>* flag() const;
  /// The signal number received, 0 while none came.
  int signal() const;
  /// The same as an atomic the engine can read (MpiRunOptions::signal).
  const std::atomic<int>* signal_number() const;
  bool cancelled() const { return signal() != 0; }
  /// 128 + the signal: the shell's convention for a process stopped by it.
  int exit_code() const { return 128 + signal(); }
};

}  // namespace gesweep::cli
