#include "engine/mpi/mpi_runner.h"

#include <mpi.h>
#include <tbb/concurrent_queue.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>
#include <vector>

#include "engine/common/errors.h"
#include "engine/sweep/runner.h"

namespace gesweep {
namespace {

// Message tags of the protocol between the ranks and rank 0 (docs/cluster.md, "MPI").
constexpr int kTagRequest = 1;  // rank -> 0: int32, batches wanted
constexpr int kTagAssign = 2;   // 0 -> rank: int64[n], batch numbers (n = 0: no more work)
constexpr int kTagResult = 3;   // rank -> 0: one finished batch, packed (PackBlock)
constexpr int kTagDone = 4;     // rank -> 0: int64[2], batches sent and runs computed; the rank's last message

// An idle main thread sleeps this long between polls: MPI's own blocking calls spin, which on a
// shared or oversubscribed node takes a core from the compute threads.
constexpr auto kIdlePoll = std::chrono::microseconds(200);
// Batches rank 0 can hold received but not yet written: with the compute threads' buffers, this
// bounds rank 0's memory; a full queue makes the senders wait (back-pressure).
constexpr int kReceiveBuffers = 8;
// Progress log line interval on rank 0 (a log, not a terminal bar: mpirun pipes stderr).
constexpr double kLogInterval_s = 5.0;

void CheckMpi(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  std::cerr << "gesweep: MPI error in " << what << ": " << std::string(text, static_cast<std::size_t>(length)) << "\n";
  MPI_Abort(MPI_COMM_WORLD, 1);
}

// Initialises MPI for the runner's lifetime (main thread only calls MPI: FUNNELED), and finalises
// it when this object initialised it, also during unwinding.
class MpiSession {
 public:
  MpiSession() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;
      CheckMpi(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
      owner_ = true;
      GESWEEP_DEMAND(provided >= MPI_THREAD_FUNNELED);
    }
  }
  ~MpiSession() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (owner_ && !finalized) MPI_Finalize();
  }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

 private:
  bool owner_ = false;
};

// ---- Packing a batch (bit-exact copies of the values; ranks of one job share the byte order) ----

template <typename T>
void Append(std::vector<char>& out, const T* values, std::size_t count) {
  const auto bytes = count * sizeof(T);
  const std::size_t at = out.size();
  out.resize(at + bytes);
  if (bytes) std::memcpy(out.data() + at, values, bytes);
}

class Unpacker {
 public:
  Unpacker(const char* data, std::size_t size) : data_(data), size_(size) {}
  template <typename T>
  void Take(T* values, std::size_t count) {
    const auto bytes = count * sizeof(T);
    GESWEEP_DEMAND(at_ + bytes <= size_);
    if (bytes) std::memcpy(values, data_ + at_, bytes);
    at_ += bytes;
  }
  bool AtEnd() const { return at_ == size_; }

 private:
  const char* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

void PackBlock(const SweepPlan& plan, const ResultBlock& block, std::vector<char>& out) {
  out.clear();
  out.reserve(static_cast<std::size_t>(BatchMessageBytes(plan, block.rows)));
  const auto n = static_cast<std::size_t>(block.rows);
  const std::int64_t header[2] = {block.block_index, block.rows};
  Append(out, header, 2);
  Append(out, block.design_index.data(), n);
  Append(out, block.run_id.data(), n);
  Append(out, block.status.data(), n);
  for (std::size_t c = 0; c < block.design.size(); ++c) Append(out, block.design[c].data(), n);
  const auto& columns = plan.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    Append(out, block.results[c].data(), n * static_cast<std::size_t>(columns[c].doubles_per_run()));
  }
  for (std::size_t r = 0; r < n; ++r) {
    const auto length = static_cast<std::uint16_t>(block.message[r].size());
    Append(out, &length, 1);
    Append(out, block.message[r].data(), length);
  }
}

