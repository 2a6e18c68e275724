// A sink-rate limit's probability by adaptive multilevel splitting in time (Cerou & Guyader,
// Stochastic Analysis and Applications 25, 2007; the generalised, unbiased form of Brehier, Gazeau,
// Goudenege, Lelievre & Rousset, Annals of Applied Probability 26, 2016), independent of subset
// simulation (docs/dispersion.md, "Splitting in time"). Not a test: minutes of CPU.
//
//   risk_splitting STUDY LIMIT N K SEED REPETITIONS [LOOKAHEAD_PER_S [SERIES_S]]
//
// A landing is a Markov process driven by white noise held per sample, so its future after time t
// depends on its state at t and on the noise samples held from t on only. Splitting moves in time,
// not in u-space, so the discontinuity of the first touch in u (docs/dispersion.md, "Why the
// landing's chains collapse") does not stop it:
// 1. N landings with u ~ N(0, I) (std::mt19937_64, not the engine's streams). Each has a score S,
//    the largest over its series (every SERIES_S, default 0.01 s, up to its touchdown) of
//        xi(t) = sink rate(t) - LOOKAHEAD_PER_S * (H(t) - H_touch),
//    the sink rate -dH/dt by the difference of two series samples and H_touch the height of the
//    still-air landing's touchdown, with xi at touchdown the touchdown sink rate itself.
// 2. While the K-th smallest score z is below the limit: every landing with S <= z is killed (K_j of
//    them, ties included). Each is replaced by a clone of a survivor drawn uniformly: the survivor's
//    noise held before the first series time tau with xi(tau) > z, fresh noise from tau on, flown
//    from the start (so its path is the survivor's up to tau, bit for bit, and its score exceeds z).
//    No survivor (every score <= z): extinction, estimate 0.
// 3. P = prod_j (1 - K_j / N) * (the fraction of the N final landings past the limit). Unbiased for
//    any score of this form, a running maximum of a function of the Markov state (Brehier et al.
//    2016); the score decides only the variance.
// Each repetition uses the seed (SEED, repetition); the estimates' mean, their measured CoV and the
// landings flown are printed.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/disturbance/run_noise.h"
#include "engine/risk/landing_risk.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

namespace {

using gesweep::NoisePointIndex;
using gesweep::NoiseStream;

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();

// What one landing gave: whether it passed the limit, its score and its xi over the series times.
struct Replica {
  std::vector<double> u;
  std::vector<double> xi;  // per series sample up to touchdown; the last is the touchdown's
  double score = kMinusInfinity;
  bool failed = false;  // past the limit
};

class Splitting {
 public:
  Splitting(const gesweep::SweepPlan& series_plan, const gesweep::risk::RiskSpec& spec, int limit,
            double lookahead)
      : plan_(series_plan),
        limit_(spec.limits[static_cast<std::size_t>(limit)]),
        lookahead_(lookahead),
        workspaces_([this] { return Slot(plan_); }) {
    const auto& schema = plan_.schema();
    for (std::size_t c = 0; c < schema.columns.size(); ++c) {
      const std::string& path = schema.columns[c].path;
      if (path == "series/landing/height_m") height_ = static_cast<int>(c);
      if (path == "results/landing/touchdown_sink_rate_mps") sink_ = static_cast<int>(c);
      if (path == "results/landing/touchdown_time_s") touchdown_ = static_cast<int>(c);
      if (path == "results/landing/final_height_m") final_height_ = static_cast<int>(c);
      if (path == limit_.path) column_ = static_cast<int>(c);
    }
    for (const auto& axis : schema.axes) {
      if (axis.path == "series/landing/time_s") times_ = axis.times_s;
    }
    if (height_ < 0 || sink_ < 0 || touchdown_ < 0 || column_ < 0 || times_.size() < 2) {
      throw std::runtime_error("the study's landing has no height series or no touchdown columns");
    }
    dimension_ = static_cast<std::size_t>(gesweep::risk::CellDimension(plan_, 0));
    sample_interval_ = gesweep::risk::CellSampleInterval(plan_, 0);
    Replica still;
    still.u.assign(dimension_, 0.0);
    Fly(still, &h_touch_);  // sets H_touch before its own score is formed
  }

  std::size_t dimension() const { return dimension_; }
  double touchdown_height() const { return h_touch_; }

