#pragma once
/// What the MPI transports of engine/mpi share (the sweep's runner, mpi_runner.h, and the subset
/// simulation's batch exchange, risk_exchange.h): MPI's start, its errors as exceptions, and how the
/// ranks agree on a person's mistake so that one line is printed and every rank exits alike.
/// Internal to engine/mpi: the only files that include <mpi.h>.

#include <mpi.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

namespace gesweep::mpi {

/// An MPI call failed: nothing any rank can recover from (the caller prints and calls AbortMpi).
class MpiError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws MpiError naming `what` and MPI's text unless `code` is MPI_SUCCESS.
void CheckMpi(int code, const char* what);

/// Initialises MPI when the caller has not (MPI_THREAD_FUNNELED: only the main thread calls MPI);
/// FinalizeMpi (mpi_runner.h) finalises it once the caller has printed the outcome -- a rank that
/// finalises before its output is out may lose it when mpirun is stopping the job.
void EnsureMpi();

/// An idle main thread sleeps this long between polls: MPI's own blocking calls spin, which on a
/// shared or oversubscribed node takes a core from the compute threads.
inline constexpr auto kIdlePoll = std::chrono::microseconds(200);

/// Waits for `request` without spinning: tests it, and sleeps kIdlePoll between tests.
void WaitPolling(MPI_Request& request, const char* what);

/// Rank 0 receives one text from every rank (empty for most).
std::vector<std::string> GatherText(const std::string& text, int ranks);

/// Every rank learns the worst code (2 > 1 > 0) and rank 0 the first text of a rank with that code.
int AgreeOnError(int code, const std::string& text, int rank, int ranks, std::string* first);

}  // namespace gesweep::mpi
