#include "engine/cli/signals.h"

#include <csignal>

#include "engine/common/errors.h"

namespace gesweep::cli {
namespace {

std::atomic<bool> g_cancel{false};
std::atomic<int> g_signal{0};
std::atomic<bool> g_installed{false};
struct sigaction g_previous_int {};
struct sigaction g_previous_term {};

extern "C" void OnSignal(int signal) {
  // Async-signal-safe: lock-free atomics only.
  g_signal.store(signal);
  g_cancel.store(true);
}

}  // namespace

SignalCancellation::SignalCancellation() {
  GESWEEP_DEMAND(!g_installed.exchange(true));
  g_cancel.store(false);
  g_signal.store(0);
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // the writer's and the report's system calls go on
  sigaction(SIGINT, &action, &g_previous_int);
  sigaction(SIGTERM, &action, &g_previous_term);
}

SignalCancellation::~SignalCancellation() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_installed.store(false);
}

const std::atomic<bool>* SignalCancellation::flag() const { return &g_cancel; }

int SignalCancellation::signal() const { return g_signal.load(); }

const std::atomic<int>* SignalCancellation::signal_number() const { return &g_signal; }

}  // namespace gesweep::cli
