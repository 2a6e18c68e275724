#include "engine/mpi/mpi_runner.h"

#include <mpi.h>
#include <tbb/concurrent_queue.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "engine/archive/archive_layout.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/mpi/mpi_common.h"
#include "engine/sweep/study.h"

namespace gesweep {
namespace {

using mpi::AgreeOnError;
using mpi::CheckMpi;
using mpi::EnsureMpi;
using mpi::kIdlePoll;

// Message tags (docs/cluster.md, "MPI").
constexpr int kTagRequest = 1;  // rank -> 0: int64[3] {batches wanted (0: I am done), runs done, runs failed}
constexpr int kTagGrant = 2;    // 0 -> rank: int64[n] batch numbers (n = 0: no more)
constexpr int kTagResult = 3;   // rank -> the owning node's writer: one filtered batch (PackBlock)
constexpr int kTagFinished = 4;  // rank -> each writer: int64, the batches it sent that writer
constexpr int kTagError = 5;     // rank -> 0: char[], why it cannot go on (stop handing out batches)

// Filtered batches a rank holds for sending (back-pressure on its pipeline beyond that).
constexpr int kOutgoingBatches = 8;

// ---- Who is who ----

struct Topology {
  int rank = 0, ranks = 1;
  int node = 0, nodes = 1;       // node index: the order of the nodes' writers by world rank
  bool writer = false;           // lowest rank of its node
  std::vector<int> writer_rank;  // by node
  std::vector<int> node_of;      // by world rank
};

int RanksPerNode(const MpiRunOptions& options) {
  if (options.ranks_per_node > 0) return options.ranks_per_node;
  if (const char* env = std::getenv("GESWEEP_RANKS_PER_NODE"); env && *env) {
    char* end = nullptr;
    const long value = std::strtol(env, &end, 10);
    if (end && *end == '\0' && value >= 1 && value <= 1 << 20) return static_cast<int>(value);
  }
  return 0;
}

Topology MakeTopology(int ranks_per_node) {
  Topology t;
  MPI_Comm_rank(MPI_COMM_WORLD, &t.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &t.ranks);
  MPI_Comm node_comm = MPI_COMM_NULL;
  if (ranks_per_node > 0) {
    CheckMpi(MPI_Comm_split(MPI_COMM_WORLD, t.rank / ranks_per_node, t.rank, &node_comm), "MPI_Comm_split");
  } else {
    CheckMpi(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, t.rank, MPI_INFO_NULL, &node_comm),
             "MPI_Comm_split_type");
  }
  int node_rank = 0;
  MPI_Comm_rank(node_comm, &node_rank);
  t.writer = node_rank == 0;
  std::vector<int> is_writer(static_cast<std::size_t>(t.ranks), 0);
  const int mine = t.writer ? 1 : 0;
  CheckMpi(MPI_Allgather(&mine, 1, MPI_INT, is_writer.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  for (int r = 0; r < t.ranks; ++r) {
    if (is_writer[static_cast<std::size_t>(r)]) {
      if (r == t.rank) t.node = static_cast<int>(t.writer_rank.size());
      t.writer_rank.push_back(r);
    }
  }
  t.nodes = static_cast<int>(t.writer_rank.size());
  CheckMpi(MPI_Bcast(&t.node, 1, MPI_INT, 0, node_comm), "MPI_Bcast");
  MPI_Comm_free(&node_comm);
  t.node_of.resize(static_cast<std::size_t>(t.ranks));
  CheckMpi(MPI_Allgather(&t.node, 1, MPI_INT, t.node_of.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  return t;
}

// Node k's part of the plan: batches [first, first + count). Contiguous, in node order, about B/K
// each; a node whose only batch would be the plan's partial last one gives it to the node before
// (its shard would be smaller than a batch, with chunks of another size than the workers make).
struct BatchRange {
  std::int64_t first = 0, count = 0;
};

std::vector<BatchRange> NodeRanges(const SweepPlan& plan, int nodes) {
  const std::int64_t batches = plan.block_count();
  std::vector<BatchRange> ranges(static_cast<std::size_t>(nodes));
  for (int k = 0; k < nodes; ++k) {
    const std::int64_t a = batches * k / nodes, b = batches * (k + 1) / nodes;
    ranges[static_cast<std::size_t>(k)] = {a, b - a};
  }
  const bool last_partial = plan.run_count() % plan.chunk_runs() != 0;
  BatchRange& last = ranges.back();
  if (nodes > 1 && last_partial && last.count == 1) {
    for (int k = nodes - 2; k >= 0; --k) {
      if (ranges[static_cast<std::size_t>(k)].count > 0) {
        ranges[static_cast<std::size_t>(k)].count += 1;
        last = {last.first + 1, 0};
        break;
      }
    }
  }
  return ranges;
}

int OwnerOf(const std::vector<BatchRange>& ranges, std::int64_t batch) {
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    if (batch >= ranges[k].first && batch < ranges[k].first + ranges[k].count) return static_cast<int>(k);
  }
  GESWEEP_UNREACHABLE();  // every batch is in some rank's range
}

// What every rank must agree on before anything is written: the same study (fingerprint), design,
// shard, batch size and output columns.
std::vector<std::int64_t> PlanSignature(const SweepPlan& plan) {
  std::int64_t doubles = 0;
  for (const auto& column : plan.schema().columns) doubles += column.doubles_per_run();
  std::int64_t fingerprint = 0;
  std::memcpy(&fingerprint, &plan.study().fingerprint, sizeof fingerprint);
  return {fingerprint,
          plan.design_runs(),
          plan.first_run(),
          plan.run_count(),
          plan.chunk_runs(),
          plan.design().column_count(),
          static_cast<std::int64_t>(plan.schema().columns.size()),
          doubles};
}

// ---- A filtered batch on the wire ----

void PackBlock(const ResultBlock& block, std::vector<char>& out) {
  constexpr std::size_t kField = sizeof(std::int64_t);  // every header field is one int64
  std::size_t bytes = 5 * kField;
  for (int c = 0; c < block.chunk_count; ++c)
    bytes += 4 * kField + block.chunks[static_cast<std::size_t>(c)].bytes.size();
  out.resize(bytes);
  char* at = out.data();
  auto put = [&](std::int64_t value) {
    std::memcpy(at, &value, 8);
    at += 8;
  };
  put(block.block_index);
  put(block.rows);
  put(block.chunk_count);
  put(block.runs_failed);
  put(0);
  for (int c = 0; c < block.chunk_count; ++c) {
    const StoredChunk& chunk = block.chunks[static_cast<std::size_t>(c)];
    put(chunk.dataset);
    put(chunk.row);
    put(chunk.filter_mask);
    put(static_cast<std::int64_t>(chunk.bytes.size()));
  }
  for (int c = 0; c < block.chunk_count; ++c) {
    const StoredChunk& chunk = block.chunks[static_cast<std::size_t>(c)];
    std::memcpy(at, chunk.bytes.data(), chunk.bytes.size());
    at += chunk.bytes.size();
  }
}

// Unpacks a received batch into `block` and checks that it is one of `range`'s batches of `plan`,
// with chunks of the layout's datasets.
void UnpackBlock(const SweepPlan& plan, const archive::ArchiveLayout& layout, const BatchRange& range,
                 const std::vector<char>& data, ResultBlock& block) {
  const char* at = data.data();
  const char* end = data.data() + data.size();
  auto get = [&]() {
    GESWEEP_DEMAND(at + 8 <= end);
    std::int64_t value = 0;
    std::memcpy(&value, at, 8);
    at += 8;
    return value;
  };
  block.block_index = get();
  GESWEEP_DEMAND(block.block_index >= range.first && block.block_index < range.first + range.count);
  block.first_row = block.block_index * plan.chunk_runs();
  block.rows = static_cast<int>(get());
  GESWEEP_DEMAND(block.rows == std::min<std::int64_t>(plan.chunk_runs(), plan.run_count() - block.first_row));
  const std::int64_t count = get();
  GESWEEP_DEMAND(count >= 1 && count <= 1 << 24);
  block.runs_failed = static_cast<int>(get());
  get();
  block.chunk_count = static_cast<int>(count);
  if (block.chunks.size() < static_cast<std::size_t>(count))
    block.chunks.resize(static_cast<std::size_t>(count));
  std::vector<std::int64_t> sizes(static_cast<std::size_t>(count));
  for (std::int64_t c = 0; c < count; ++c) {
    StoredChunk& chunk = block.chunks[static_cast<std::size_t>(c)];
    chunk.dataset = static_cast<int>(get());
    GESWEEP_DEMAND(chunk.dataset >= 0 && chunk.dataset < static_cast<int>(layout.datasets().size()));
    chunk.row = get();
    GESWEEP_DEMAND(chunk.row >= 0 && chunk.row < block.rows);
    chunk.filter_mask = static_cast<std::uint32_t>(get());
    sizes[static_cast<std::size_t>(c)] = get();
  }
  for (std::int64_t c = 0; c < count; ++c) {
    const auto size = static_cast<std::size_t>(sizes[static_cast<std::size_t>(c)]);
    GESWEEP_DEMAND(size >= 1 && at + size <= end);
    block.chunks[static_cast<std::size_t>(c)].bytes.assign(at, at + size);
    at += size;
  }
  GESWEEP_DEMAND(at == end);
}

// ---- The transport ----

// Batch numbers for this rank's pipeline, pushed by the main thread (-1: no more).
class QueueSource final : public BatchSource {
 public:
  std::int64_t Next() override {
    std::int64_t index = -1;
    queue_.pop(index);
    return index;
  }
  void Push(std::int64_t index) { queue_.push(index); }

 private:
  tbb::concurrent_bounded_queue<std::int64_t> queue_;
};

// Where this rank's finished batches go: this node's shard archive when this rank is the node's
// writer and the batch is the node's, else a packed message for the owning node's writer (sent by
// the main thread).
class TransportSink final : public ResultSink {
 public:
  TransportSink(const SweepPlan& plan, const std::vector<BatchRange>& ranges, int node, ArchiveWriter* writer,
                std::mutex* write_mutex)
      : layout_(plan), ranges_(ranges), node_(node), writer_(writer), write_mutex_(write_mutex) {
    outgoing_.set_capacity(kOutgoingBatches);
  }

  void Encode(ResultBlock& block) override { layout_.Encode(block); }

  void Write(const ResultBlock& block) override {
    const int owner = OwnerOf(ranges_, block.block_index);
    if (owner == node_ && writer_ != nullptr) {
      std::lock_guard<std::mutex> lock(*write_mutex_);
      writer_->Write(block);
    } else {
      auto message = std::make_unique<Outgoing>();
      message->node = owner;
      PackBlock(block, message->bytes);
      outgoing_.push(std::move(message));
    }
    delivered_.fetch_add(1);
  }

  struct Outgoing {
    int node = 0;
    std::vector<char> bytes;
    MPI_Request request = MPI_REQUEST_NULL;
  };
  bool TryTake(std::unique_ptr<Outgoing>& message) { return outgoing_.try_pop(message); }
  bool outgoing_empty() const { return outgoing_.empty(); }
  std::int64_t delivered() const { return delivered_.load(); }
  const archive::ArchiveLayout& layout() const { return layout_; }

 private:
  archive::ArchiveLayout layout_;
  const std::vector<BatchRange>& ranges_;
  int node_;
  ArchiveWriter* writer_;
  std::mutex* write_mutex_;
  tbb::concurrent_bounded_queue<std::unique_ptr<Outgoing>> outgoing_;
  std::atomic<std::int64_t> delivered_{0};
};

// Rank 0's book of the batches still to hand out, one queue per node.
class Dispatcher {
 public:
  Dispatcher(std::vector<std::deque<std::int64_t>> pending, int ranks)
      : pending_(std::move(pending)), ranks_(ranks) {
    for (const auto& queue : pending_) remaining_ += static_cast<std::int64_t>(queue.size());
  }
  // Up to `want` batches for a rank of `node`: its node's first, then (once they are gone) from the
  // end of the node with the most left. Guided: at most remaining / (2·ranks), at least 1.
  std::vector<std::int64_t> Grant(int node, std::int64_t want) {
    std::vector<std::int64_t> out;
    if (stopped_ || remaining_ == 0 || want <= 0) return out;
    const std::int64_t fair = std::max<std::int64_t>(1, remaining_ / (2 * ranks_));
    const std::int64_t n = std::min(want, fair);
    auto& own = pending_[static_cast<std::size_t>(node)];
    while (static_cast<std::int64_t>(out.size()) < n && !own.empty()) {
      out.push_back(own.front());
      own.pop_front();
    }
    while (static_cast<std::int64_t>(out.size()) < n) {
      std::size_t victim = 0;
      for (std::size_t k = 1; k < pending_.size(); ++k)
        if (pending_[k].size() > pending_[victim].size()) victim = k;
      if (pending_[victim].empty()) break;
      out.push_back(pending_[victim].back());
      pending_[victim].pop_back();
    }
    remaining_ -= static_cast<std::int64_t>(out.size());
    return out;
  }
  void Stop() { stopped_ = true; }
  bool stopped() const { return stopped_; }
  std::int64_t remaining() const { return remaining_; }

 private:
  std::vector<std::deque<std::int64_t>> pending_;
  std::int64_t ranks_;
  std::int64_t remaining_ = 0;
  bool stopped_ = false;
};

// Inside a catch (...): the code of the failure this rank agrees on with the others (AgreeOnError), 2
// for an InputError (worded by describe_input_error when given), 1 for an ArchiveError, with its
// message in `error`; anything else is rethrown.
int ErrorOfThisRank(const MpiRunOptions& options, std::string& error) {
  try {
    throw;
  } catch (const InputError& e) {
    error = options.describe_input_error ? options.describe_input_error(e) : std::string(e.what());
    return 2;
  } catch (const ArchiveError& e) {
    error = e.what();
    return 1;
  }
}

bool Cancelled(const MpiRunOptions& options) { return options.cancel != nullptr && options.cancel->load(); }

std::string ErrorText(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown exception";
  }
}

}  // namespace

std::filesystem::path NodeArchivePath(const std::filesystem::path& output, int node, int nodes) {
  std::filesystem::path stem = output;
  if (stem.extension() == ".h5") stem.replace_extension();
  return std::filesystem::path(stem.string() + ".node" + std::to_string(node) + "-of-" +
                               std::to_string(nodes) + ".h5");
}

std::int64_t BatchMessageBytes(const SweepPlan& plan, int rows) {
  std::int64_t doubles = plan.design().column_count();
  for (const auto& column : plan.schema().columns) doubles += column.doubles_per_run();
  // per run: design index, run id, status; the doubles (messages are sparse)
  return static_cast<std::int64_t>(rows) * (8 + 8 + 1 + 8 * doubles);
}

void FinalizeMpi() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (initialized && !finalized) MPI_Finalize();
}

[[noreturn]] void AbortMpi(int code) {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (initialized && !finalized) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

namespace {

// Stage 1: every rank must have built the same plan (a study file that differs between nodes would
// otherwise mix two studies in one archive).
bool RanksBuiltTheSamePlan(const SweepPlan& plan) {
  const std::vector<std::int64_t> mine = PlanSignature(plan);
  std::vector<std::int64_t> lowest(mine.size()), highest(mine.size());
  const int n = static_cast<int>(mine.size());
  CheckMpi(MPI_Allreduce(mine.data(), lowest.data(), n, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD),
           "MPI_Allreduce");
  CheckMpi(MPI_Allreduce(mine.data(), highest.data(), n, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD),
           "MPI_Allreduce");
  return lowest == highest;
}

// Stage 2, rank 0: the output is a file this run may write, and no node shards of a run on another
// number of nodes lie beside it (with kForce they are removed). Throws InputError (or RequestError).
void CheckOutputForNodes(const MpiRunOptions& options, int nodes) {
  const std::string out = options.output.string();
  std::error_code ec;
  if (std::filesystem::is_directory(options.output, ec)) {
    throw InputError("command line", "output", out,
                     "is a directory; expected an archive file name such as out.h5");
  }
  if (options.mode == ArchiveOpenMode::kCreate && std::filesystem::exists(options.output, ec)) {
    throw RequestError("command line", "output", out, "already exists", "resume_or_force");
  }
  // Node shards of another node count: they cannot be resumed by this layout.
  std::filesystem::path directory = options.output.parent_path();
  if (directory.empty()) directory = ".";
  std::filesystem::path stem = options.output.filename();
  if (stem.extension() == ".h5") stem.replace_extension();
  const std::regex pattern(std::regex_replace(stem.string(), std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                           R"(\.node\d+-of-(\d+)\.h5)");
  if (!std::filesystem::is_directory(directory, ec)) return;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, match, pattern) || std::stoi(match[1].str()) == nodes) continue;
    if (options.mode == ArchiveOpenMode::kForce) {
      std::filesystem::remove(entry.path(), ec);
    } else {
      const bool resuming = options.mode == ArchiveOpenMode::kResume;
      throw RequestError(
          "command line", "output", out,
          "has node shards of a run on " + match[1].str() + " nodes (" + entry.path().string() +
              "), this run has " + std::to_string(nodes) +
              (resuming ? "; resume with as many nodes (GESWEEP_RANKS_PER_NODE or the same allocation)" : ""),
          resuming ? "" : "force_or_resume_nodes");
    }
  }
}

// A writer's shard of its node's batches: the ordinary ArchiveWriter (crash safety, --resume).
struct NodeShard {
  std::unique_ptr<SweepPlan> plan;  // the study restricted to the node's batches
  std::unique_ptr<ArchiveWriter> writer;
  ArchiveOpenReport opened;
  std::vector<std::int64_t> pending;  // the node's batches still to run, as indices of the whole plan
};

// Stage 2, writers: opens the node's shard into `shard` (filled as far as it got when it throws).
void OpenNodeShard(const SweepPlan& plan, const MpiRunOptions& options, const Topology& t,
                   const BatchRange& range, int threads, NodeShard& shard) {
  shard.plan = std::make_unique<SweepPlan>(LoadStudy(plan.study().path), plan.shard());
  if (shard.plan->chunk_runs() != plan.chunk_runs() || shard.plan->block_count() != plan.block_count()) {
    throw InputError(plan.study().path, "", "", "the study file changed while the MPI job started");
  }
  shard.plan->RestrictToBatches(range.first, range.count);
  RunProvenance provenance{options.command_line + " (" + std::to_string(t.ranks) + " MPI ranks)",
                           threads * t.ranks, t.node, t.nodes, t.ranks};
  shard.writer = ArchiveWriter::Open(NodeArchivePath(options.output, t.node, t.nodes), *shard.plan,
                                     provenance, options.mode, &shard.opened);
  if (shard.plan->chunk_runs() != plan.chunk_runs()) {
    throw InputError("command line", "output", NodeArchivePath(options.output, t.node, t.nodes).string(),
                     "cannot resume: it has batches of " + std::to_string(shard.plan->chunk_runs()) +
                         " runs, this run " + std::to_string(plan.chunk_runs()));
  }
  shard.writer->set_block_row_offset(range.first * plan.chunk_runs());
  for (const std::int64_t local : shard.opened.pending_blocks) shard.pending.push_back(range.first + local);
}

// Stage 3: rank 0 learns every node's pending batches (returned by node; empty on the other ranks),
// every rank the runs complete at the start (`all_complete`).
std::vector<std::deque<std::int64_t>> GatherPendingBatches(const std::vector<std::int64_t>& pending_mine,
                                                           std::int64_t complete_runs, const Topology& t,
                                                           std::int64_t& all_complete) {
  const int mine = static_cast<int>(pending_mine.size());
  std::vector<int> counts(static_cast<std::size_t>(t.ranks)), offsets(static_cast<std::size_t>(t.ranks));
  CheckMpi(MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  int total = 0;
  for (int r = 0; r < t.ranks; ++r) {
    offsets[static_cast<std::size_t>(r)] = total;
    total += counts[static_cast<std::size_t>(r)];
  }
  std::vector<std::int64_t> all(static_cast<std::size_t>(std::max(total, 1)));
  CheckMpi(MPI_Gatherv(pending_mine.data(), mine, MPI_INT64_T, all.data(), counts.data(), offsets.data(),
                       MPI_INT64_T, 0, MPI_COMM_WORLD),
           "MPI_Gatherv");
  all_complete = 0;
  CheckMpi(MPI_Allreduce(&complete_runs, &all_complete, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD),
           "MPI_Allreduce");
  std::vector<std::deque<std::int64_t>> pending(static_cast<std::size_t>(t.nodes));
  if (t.rank == 0) {
    for (int r = 0; r < t.ranks; ++r) {
      const auto from = all.begin() + offsets[static_cast<std::size_t>(r)];
      auto& node_pending = pending[static_cast<std::size_t>(t.node_of[static_cast<std::size_t>(r)])];
      node_pending.insert(node_pending.end(), from, from + counts[static_cast<std::size_t>(r)]);
    }
  }
  return pending;
}

// Stage 4: the one pipeline (RunSweep) on its own thread, fed and drained by this thread's MPI
// traffic. Each turn of Run's loop: a fatal error stops the handing out of batches; this rank's
// pipeline gets batches (rank 0 from the Dispatcher, the others by request); rank 0 serves the others'
// requests and hears their errors; rows for other nodes go to their writers; a writer writes what it
// receives. The loop ends when every rank has had its last grant and every writer has every row.
class Exchange {
 public:
  Exchange(const SweepPlan& plan, const MpiRunOptions& options, const Topology& t,
           const std::vector<BatchRange>& ranges, bool writes, ArchiveWriter* writer, std::int64_t target,
           std::vector<std::deque<std::int64_t>> pending, SweepProgress& shown, MpiSweepReport& report)
      : plan_(plan),
        options_(options),
        t_(t),
        ranges_(ranges),
        writes_(writes),
        writer_(writer),
        target_(target),
        shown_(shown),
        report_(report),
        dispatcher_(std::move(pending), t.ranks),
        sink_(plan, ranges, t.node, writes ? writer : nullptr, &write_mutex_),
        sent_to_(static_cast<std::size_t>(t.nodes), 0),
        received_from_(static_cast<std::size_t>(t.ranks), 0),
        expected_from_(static_cast<std::size_t>(t.ranks), -1),
        done_of_(static_cast<std::size_t>(t.ranks), 0),
        failed_of_(static_cast<std::size_t>(t.ranks), 0),
        my_range_(ranges[static_cast<std::size_t>(t.node)]) {}

  // Computes this rank's share with `threads` threads and serves the traffic until every rank is done.
  void Run(int threads) {
    RunnerOptions runner_options;
    runner_options.threads = threads;
    runner_options.cancel = options_.cancel;
    runner_options.lanes = options_.lanes;
    start_ = std::chrono::steady_clock::now();
    std::thread compute([&] {
      try {
        outcome_ = RunSweep(plan_, source_, sink_, runner_options, &computed_);
      } catch (...) {
        compute_error_ = std::current_exception();
      }
      compute_done_.store(true);
    });
    for (;;) {
      if (compute_done_.load() && compute_error_ && fatal_.empty()) Fail(ErrorText(compute_error_));
      ReportFatal();
      if (t_.rank == 0 && Cancelled(options_) && !dispatcher_.stopped()) {
        report_.cancelled = dispatcher_.remaining() > 0;
        dispatcher_.Stop();
      }
      bool progressed = FeedPipeline();
      progressed = ReceiveGrant() || progressed;
      if (t_.rank == 0) progressed = ServeOtherRanks() || progressed;
      progressed = SendRows() || progressed;
      progressed = SendFinished() || progressed;
      progressed = ReceiveRows() || progressed;
      const bool rank0_done = t_.rank != 0 || ranks_ended_ == t_.ranks - 1;
      if (compute_done_.load() && ended_ && finished_sent_ && WriterComplete() && rank0_done) break;
      if (!progressed) std::this_thread::sleep_for(kIdlePoll);
    }
    compute.join();
  }

  // Keeps the first reason to stop of this rank (an I/O error of its writer, a bug).
  void Fail(const std::string& why) {
    if (fatal_.empty()) fatal_ = why;
  }
  const std::string& fatal() const { return fatal_; }
  const SweepOutcome& outcome() const { return outcome_; }
  std::int64_t runs_computed() const { return computed_.runs_done.load(); }
  std::chrono::steady_clock::time_point start() const { return start_; }

 private:
  // A fatal error stops the handing out of batches everywhere (rank 0 hears of it).
  void ReportFatal() {
    if (fatal_.empty() || fatal_reported_) return;
    fatal_reported_ = true;
    if (t_.rank == 0) {
      dispatcher_.Stop();
    } else {
      CheckMpi(
          MPI_Send(fatal_.data(), static_cast<int>(fatal_.size()), MPI_CHAR, 0, kTagError, MPI_COMM_WORLD),
          "MPI_Send error");
    }
  }

  void CloseSource() {
    if (!source_closed_) source_.Push(-1);
    source_closed_ = true;
  }

  // Batches for this rank's pipeline: rank 0 grants its own, the others ask rank 0.
  bool FeedPipeline() {
    const std::int64_t outstanding = granted_ - sink_.delivered();
    if (t_.rank == 0) {
      if (ended_) return false;
      bool progressed = false;
      if (compute_done_.load()) {
        ended_ = true;
      } else if (outstanding < target_) {
        const std::vector<std::int64_t> grant = dispatcher_.Grant(t_.node, target_ - outstanding);
        for (const std::int64_t batch : grant) source_.Push(batch);
        granted_ += static_cast<std::int64_t>(grant.size());
        if (grant.empty()) ended_ = true;
        progressed = !grant.empty() || ended_;
      }
      if (ended_) CloseSource();
      return progressed;
    }
    if (ended_ || request_pending_ || !(outstanding < target_ || compute_done_.load())) return false;
    const std::int64_t request[3] = {compute_done_.load() ? 0 : target_ - outstanding,
                                     computed_.runs_done.load(), computed_.runs_failed.load()};
    CheckMpi(MPI_Send(request, 3, MPI_INT64_T, 0, kTagRequest, MPI_COMM_WORLD), "MPI_Send request");
    request_pending_ = true;
    return true;
  }

  // Ranks > 0: rank 0's answer to the request; an empty grant is the last.
  bool ReceiveGrant() {
    if (!request_pending_) return false;
    int ready = 0;
    MPI_Status status;
    CheckMpi(MPI_Iprobe(0, kTagGrant, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe grant");
    if (!ready) return false;
    int count = 0;
    MPI_Get_count(&status, MPI_INT64_T, &count);
    std::vector<std::int64_t> grant(static_cast<std::size_t>(count));
    CheckMpi(MPI_Recv(grant.data(), count, MPI_INT64_T, 0, kTagGrant, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
             "MPI_Recv grant");
    request_pending_ = false;
    for (const std::int64_t batch : grant) source_.Push(batch);
    granted_ += count;
    if (count == 0) {
      ended_ = true;
      CloseSource();
    }
    return true;
  }

  // Rank 0: requests of the others (with their progress, summed into `shown`), and their errors.
  bool ServeOtherRanks() {
    bool progressed = false;
    int ready = 0;
    MPI_Status status;
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe request");
    if (ready) {
      std::int64_t request[3] = {0, 0, 0};
      const int from = status.MPI_SOURCE;
      CheckMpi(MPI_Recv(request, 3, MPI_INT64_T, from, kTagRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
               "MPI_Recv request");
      done_of_[static_cast<std::size_t>(from)] = request[1];
      failed_of_[static_cast<std::size_t>(from)] = request[2];
      const std::vector<std::int64_t> grant =
          dispatcher_.Grant(t_.node_of[static_cast<std::size_t>(from)], request[0]);
      CheckMpi(MPI_Send(grant.data(), static_cast<int>(grant.size()), MPI_INT64_T, from, kTagGrant,
                        MPI_COMM_WORLD),
               "MPI_Send grant");
      if (grant.empty()) ++ranks_ended_;
      progressed = true;
    }
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagError, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe error");
    if (ready) {
      int length = 0;
      MPI_Get_count(&status, MPI_CHAR, &length);
      std::string text(static_cast<std::size_t>(length), '\0');
      CheckMpi(MPI_Recv(text.data(), length, MPI_CHAR, status.MPI_SOURCE, kTagError, MPI_COMM_WORLD,
                        MPI_STATUS_IGNORE),
               "MPI_Recv error");
      dispatcher_.Stop();
      if (report_.error.empty()) report_.error = text;
      progressed = true;
    }
    std::int64_t done = computed_.runs_done.load(), failed = computed_.runs_failed.load();
    for (int r = 1; r < t_.ranks; ++r) {
      done += done_of_[static_cast<std::size_t>(r)];
      failed += failed_of_[static_cast<std::size_t>(r)];
    }
    shown_.runs_done.store(done);
    shown_.runs_failed.store(failed);
    return progressed;
  }

  // Filtered batches for other nodes' writers, sent without waiting; the sends that completed dropped.
  bool SendRows() {
    bool progressed = false;
    std::unique_ptr<TransportSink::Outgoing> message;
    while (sink_.TryTake(message)) {
      const int to = t_.writer_rank[static_cast<std::size_t>(message->node)];
      CheckMpi(MPI_Isend(message->bytes.data(), static_cast<int>(message->bytes.size()), MPI_BYTE, to,
                         kTagResult, MPI_COMM_WORLD, &message->request),
               "MPI_Isend result");
      ++sent_to_[static_cast<std::size_t>(message->node)];
      in_flight_.push_back(std::move(message));
      progressed = true;
    }
    for (auto it = in_flight_.begin(); it != in_flight_.end();) {
      int complete = 0;
      CheckMpi(MPI_Test(&(*it)->request, &complete, MPI_STATUS_IGNORE), "MPI_Test");
      if (complete) {
        it = in_flight_.erase(it);
        progressed = true;
      } else {
        ++it;
      }
    }
    return progressed;
  }

  // Once this rank has computed and sent everything: each other writer learns how many batches to expect.
  bool SendFinished() {
    if (finished_sent_ || !compute_done_.load() || !ended_ || !sink_.outgoing_empty() ||
        !in_flight_.empty()) {
      return false;
    }
    for (int k = 0; k < t_.nodes; ++k) {
      const int to = t_.writer_rank[static_cast<std::size_t>(k)];
      if (ranges_[static_cast<std::size_t>(k)].count == 0 || to == t_.rank) continue;
      CheckMpi(
          MPI_Send(&sent_to_[static_cast<std::size_t>(k)], 1, MPI_INT64_T, to, kTagFinished, MPI_COMM_WORLD),
          "MPI_Send finished");
    }
    finished_sent_ = true;
    return true;
  }

  // The node's writer: batches from the other ranks, and how many each will send.
  bool ReceiveRows() {
    if (!writes_) return false;
    bool progressed = false;
    int ready = 0;
    MPI_Status status;
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &ready, &status), "MPI_Iprobe result");
    if (ready) {
      int bytes = 0;
      MPI_Get_count(&status, MPI_BYTE, &bytes);
      buffer_.resize(static_cast<std::size_t>(bytes));
      const int from = status.MPI_SOURCE;
      CheckMpi(MPI_Recv(buffer_.data(), bytes, MPI_BYTE, from, kTagResult, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
               "MPI_Recv result");
      ++received_from_[static_cast<std::size_t>(from)];
      if (fatal_.empty()) {
        try {
          UnpackBlock(plan_, sink_.layout(), my_range_, buffer_, received_);
          std::lock_guard<std::mutex> lock(write_mutex_);
          writer_->Write(received_);
        } catch (const std::exception& e) {
          Fail(std::string("the writer of node ") + std::to_string(t_.node) + ": " + e.what());
        }
      }
      progressed = true;
    }
    CheckMpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagFinished, MPI_COMM_WORLD, &ready, &status),
             "MPI_Iprobe finished");
    if (ready) {
      std::int64_t count = 0;
      CheckMpi(MPI_Recv(&count, 1, MPI_INT64_T, status.MPI_SOURCE, kTagFinished, MPI_COMM_WORLD,
                        MPI_STATUS_IGNORE),
               "MPI_Recv finished");
      expected_from_[static_cast<std::size_t>(status.MPI_SOURCE)] = count;
      progressed = true;
    }
    return progressed;
  }

  // A rank that writes no shard is complete; a writer once every other rank's batches have arrived.
  bool WriterComplete() const {
    if (!writes_) return true;
    for (int r = 0; r < t_.ranks; ++r) {
      if (r == t_.rank) continue;
      const auto i = static_cast<std::size_t>(r);
      if (expected_from_[i] < 0 || received_from_[i] != expected_from_[i]) return false;
    }
    return true;
  }

  const SweepPlan& plan_;
  const MpiRunOptions& options_;
  const Topology& t_;
  const std::vector<BatchRange>& ranges_;
  const bool writes_;
  ArchiveWriter* writer_;
  const std::int64_t target_;  // batches a rank holds: the pipeline's tokens + prefetch
  SweepProgress& shown_;
  MpiSweepReport& report_;
  Dispatcher dispatcher_;
  std::mutex write_mutex_;
  QueueSource source_;
  TransportSink sink_;
  SweepProgress computed_;
  std::atomic<bool> compute_done_{false};
  std::exception_ptr compute_error_;
  SweepOutcome outcome_;
  std::chrono::steady_clock::time_point start_;

  std::int64_t granted_ = 0;      // batches this rank was given
  bool request_pending_ = false;  // a request to rank 0 awaits its grant (ranks > 0)
  bool ended_ = false;            // this rank got its last (empty) grant
  bool source_closed_ = false;    // -1 pushed to the pipeline
  int ranks_ended_ = 0;           // rank 0: other ranks that got their last grant
  std::vector<std::int64_t> sent_to_;
  bool finished_sent_ = false;
  std::vector<std::int64_t> received_from_;
  std::vector<std::int64_t> expected_from_;
  std::vector<std::int64_t> done_of_, failed_of_;
  std::list<std::unique_ptr<TransportSink::Outgoing>> in_flight_;
  std::vector<char> buffer_;
  ResultBlock received_;
  std::string fatal_;
  bool fatal_reported_ = false;
  const BatchRange my_range_;
};

// Stage 5: the node shards are closed; every rank learns the counts (ok, failed, pending, computed by
// rank) and whether a rank was cancelled. Returns false, with report.error_code set, on an error.
bool CloseNodeShards(std::unique_ptr<ArchiveWriter>& writer, bool writes, const Topology& t,
                     Exchange& exchange, MpiSweepReport& report) {
  std::int64_t counts_mine[3] = {0, 0, 0};
  if (writes && exchange.fatal().empty()) {
    try {
      writer->Finish();
      counts_mine[0] = writer->runs_ok();
      counts_mine[1] = writer->runs_failed();
      counts_mine[2] = writer->runs_pending();
    } catch (const ArchiveError& e) {
      exchange.Fail(std::string("the writer of node ") + std::to_string(t.node) + ": " + e.what());
    }
  }
  writer.reset();
  std::int64_t counts_all[3] = {0, 0, 0};
  CheckMpi(MPI_Allreduce(counts_mine, counts_all, 3, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  report.runs_ok = counts_all[0];
  report.runs_failed = counts_all[1];
  report.runs_pending = counts_all[2];
  std::int64_t computed_mine = report.runs_computed;
  CheckMpi(MPI_Gather(&computed_mine, 1, MPI_INT64_T, report.runs_per_rank.data(), 1, MPI_INT64_T, 0,
                      MPI_COMM_WORLD),
           "MPI_Gather");
  int cancelled = report.cancelled ? 1 : 0, any_cancelled = 0;
  CheckMpi(MPI_Allreduce(&cancelled, &any_cancelled, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  report.cancelled = any_cancelled != 0 && report.runs_pending > 0;
  const std::string rank0_error = report.error;  // an error another rank reported during the sweep
  const std::string& fatal = exchange.fatal();
  if ((report.error_code = AgreeOnError(fatal.empty() ? 0 : 1, fatal, t.rank, t.ranks, &report.error)) != 0) {
    if (report.error.empty()) report.error = rank0_error;
    return false;
  }
  return true;
}

// Rank 0 maps the node shards into the output once no run is pending; every rank learns whether it did.
void MergeNodeShards(const SweepPlan& plan, const MpiRunOptions& options, const Topology& t,
                     std::chrono::steady_clock::time_point start, MpiSweepReport& report) {
  int merged = 0;
  int code = 0;
  std::string error;
  if (t.rank == 0 && report.runs_pending == 0) {
    try {
      std::vector<std::filesystem::path> shards(report.node_archives.begin(), report.node_archives.end());
      MergeScope scope{plan.first_run(), plan.run_count(), plan.shard().index, plan.shard().count};
      report.merge =
          MergeArchives(shards, options.output, /*force=*/true,
                        options.command_line + " (merge of the node shards)", options.merge, scope);
      merged = 1;
    } catch (...) {
      code = ErrorOfThisRank(options, error);
    }
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  CheckMpi(MPI_Bcast(&merged, 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Bcast");
  report.merged = merged != 0;
  report.error_code = AgreeOnError(code, error, t.rank, t.ranks, &report.error);
}

}  // namespace

MpiSweepReport RunStudyMpi(const SweepPlan& plan, const MpiRunOptions& options, SweepProgress* progress,
                           const MpiStartCallback& on_started) {
  EnsureMpi();
  SweepProgress local_progress;
  SweepProgress& shown = progress ? *progress : local_progress;
  MpiSweepReport report;
  const Topology t = MakeTopology(RanksPerNode(options));
  report.rank = t.rank;
  report.ranks = t.ranks;
  report.node = t.node;
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  const int prefetch = options.prefetch_batches > 0 ? options.prefetch_batches : threads;
  const std::int64_t target =
      2 * threads + prefetch;  // batches a rank holds: the pipeline's tokens + prefetch

  if (!RanksBuiltTheSamePlan(plan)) {
    report.error_code = 2;
    report.error = "the " + std::to_string(t.ranks) +
                   " MPI ranks did not build the same sweep (study fingerprint, design, shard or batch size "
                   "differ): every node must see the same study and aircraft files";
    return report;
  }

  // 2. The nodes' parts of the plan and their shard archives.
  const std::vector<BatchRange> ranges = NodeRanges(plan, t.nodes);
  report.nodes = t.nodes;
  for (int k = 0; k < t.nodes; ++k)
    if (ranges[static_cast<std::size_t>(k)].count > 0)
      report.node_archives.push_back(NodeArchivePath(options.output, k, t.nodes).string());
  const bool writes = t.writer && ranges[static_cast<std::size_t>(t.node)].count > 0;
  report.writer = writes;

  std::string error;
  int code = 0;
  if (t.rank == 0) {
    try {
      CheckOutputForNodes(options, t.nodes);
    } catch (const InputError& e) {
      code = 2;
      error = options.describe_input_error ? options.describe_input_error(e) : std::string(e.what());
    }
  }
  if ((report.error_code = AgreeOnError(code, error, t.rank, t.ranks, &report.error)) != 0) return report;

  NodeShard shard;
  if (writes) {
    try {
      OpenNodeShard(plan, options, t, ranges[static_cast<std::size_t>(t.node)], threads, shard);
    } catch (...) {
      code = ErrorOfThisRank(options, error);
    }
  }
  if ((report.error_code = AgreeOnError(code, error, t.rank, t.ranks, &report.error)) != 0) return report;

  std::int64_t all_complete = 0;
  std::vector<std::deque<std::int64_t>> pending =
      GatherPendingBatches(shard.pending, writes ? shard.opened.runs_complete : 0, t, all_complete);
  report.runs_complete_at_start = all_complete;
  report.runs_to_do = plan.run_count() - all_complete;
  shown.runs_skipped.store(all_complete);
  shown.runs_to_do.store(report.runs_to_do);
  report.runs_per_rank.assign(static_cast<std::size_t>(t.ranks), 0);
  if (on_started) on_started(report);

  Exchange exchange(plan, options, t, ranges, writes, shard.writer.get(), target, std::move(pending), shown,
                    report);
  exchange.Run(threads);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - exchange.start()).count();
  if (exchange.outcome().cancelled && t.rank != 0) report.cancelled = true;
  report.runs_computed = exchange.runs_computed();

  if (!CloseNodeShards(shard.writer, writes, t, exchange, report)) return report;
  MergeNodeShards(plan, options, t, exchange.start(), report);
  return report;
}

}  // namespace gesweep
