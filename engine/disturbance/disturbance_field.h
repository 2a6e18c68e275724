#pragma once
/// The moving atmosphere of one run (docs/model.md §9, docs/disturbance.md): the object a time
/// response owns. It adds kStateCount states to the airplane's (the forming filters, the pitch-rate
/// lag and the distance flown into the gust), gives their derivatives, and the air motion at the
/// airplane that Eq. (1) in air-relative form takes (LongitudinalModel::StateDerivative).
///
/// Use inside an OdeProblem (engine/simulation/integrator.h):
///   DisturbanceField field(options, study_seed, run_index);
///   std::vector<double> breakpoints = field.Breakpoints(t0, t_end);   // merge with the inputs' own
///   std::vector<DisturbanceField::Segment> table = field.SegmentTable(breakpoints, t0);
///   // in Derivative(t, x, segment, dxdt):
///   AirMotion air = field.Evaluate(table[segment], H, u0 + Δu, x_field, dx_field);
///   then Eq. (1) with air.u_g_mps, air.w_g_mps, air.q_g_radps, air.w_g_dot_mps2.
/// The white noise is sampled every Δt_n from t = 0 and held (a function of time alone), so every
/// integrator that honours the breakpoints sees the same input whatever its steps. Not thread-safe
/// (a one-sample cache of the noise and a one-height cache of the height's terms): one field per run.

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/disturbance/disturbance_options.h"
#include "engine/disturbance/dryden.h"
#include "engine/disturbance/run_noise.h"

namespace gesweep {

/// The air motion at the airplane and its parts (velocities in m/s, positive forward and down).
struct AirMotion {
  double u_g_mps = 0;        ///< total u_g: mean wind + turbulence u + a u gust
  double w_g_mps = 0;        ///< total w_g: turbulence w + a w gust
  double q_g_radps = 0;      ///< pitch-rate gust (0 unless pitch_rate_gust)
  double w_g_dot_mps2 = 0;   ///< dw_g/dt along the flight path
  double airspeed_mps = 0;   ///< u0 + Δu − u_g, the speed the derivatives and filters use
  double mean_wind_mps = 0;  ///< the mean wind W(h)
  double turbulence_u_mps = 0;
  double turbulence_w_mps = 0;
  double gust_mps = 0;  ///< the discrete gust on its axis
};

class DisturbanceField {
 public:
  /// The field's states: the normalised u filter, the two w filter states, the pitch-rate lag (m/s)
  /// and the distance flown into the gust relative to the air (m).
  enum StateIndex : int {
    kTurbulenceU = 0,
    kTurbulenceW1 = 1,
    kTurbulenceW2 = 2,
    kPitchRateLag = 3,
    kGustDistance = 4
  };
  static constexpr int kStateCount = 5;
  using State = std::array<double, kStateCount>;

  /// What Evaluate needs to know about the integrator's segment: the held noise sample in force and
  /// whether the airplane has entered the gust.
  struct Segment {
    std::int64_t sample_index = 0;
    bool gust_started = false;
  };

  /// Throws InputError (source "disturbance options") when the options are out of range.
  DisturbanceField(const DisturbanceOptions& options, std::uint64_t study_seed, std::uint64_t run_index);
  /// The noise is the given point (RunNoise(point)); it must outlive the field.
  DisturbanceField(const DisturbanceOptions& options, std::span<const double> noise_point);

  const DisturbanceOptions& options() const { return options_; }
  const RunNoise& noise() const { return noise_; }
  /// σ_w in force, m/s (0 without turbulence).
  double sigma_w_mps() const { return sigma_w_mps_; }
  /// Whether any disturbance is present (false: still air; Evaluate then gives zeros).
  bool active() const { return turbulent_ || has_gust_ || options_.wind_20ft_mps != 0.0; }

  /// The initial field state: the filters drawn from their stationary distribution (so the
  /// turbulence is stationary from t = 0), the pitch-rate lag at w_g(0) (q_g(0) = 0), distance 0.
  State InitialState() const;