  // Flies `r.u`: its xi series, score and whether it passed the limit.
  void Fly(Replica& r, double* touch_height = nullptr) {
    Slot& slot = workspaces_.local();
    slot.block.Reset(plan_, 0);
    gesweep::risk::ExecuteCellRun(plan_, 0, slot.workspace, slot.block, r.u);
    const auto value = [&](int c) { return slot.block.results[static_cast<std::size_t>(c)][0]; };
    const double touchdown = value(touchdown_), sink = value(sink_), limit_value = value(column_);
    if (touch_height != nullptr) *touch_height = value(final_height_);
    r.failed = limit_.above ? limit_value > limit_.value : limit_value < limit_.value;
    r.xi.clear();
    const double* h = slot.block.results[static_cast<std::size_t>(height_)].data();
    const double dt = times_[1] - times_[0];
    for (std::size_t i = 1; i < times_.size() && (!(touchdown <= times_[i])); ++i) {
      if (!std::isfinite(h[i]) || !std::isfinite(h[i - 1])) break;
      r.xi.push_back(-(h[i] - h[i - 1]) / dt - lookahead_ * (h[i] - h_touch_));
    }
    if (std::isfinite(sink)) r.xi.push_back(sink);
    r.score = kMinusInfinity;
    for (const double x : r.xi) r.score = std::max(r.score, x);
  }

  // The first series index whose xi exceeds z (the last entry is the touchdown's).
  static std::size_t FirstAbove(const Replica& r, double z) {
    for (std::size_t i = 0; i < r.xi.size(); ++i) {
      if (r.xi[i] > z) return i;
    }
    return r.xi.size();
  }

  // The time of series entry i of a replica's xi (entry i is series sample i + 1).
  double TimeOf(std::size_t i) const { return times_[std::min(i + 1, times_.size() - 1)]; }

  // The noise sample held from time t on: samples k < KeepBelow(t) are held before t.
  std::uint64_t KeepBelow(double t) const {
    return static_cast<std::uint64_t>(std::floor(t / sample_interval_ + 1e-9));
  }

  gesweep::risk::RiskLimit limit() const { return limit_; }

