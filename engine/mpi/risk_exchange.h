#pragma once
/// MPI as the transport of a subset simulation's batches (`mpirun -n R gesweep risk STUDY -o ARCHIVE
/// --mpi`; docs/dispersion.md, "On MPI ranks"): every rank of MPI_COMM_WORLD runs the same driver
/// (RunRisk, engine/risk/landing_risk.h) and flies its share of each batch; MpiBatchExchange gives
/// every rank every share (risk::BatchExchange), and the few collectives the command needs around
/// the run: the resume cache from rank 0, the ranks' agreement on an error, a signal and an exit code.
/// Every call is collective (every rank makes it, in the same order) and made from the thread that
/// initialised MPI (MPI_THREAD_FUNNELED).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "engine/risk/landing_risk.h"

namespace gesweep {

class MpiBatchExchange final : public risk::BatchExchange {
 public:
  /// Initialises MPI unless it is (the caller holds an MpiFinalizer, mpi_runner.h).
  MpiBatchExchange();
  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }
  /// Every rank's bytes to every rank (MPI_Iallgatherv, waited for without spinning).
  std::vector<std::vector<unsigned char>> AllGather(std::span<const unsigned char> mine) override;
  /// Rank 0's bytes on every rank (the others pass anything).
  std::vector<unsigned char> Broadcast(std::vector<unsigned char> bytes) const;
  /// The largest of the ranks' values, on every rank.
  std::int64_t Max(std::int64_t value) const;
  /// Whether every rank passed the same value.
  bool Same(std::uint64_t value) const;
  /// Every rank learns the worst code (2 > 1 > 0); rank 0 gets in `first` the text of the first rank
  /// with that code (the one line to print).
  int AgreeOnError(int code, const std::string& text, std::string* first) const;

 private:
  int rank_ = 0, ranks_ = 1;
};

}  // namespace gesweep