  /// The instants where the field's input jumps in (start_s, end_s), ascending: k·Δt_n (k ≥ 1) with
  /// turbulence, and gust_start_s with a gust.
  /// `cancel` (may be null) is read every kCancelCheckInterval instants: once it is true the list
  /// is abandoned and empty (the run is being stopped; the integrator stops before its first step).
  std::vector<double> Breakpoints(double start_s, double end_s,
                                  const std::atomic<bool>* cancel = nullptr) const;

  /// For each segment of an ascending breakpoint list (segment s = [b_{s−1}, b_s), segment 0 from
  /// start_s, as integrator.h numbers them) the Segment in force. The list must contain Breakpoints().
  /// `cancel` as for Breakpoints: once true the table keeps its size but is left unfilled.
  std::vector<Segment> SegmentTable(std::span<const double> breakpoints_s, double start_s,
                                    const std::atomic<bool>* cancel = nullptr) const;

  /// How many table entries are built between two reads of a cancellation flag (a few ms of work).
  static constexpr std::int64_t kCancelCheckInterval = 1 << 16;

  /// The number of sample instants k·Δt_n (k ≥ 1) at or before t: the held sample's index at t.
  std::int64_t SampleIndexAt(double time_s) const;

  /// The held unit-intensity white noise ξ of a stream on sample k: N(0, 1)/√Δt_n, 1/√s.
  double HeldNoise(NoiseStream stream, std::int64_t sample_index) const;

  /// Air motion at the airplane and the field's state derivatives, at height H (m) and inertial
  /// speed u0 + Δu (m/s), for field state x. Pure but for the caches (the noise sample, and the mean
  /// wind and Dryden scales of the last height: an integrator evaluates the field several times at
  /// the same height, at a step's end, its restart, its event check and its monitor).
  AirMotion Evaluate(const Segment& segment, double height_m, double inertial_speed_mps, const State& x,
                     State& dxdt) const;
  /// The air motion alone, as Evaluate gives it but without the state derivatives and ẇ_g
  /// (w_g_dot_mps2 is NaN): what a controller, an event or a monitor reads, at less cost.
  AirMotion Motion(const Segment& segment, double height_m, double inertial_speed_mps, const State& x) const;

  /// What Motion and Evaluate take from the height alone, the same doubles: the mean wind W(h) (m/s)
  /// and the Dryden σ_u (m/s), L_u and L_w (m) (zeros without turbulence). For a batch's lanes
  /// (engine/control/landing_lanes.h), which compute the rest of the field's arithmetic on vectors.
  void HeightTerms(double height_m, double& mean_wind_mps, double& sigma_u_mps, double& length_u_m,
                   double& length_w_m) const;

 private:
  DisturbanceField(const DisturbanceOptions& options, const RunNoise& noise);
  DisturbanceOptions options_;
  RunNoise noise_;
  double sigma_w_mps_ = 0;
  bool turbulent_ = false;
  bool has_gust_ = false;
  double noise_scale_ = 0;  // 1/√Δt_n
  // The terms that depend on the height alone, at the last height (NaN: none yet; a NaN height never
  // hits), and their values at and above the ceiling (and the scales at and below the floor), where
  // the formulas clamp the height: the same doubles without a log or pow.
  void UpdateHeightTerms(double height_m) const;
  double ceiling_mean_wind_mps_ = 0;
  DrydenScales ceiling_scales_;
  DrydenScales floor_scales_;
  mutable double cached_height_m_;
  mutable double cached_mean_wind_mps_ = 0;
  mutable DrydenScales cached_scales_;
  mutable std::int64_t cached_index_ = -1;
  // The filters' rates and the square roots of their noise gains at the last (height, airspeed).
  mutable double cached_rates_height_m_;
  mutable double cached_rates_airspeed_mps_ = 0;
  mutable double cached_a_u_ = 0;
  mutable double cached_a_w_ = 0;
  mutable double cached_gain_u_ = 0;
  mutable double cached_gain_w_ = 0;
  mutable double cached_u_ = 0;
  mutable double cached_w_ = 0;
};

}  // namespace gesweep