// Unpacks a batch into `block` (allocated for `plan`) and checks that it lands where the plan puts
// it: a batch's rows are the design runs first_run + block_index·chunk_runs onwards.
void UnpackBlock(const SweepPlan& plan, const char* data, std::size_t size, ResultBlock& block) {
  Unpacker in(data, size);
  std::int64_t header[2] = {0, 0};
  in.Take(header, 2);
  block.block_index = header[0];
  block.first_row = header[0] * plan.chunk_runs();
  GESWEEP_DEMAND(header[0] >= 0 && header[0] < plan.block_count());
  block.rows = static_cast<int>(header[1]);
  GESWEEP_DEMAND(block.rows == std::min<std::int64_t>(plan.chunk_runs(), plan.run_count() - block.first_row));
  const auto n = static_cast<std::size_t>(block.rows);
  in.Take(block.design_index.data(), n);
  in.Take(block.run_id.data(), n);
  in.Take(block.status.data(), n);
  for (std::size_t r = 0; r < n; ++r) {
    GESWEEP_DEMAND(block.design_index[r] == plan.first_run() + block.first_row + static_cast<std::int64_t>(r));
  }
  for (std::size_t c = 0; c < block.design.size(); ++c) in.Take(block.design[c].data(), n);
  const auto& columns = plan.schema().columns;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    in.Take(block.results[c].data(), n * static_cast<std::size_t>(columns[c].doubles_per_run()));
  }
  for (std::size_t r = 0; r < n; ++r) {
    std::uint16_t length = 0;
    in.Take(&length, 1);
    GESWEEP_DEMAND(length <= kMessageLength);
    block.message[r].resize(length);
    in.Take(block.message[r].data(), length);
  }
  GESWEEP_DEMAND(in.AtEnd());
}

// ---- One rank's compute threads ----

// Computes batches with oneTBB, the way RunSweep does (a pipeline of batches, the runs of a batch
// in parallel, a workspace per thread), but fed batch numbers one at a time from outside and
// handing finished batches back through a queue: the main thread talks MPI meanwhile.
class BatchEngine {
 public:
  BatchEngine(const SweepPlan& plan, int threads, int buffers) : plan_(plan), threads_(threads) {
    pool_.resize(static_cast<std::size_t>(buffers));
    for (auto& block : pool_) {
      block.Allocate(plan);
      free_.push(&block);
    }
    thread_ = std::thread([this] { Loop(); });
  }
  ~BatchEngine() {
    Close();
    thread_.join();
  }
  BatchEngine(const BatchEngine&) = delete;
  BatchEngine& operator=(const BatchEngine&) = delete;

  /// Queues batch `block_index` (never blocks).
  void Push(std::int64_t block_index) { todo_.push(block_index); }
  /// No more batches: the engine finishes the queued ones and stops.
  void Close() {
    if (!closed_) todo_.push(-1);
    closed_ = true;
  }
  /// A finished batch, if any; give it back with Release once sent or written.
  bool TryPop(ResultBlock*& block) { return done_.try_pop(block); }
  /// Returns a batch buffer (any thread).
  void Release(ResultBlock* block) { free_.push(block); }
  /// The exception that stopped the compute threads (none for numerical failures: those are data).
  std::exception_ptr error() const { return finished_.load() ? error_ : nullptr; }
  std::int64_t runs_done() const { return runs_done_.load(); }

 private:
  void Loop() {
    const int tokens = 2 * threads_;  // as RunSweep: two batches in flight per thread
    tbb::enumerable_thread_specific<RunWorkspace> workspaces([this] { return RunWorkspace(plan_); });
    try {
      tbb::task_arena arena(threads_);
      arena.execute([&] {
        tbb::parallel_pipeline(
            static_cast<std::size_t>(tokens),
            tbb::make_filter<void, ResultBlock*>(
                tbb::filter_mode::serial_in_order,
                [&](tbb::flow_control& control) -> ResultBlock* {
                  std::int64_t index = -1;
                  todo_.pop(index);
                  if (index < 0) {
                    control.stop();
                    return nullptr;
                  }
                  ResultBlock* block = nullptr;
                  free_.pop(block);
                  block->Reset(plan_, index);
                  return block;
                }) &
                tbb::make_filter<ResultBlock*, ResultBlock*>(
                    tbb::filter_mode::parallel,
                    [&](ResultBlock* block) {
                      tbb::parallel_for(tbb::blocked_range<int>(0, block->rows, 1),
                                        [&](const tbb::blocked_range<int>& range) {
                                          RunWorkspace& workspace = workspaces.local();
                                          for (int row = range.begin(); row != range.end(); ++row) {
                                            ExecuteRun(plan_, block->design_index[static_cast<std::size_t>(row)],
                                                       workspace, *block, row);
                                          }
                                        });
                      runs_done_.fetch_add(block->rows, std::memory_order_relaxed);
                      return block;
                    }) &
                tbb::make_filter<ResultBlock*, void>(tbb::filter_mode::serial_out_of_order,
                                                     [&](ResultBlock* block) { done_.push(block); }));
      });
    } catch (...) {
      error_ = std::current_exception();
    }
    finished_.store(true);
  }