 private:
  struct Slot {
    explicit Slot(const gesweep::SweepPlan& plan) : workspace(plan) { block.Allocate(plan); }
    gesweep::RunWorkspace workspace;
    gesweep::ResultBlock block;
  };
  const gesweep::SweepPlan& plan_;
  gesweep::risk::RiskLimit limit_;
  double lookahead_;
  tbb::enumerable_thread_specific<Slot> workspaces_;
  int height_ = -1, sink_ = -1, touchdown_ = -1, final_height_ = -1, column_ = -1;
  std::vector<double> times_;
  std::size_t dimension_ = 0;
  double sample_interval_ = 0;
  double h_touch_ = 0;
};

struct Estimate {
  double probability = 0;
  long landings = 0;
  int iterations = 0;
  int final_failures = 0;
  long mismatched_clones = 0;  // clones whose score did not exceed the level (must be 0)
};

// An engine seeded by four counters (each split into two 32-bit words for std::seed_seq).
std::mt19937_64 Engine(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  std::vector<std::uint32_t> words;
  for (const std::uint64_t v : {a, b, c, d}) {
    words.push_back(static_cast<std::uint32_t>(v));
    words.push_back(static_cast<std::uint32_t>(v >> 32));
  }
  std::seed_seq sequence(words.begin(), words.end());
  return std::mt19937_64(sequence);
}

void Draw(std::mt19937_64& engine, std::vector<double>& u, std::size_t from_coordinate) {
  std::normal_distribution<double> normal;
  for (std::size_t i = from_coordinate; i < u.size(); ++i) u[i] = normal(engine);
}

Estimate Run(Splitting& s, int n, int k, std::uint64_t seed, int repetition) {
  std::vector<Replica> replicas(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    std::mt19937_64 engine =
        Engine(seed, static_cast<std::uint64_t>(repetition), 0, static_cast<std::uint64_t>(i));
    replicas[static_cast<std::size_t>(i)].u.resize(s.dimension());
    Draw(engine, replicas[static_cast<std::size_t>(i)].u, 0);
  }
  tbb::parallel_for(0, n, [&](int i) { s.Fly(replicas[static_cast<std::size_t>(i)]); });
  Estimate e;
  e.landings = n;
  double log_product = 0;
  const double target = s.limit().value;
  for (int iteration = 1;; ++iteration) {
    std::vector<double> scores(replicas.size());
    for (std::size_t i = 0; i < replicas.size(); ++i) scores[i] = replicas[i].score;
    std::nth_element(scores.begin(), scores.begin() + (k - 1), scores.end());
    const double z = scores[static_cast<std::size_t>(k - 1)];
    if (!(z < target)) break;
    std::vector<std::size_t> killed, survivors;
    for (std::size_t i = 0; i < replicas.size(); ++i)
      (replicas[i].score <= z ? killed : survivors).push_back(i);
    if (survivors.empty()) {
      e.probability = 0;
      e.iterations = iteration;
      return e;
    }
    log_product += std::log1p(-static_cast<double>(killed.size()) / n);
    std::vector<Replica> clones(killed.size());
    tbb::parallel_for(std::size_t{0}, killed.size(), [&](std::size_t j) {
      std::mt19937_64 engine = Engine(seed, static_cast<std::uint64_t>(repetition),
                                      static_cast<std::uint64_t>(iteration), static_cast<std::uint64_t>(j));
      const std::size_t parent =
          survivors[std::uniform_int_distribution<std::size_t>(0, survivors.size() - 1)(engine)];
      const Replica& p = replicas[parent];
      const std::size_t at = Splitting::FirstAbove(p, z);
      Replica& c = clones[j];
      c.u = p.u;
      const std::uint64_t keep = s.KeepBelow(s.TimeOf(at));
      // Fresh turbulence from the branch time on (the filters' initial state and the samples held
      // before it are the parent's).
      const auto from = static_cast<std::size_t>(NoisePointIndex(NoiseStream::kTurbulenceU, keep));
      if (at + 1 < p.xi.size()) Draw(engine, c.u, std::min(from, c.u.size()));
      s.Fly(c);
    });
    for (std::size_t j = 0; j < killed.size(); ++j) {
      if (!(clones[j].score > z)) ++e.mismatched_clones;
      replicas[killed[j]] = std::move(clones[j]);
    }
    e.landings += static_cast<long>(killed.size());
    e.iterations = iteration;
  }
  for (const auto& r : replicas) e.final_failures += r.failed ? 1 : 0;
  e.probability = std::exp(log_product) * e.final_failures / n;
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 7 || argc > 9) {
    std::fprintf(stderr,
                 "usage: risk_splitting STUDY LIMIT N K SEED REPETITIONS [LOOKAHEAD_PER_S [SERIES_S]]\n");
    return 2;
  }
  const int limit = std::atoi(argv[2]);
  const int n = std::atoi(argv[3]);
  const int k = std::atoi(argv[4]);
  const std::uint64_t seed = std::strtoull(argv[5], nullptr, 10);
  const int repetitions = std::atoi(argv[6]);
  const double lookahead = argc >= 8 ? std::atof(argv[7]) : 1.0;
  const double series_s = argc == 9 ? std::atof(argv[8]) : 0.01;
  if (n < 2 || k < 1 || k >= n || repetitions < 1 || !(lookahead >= 0) || !(series_s > 0)) {
    std::fprintf(stderr,
                 "risk_splitting: expected N >= 2, 1 <= K < N, REPETITIONS >= 1, LOOKAHEAD_PER_S >= 0, "
                 "SERIES_S > 0\n");
    return 2;
  }
  try {
    gesweep::Study study = gesweep::LoadStudy(argv[1]);
    study.storage.time_series = true;
    study.storage.output_dt_s = series_s;
    const gesweep::SweepPlan plan(std::move(study), gesweep::ShardSpec{});
    const gesweep::risk::RiskSpec spec = gesweep::risk::ReadRiskSpec(plan);
    if (limit < 0 || limit >= static_cast<int>(spec.limits.size())) {
      std::fprintf(stderr, "risk_splitting: %s: LIMIT = %d: the study has %zu limits\n", argv[1], limit,
                   spec.limits.size());
      return 2;
    }
    // The score is a sink rate, climbing towards the limit: only an upper limit on it is estimated.
    const auto& chosen = spec.limits[static_cast<std::size_t>(limit)];
    if (chosen.column != "touchdown_sink_rate_mps" || !chosen.above) {
      std::fprintf(stderr,
                   "risk_splitting: %s: LIMIT = %d (%s): expected a limit touchdown_sink_rate_mps > value\n",
                   argv[1], limit, chosen.text.c_str());
      return 2;
    }
    Splitting splitting(plan, spec, limit, lookahead);
    std::printf("# %s, %s: N = %d, K = %d, lookahead %g /s, dimension %zu, still-air touchdown H = %.4f m\n",
                argv[1], spec.limits[static_cast<std::size_t>(limit)].text.c_str(), n, k, lookahead,
                splitting.dimension(), splitting.touchdown_height());
    std::printf(
        "| repetition | P | iterations | final past the limit | landings | clones not above the level |\n");
    std::printf("|---|---|---|---|---|---|\n");
    gesweep::risk::programs::RepetitionTally tally;
    for (int r = 0; r < repetitions; ++r) {
      const Estimate e = Run(splitting, n, k, seed, r);
      std::printf("| %d | %.4g | %d | %d | %ld | %ld |\n", r, e.probability, e.iterations, e.final_failures,
                  e.landings, e.mismatched_clones);
      std::fflush(stdout);
      tally.Add(e.probability, e.landings);
    }
    tally.Print();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_splitting: %s\n", e.what());
    return 2;
  }
  return 0;
}