  const SweepPlan& plan_;
  int threads_;
  std::vector<ResultBlock> pool_;
  tbb::concurrent_bounded_queue<ResultBlock*> free_;
  tbb::concurrent_bounded_queue<std::int64_t> todo_;
  tbb::concurrent_queue<ResultBlock*> done_;
  std::atomic<std::int64_t> runs_done_{0};
  std::exception_ptr error_;
  std::atomic<bool> finished_{false};
  bool closed_ = false;
  std::thread thread_;
};

// Stops the job when a rank's compute threads died of something other than a run's failure (which
// is data): the other ranks would otherwise wait for its batches forever.
void AbortOnEngineError(const BatchEngine& engine, int rank) {
  if (const std::exception_ptr error = engine.error()) {
    try {
      std::rethrow_exception(error);
    } catch (const std::exception& e) {
      std::cerr << "gesweep: error: rank " << rank << ": " << e.what() << "\n";
    } catch (...) {
      std::cerr << "gesweep: error: rank " << rank << ": unknown exception\n";
    }
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
}

bool Cancelled(const MpiRunOptions& options) { return options.cancel != nullptr && options.cancel->load(); }

// What every rank must agree on before anything is written: the same study (fingerprint), design,
// shard, batch size and output columns.
std::vector<std::int64_t> PlanSignature(const SweepPlan& plan) {
  std::int64_t doubles = 0;
  for (const auto& column : plan.schema().columns) doubles += column.doubles_per_run();
  std::int64_t fingerprint = 0;
  std::memcpy(&fingerprint, &plan.study().fingerprint, sizeof fingerprint);
  return {fingerprint,      plan.design_runs(), plan.first_run(), plan.run_count(),
          plan.chunk_runs(), plan.design().column_count(), static_cast<std::int64_t>(plan.schema().columns.size()),
          doubles};
}

// ---- A compute rank (rank > 0) ----

void RunWorkerRank(const SweepPlan& plan, const MpiRunOptions& options, int threads, int target, int rank,
                   MpiSweepReport& report) {
  BatchEngine engine(plan, threads, target + 1);
  std::vector<char> buffer;
  std::vector<std::int64_t> assigned;
  int outstanding = 0;  // batches received and not yet sent back
  bool request_pending = false;
  bool exhausted = false;
  std::int64_t sent = 0;
  for (;;) {
    bool progressed = false;
    AbortOnEngineError(engine, rank);
    if (!request_pending && !exhausted && Cancelled(options)) {
      exhausted = true;  // ask for nothing more; finish and send what we hold
      engine.Close();
    }
    if (!request_pending && !exhausted && outstanding < target) {
      const int want = target - outstanding;
      CheckMpi(MPI_Send(&want, 1, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD), "MPI_Send request");
      request_pending = true;
      progressed = true;
    }
    if (request_pending) {
      int ready = 0;
      MPI_Status status;
      CheckMpi(MPI_Iprobe(0, kTagAssign, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe assign");
      if (ready) {
        int count = 0;
        MPI_Get_count(&status, MPI_INT64_T, &count);
        assigned.resize(static_cast<std::size_t>(count));
        CheckMpi(MPI_Recv(assigned.data(), count, MPI_INT64_T, 0, kTagAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
                 "MPI_Recv assign");
        request_pending = false;
        progressed = true;
        if (count == 0) {
          exhausted = true;
          engine.Close();
        }
        for (const std::int64_t index : assigned) engine.Push(index);
        outstanding += count;
      }
    }
    ResultBlock* block = nullptr;
    while (engine.TryPop(block)) {
      PackBlock(plan, *block, buffer);
      engine.Release(block);
      CheckMpi(MPI_Send(buffer.data(), static_cast<int>(buffer.size()), MPI_BYTE, 0, kTagResult, MPI_COMM_WORLD),
               "MPI_Send result");
      --outstanding;
      ++sent;
      progressed = true;
    }
    if (exhausted && !request_pending && outstanding == 0) break;
    if (!progressed) std::this_thread::sleep_for(kIdlePoll);
  }
  report.runs_computed = engine.runs_done();
  const std::int64_t done[2] = {sent, report.runs_computed};
  CheckMpi(MPI_Send(done, 2, MPI_INT64_T, 0, kTagDone, MPI_COMM_WORLD), "MPI_Send done");
}

// ---- Rank 0: dispatcher, writer, and a compute rank too ----

struct WriteItem {
  ResultBlock* block = nullptr;
  bool local = false;  // from rank 0's own engine (else a receive buffer)
};

struct Rank0Outcome {
  bool cancelled = false;
  std::exception_ptr writer_error;
  std::vector<std::int64_t> runs_per_rank;
};

Rank0Outcome RunRank0(const SweepPlan& plan, const std::vector<std::int64_t>& pending, ResultSink& sink,
                      const MpiRunOptions& options, int threads, int target, int ranks, MpiSweepReport& report) {
  Rank0Outcome outcome;
  outcome.runs_per_rank.assign(static_cast<std::size_t>(ranks), 0);
  BatchEngine engine(plan, threads, target + kReceiveBuffers + 1);

  std::vector<ResultBlock> receive_pool(kReceiveBuffers);
  tbb::concurrent_queue<ResultBlock*> receive_free;
  for (auto& block : receive_pool) {
    block.Allocate(plan);
    receive_free.push(&block);
  }

  // The one writer thread, as in RunSweep: batches in any order, each at its design position.
  tbb::concurrent_bounded_queue<WriteItem> write_queue;
  std::atomic<bool> writer_failed{false};
  std::atomic<std::int64_t> runs_written{0};
  std::thread writer([&] {
    for (;;) {
      WriteItem item;
      write_queue.pop(item);
      if (item.block == nullptr) break;
      if (!writer_failed.load()) {
        try {
          sink.Write(*item.block);
          runs_written.fetch_add(item.block->rows, std::memory_order_relaxed);
        } catch (...) {
          outcome.writer_error = std::current_exception();
          writer_failed.store(true);
        }
      }
      if (item.local) {
        engine.Release(item.block);
      } else {
        receive_free.push(item.block);
      }
    }
  });

  const auto total = static_cast<std::int64_t>(pending.size());
  std::int64_t next = 0;
  int local_outstanding = 0;
  bool stop_assigning = false;
  int workers_done = 0;
  std::int64_t results_expected = 0, results_received = 0;
  std::vector<char> buffer;
  std::vector<std::int64_t> grant;
  const auto start = std::chrono::steady_clock::now();
  auto last_log = start;
  // Guided self-scheduling: a rank gets at most its share of what is left, so the last batches
  // spread over every rank instead of queueing behind one.
  auto share = [&](std::int64_t want) {
    const std::int64_t remaining = total - next;
    const std::int64_t fair = std::max<std::int64_t>(1, remaining / (2 * ranks));
    return std::min({want, fair, remaining});
  };

  for (;;) {
    bool progressed = false;
    AbortOnEngineError(engine, 0);
    if (!stop_assigning && (Cancelled(options) || writer_failed.load())) {
      stop_assigning = true;
      outcome.cancelled = next < total;
    }
    const bool no_more = stop_assigning || next >= total;
    while (!no_more && next < total && local_outstanding < target) {
      engine.Push(pending[static_cast<std::size_t>(next++)]);
      ++local_outstanding;
      progressed = true;
    }
    if (stop_assigning || next >= total) engine.Close();

    ResultBlock* block = nullptr;
    while (engine.TryPop(block)) {
      write_queue.push({block, true});
      --local_outstanding;
      progressed = true;
    }

    int ready = 0;
    MPI_Status status;
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe request");
    if (ready) {
      int want = 0;
      CheckMpi(MPI_Recv(&want, 1, MPI_INT, status.MPI_SOURCE, kTagRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
               "MPI_Recv request");
      const std::int64_t n = (stop_assigning || next >= total) ? 0 : share(want);
      grant.assign(pending.begin() + next, pending.begin() + next + n);
      next += n;
      CheckMpi(MPI_Send(grant.data(), static_cast<int>(n), MPI_INT64_T, status.MPI_SOURCE, kTagAssign, MPI_COMM_WORLD),
               "MPI_Send assign");
      progressed = true;
    }
    ResultBlock* receive_block = nullptr;
    if (receive_free.try_pop(receive_block)) {
      CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe result");
      if (ready) {
        int bytes = 0;
        MPI_Get_count(&status, MPI_BYTE, &bytes);
        buffer.resize(static_cast<std::size_t>(bytes));
        CheckMpi(MPI_Recv(buffer.data(), bytes, MPI_BYTE, status.MPI_SOURCE, kTagResult, MPI_COMM_WORLD,
                          MPI_STATUS_IGNORE),
                 "MPI_Recv result");
        UnpackBlock(plan, buffer.data(), buffer.size(), *receive_block);
        write_queue.push({receive_block, false});
        ++results_received;
        progressed = true;
      } else {
        receive_free.push(receive_block);
      }
    }
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagDone, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe done");
    if (ready) {
      std::int64_t done[2] = {0, 0};
      CheckMpi(MPI_Recv(done, 2, MPI_INT64_T, status.MPI_SOURCE, kTagDone, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
               "MPI_Recv done");
      results_expected += done[0];
      outcome.runs_per_rank[static_cast<std::size_t>(status.MPI_SOURCE)] = done[1];
      ++workers_done;
      progressed = true;
    }
    if (workers_done == ranks - 1 && results_received == results_expected && (stop_assigning || next >= total) &&
        local_outstanding == 0) {
      break;
    }
    if (!options.quiet) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_log).count() >= kLogInterval_s) {
        last_log = now;
        const double elapsed = std::chrono::duration<double>(now - start).count();
        const std::int64_t written = runs_written.load();
        std::cerr << "gesweep: " << written << " runs written, " << next << "/" << total << " batches handed out, "
                  << std::fixed << std::setprecision(1) << written / elapsed << " runs/s, " << ranks << " ranks\n"
                  << std::flush;
      }
    }
    if (!progressed) std::this_thread::sleep_for(kIdlePoll);
  }
  write_queue.push({nullptr, false});
  writer.join();
  report.runs_computed = engine.runs_done();
  outcome.runs_per_rank[0] = report.runs_computed;
  return outcome;
}

}  // namespace

std::int64_t BatchMessageBytes(const SweepPlan& plan, int rows) {
  std::int64_t doubles = plan.design().column_count();
  for (const auto& column : plan.schema().columns) doubles += column.doubles_per_run();
  // header; per run: design index, run id, status, message length; the doubles
  return 16 + static_cast<std::int64_t>(rows) * (8 + 8 + 1 + 2 + 8 * doubles);
}

int RunStudyMpi(SweepPlan& plan, const MpiRunOptions& options, MpiSweepReport* report_out) {
  MpiSession session;
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  MpiSweepReport report;
  report.ranks = ranks;
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  const int prefetch = options.prefetch_batches > 0 ? options.prefetch_batches : threads;
  const int target = 2 * threads + prefetch;  // batches a rank holds: the pipeline's tokens + prefetch

  // 1. Every rank must have built the same plan (a study file that differs between nodes would
  //    otherwise mix two studies in one archive).
  const std::vector<std::int64_t> mine = PlanSignature(plan);
  std::vector<std::int64_t> lowest(mine.size()), highest(mine.size());
  const int n = static_cast<int>(mine.size());
  CheckMpi(MPI_Allreduce(mine.data(), lowest.data(), n, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  CheckMpi(MPI_Allreduce(mine.data(), highest.data(), n, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  if (lowest != highest) {
    if (rank == 0) {
      std::cerr << "gesweep: error: the " << ranks << " MPI ranks did not build the same sweep (study fingerprint, "
                << "design, shard or batch size differ): every node must see the same study and aircraft files\n";
    }
    return 2;
  }

  // 2. Rank 0 opens the archive (the only rank that touches it) and tells the others the batch size
  //    (a resumed archive keeps its own) or that it could not.
  std::unique_ptr<ArchiveWriter> writer;
  ArchiveOpenReport opened;
  std::exception_ptr open_error;
  int open_code = 0;  // 0 ok, 1 I/O error, 2 a person's mistake
  if (rank == 0) {
    try {
      writer = ArchiveWriter::Open(options.output, plan,
                                   RunProvenance{options.command_line + " (" + std::to_string(ranks) + " MPI ranks)",
                                                 threads * ranks},
                                   options.mode, &opened);
    } catch (const InputError&) {
      open_error = std::current_exception();
      open_code = 2;
    } catch (const ArchiveError& e) {
      std::cerr << "gesweep: error: " << e.what() << "\n";
      open_code = 1;
    }
  }
  std::int64_t setup[2] = {open_code, plan.chunk_runs()};
  CheckMpi(MPI_Bcast(setup, 2, MPI_INT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
  if (setup[0] != 0) {
    if (open_error) std::rethrow_exception(open_error);  // the CLI prints it: one line, exit 2
    return static_cast<int>(setup[0]);
  }
  if (rank != 0) plan.set_chunk_runs(static_cast<int>(setup[1]));

  if (rank != 0) {
    RunWorkerRank(plan, options, threads, target, rank, report);
    std::int64_t computed = report.runs_computed;
    MPI_Gather(&computed, 1, MPI_INT64_T, nullptr, 0, MPI_INT64_T, 0, MPI_COMM_WORLD);
    std::int64_t exit_code = 0;
    CheckMpi(MPI_Bcast(&exit_code, 1, MPI_INT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
    if (report_out) *report_out = report;
    return static_cast<int>(exit_code);
  }

  const std::int64_t to_do = plan.run_count() - opened.runs_complete;
  if (!options.quiet) {
    std::cerr << "gesweep: " << plan.study().name << ": " << plan.design_runs() << " runs";
    if (plan.shard().count > 1) {
      std::cerr << ", shard " << plan.shard().index << "/" << plan.shard().count;
    }
    std::cerr << ", " << ranks << " MPI rank" << (ranks > 1 ? "s" : "") << " x " << threads << " thread"
              << (threads > 1 ? "s" : "") << " -> " << options.output.string() << "\n";
    if (opened.kind != ArchiveOpenReport::Kind::kCreated) {
      std::cerr << "gesweep: resuming: " << opened.runs_complete << " runs already complete, " << to_do
                << " to run\n";
    }
  }
  const auto start = std::chrono::steady_clock::now();
  Rank0Outcome outcome = RunRank0(plan, opened.pending_blocks, *writer, options, threads, target, ranks, report);
  std::vector<std::int64_t> per_rank(static_cast<std::size_t>(ranks), 0);
  std::int64_t computed = report.runs_computed;
  MPI_Gather(&computed, 1, MPI_INT64_T, per_rank.data(), 1, MPI_INT64_T, 0, MPI_COMM_WORLD);

  std::int64_t exit_code = 0;
  if (outcome.writer_error) {
    try {
      std::rethrow_exception(outcome.writer_error);
    } catch (const std::exception& e) {
      std::cerr << "gesweep: error: " << e.what() << " (the runs written so far are kept; fix the cause and rerun "
                << "with --resume)\n";
    }
    exit_code = 1;
  } else {
    try {
      writer->Finish();
      report.runs_ok = writer->runs_ok();
      report.runs_failed = writer->runs_failed();
      report.runs_pending = writer->runs_pending();
    } catch (const ArchiveError& e) {
      std::cerr << "gesweep: error: " << e.what() << "\n";
      exit_code = 1;
    }
  }
  report.cancelled = outcome.cancelled;
  if (exit_code == 0) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::int64_t ran = 0;
    for (const std::int64_t r : per_rank) ran += r;
    if (!options.quiet || report.runs_failed > 0 || report.cancelled) {
      std::ostringstream line;
      line << "gesweep: " << ran << " runs in " << std::fixed << std::setprecision(1) << elapsed << " s ("
           << (elapsed > 0 ? ran / elapsed : 0.0) << " runs/s) on " << ranks << " ranks (runs per rank:";
      for (const std::int64_t r : per_rank) line << " " << r;
      line << "); archive: " << report.runs_ok << " ok, " << report.runs_failed << " failed, " << report.runs_pending
           << " pending -> " << options.output.string() << "\n";
      std::cerr << line.str();
    }
    if (report.cancelled) {
      const int signal = options.signal ? options.signal->load() : 0;
      std::cerr << "gesweep: stopped by signal " << signal << "; continue with --resume\n";
      exit_code = 128 + signal;
    } else if (report.runs_failed > 0) {
      std::cerr << "gesweep: " << report.runs_failed << " runs failed; their status is 'failed' and runs/message says why\n";
      exit_code = 3;
    }
  }
  CheckMpi(MPI_Bcast(&exit_code, 1, MPI_INT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
  writer.reset();
  if (report_out) *report_out = report;
  return static_cast<int>(exit_code);
}

}  // namespace gesweep
