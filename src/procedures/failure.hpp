// Failure detection for the benched slope trial (DESIGN.md "Procedures";
// docs/slope.md "Failure detection"): instead of eyeballing displacement
// pictures, find the connected sliding mass and decide stable / failed.
//
//   sliding mass  the particles whose accumulated displacement (since the
//                 reset after the cut) exceeds a threshold, grouped by
//                 proximity (centres within link_distance_factor x (Ri + Rj),
//                 which includes every contact and keeps a dilating slide and
//                 its loose grains together); the largest group by volume;
//   failed        a sliding mass of at least min_particles particles and
//                 min_volume_fraction of the slope's volume whose mean speed
//                 stays above the moving speed for consecutive_checks checks
//                 (latched: once failed, always failed); onset = the first of
//                 those checks;
//   stable        for consecutive_checks checks: mean unbalanced-force ratio
//                 below equilibrium_ratio, no significant moving mass and the
//                 largest group not growing.
//
// Thresholds scale with the specimen's median diameter d50 and the body
// field, so the same defaults serve the paper's slopes and small test worlds.
#pragma once

#include "procedures/slope_geometry.hpp"

#include <cstddef>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace centridem {

class World;
struct ParticleStore;

// Which particles make up a sliding mass (scenario table `failure`).
struct SlidingMassCriteria {
  // `displacement_threshold_d50`: a particle has slid when its displacement
  // since the reset exceeds this many median diameters. 0.5 d50 (= 1.95e-4 m
  // for the paper's d50 = 0.39 mm, inside its colour range 1.2e-4 .. 5e-3 m):
  // a grain that moved a radius has left its seat, while the elastic response
  // to the cut is ~1e-3 of a radius.
  double displacement_threshold_d50 = 0.5;
  // `displacement_threshold_m`: an absolute threshold instead (> 0) [m].
  double displacement_threshold_m = 0.0;
  // `link_distance_factor`: two sliding particles belong to one mass when
  // their centres are within this factor x (Ri + Rj) (>= 1; 1 = touching).
  double link_distance_factor = 1.2;
};

// When a sliding mass means failure, and when the slope is stable.
struct FailureCriteria {
  SlidingMassCriteria mass;
  // `min_particles` / `min_volume_fraction`: the mass is significant when it
  // holds at least this many particles AND at least this share of the
  // slope's particle volume: a body of grains, not a few rolling ones (the
  // count guards small models), and a visible part of the slope (the share
  // guards large ones: 1 % of the paper's 31,000-particle slope is ~310
  // particles, a wedge about 1 cm^2 in section at model scale).
  std::size_t min_particles = 100;
  double min_volume_fraction = 0.01;
  // `moving_speed_factor`: the mass is moving when its mean speed exceeds this
  // factor x sqrt(g d50) (g: the body field's mean magnitude over the slope),
  // i.e. 1 % of the speed a grain gains falling d50/2. `moving_speed_m_s` > 0
  // gives an absolute speed instead [m/s].
  double moving_speed_factor = 0.01;
  double moving_speed_m_s = 0.0;
  // `consecutive_checks`: checks in a row a decision needs (>= 1).
  int consecutive_checks = 2;
  // `failure_displacement_d50`: the mass is also only moving (failing) once
  // its mean displacement exceeds this many d50: a face that adjusts after the
  // cut by a fraction of a grain and comes to rest is not a slide (found on
  // the paper-size trials: the adjustment is fast but short). 0 = off.
  double failure_displacement_d50 = 1.0;
  // `equilibrium_ratio`: mean unbalanced-force ratio (PFC mech.ratio.avg)
  // of the slope body (the particles above the foundation) below which the
  // slope is at rest.
  double equilibrium_ratio = 1e-4;
  // `growth_tolerance`: a stable slope's largest sliding group may grow by at
  // most this fraction of its particles between checks.
  double growth_tolerance = 0.05;
  // `slip_surface_bin_d50`: width of the x bins of the slip surface, in d50.
  double slip_surface_bin_d50 = 2.0;
  // `start_share`: the start zone is the majority zone (original positions)
  // of the earliest-moving share of the mass at onset (at least 10 particles).
  double start_share = 0.05;
  // `bench_share`: a bench is a source of the slide when at least this share
  // of the mass's particles came from its column.
  double bench_share = 0.05;
};

// Throws InputError naming `where`.key for out-of-range values.
void validate(const FailureCriteria& c, const std::string& where = "failure");

// Volume-weighted median diameter of the particles (the mass median for one
// density; d50 as the paper uses it) [m]; 0 for no particles.
double median_diameter(const ParticleStore& particles);

struct SlidingMass {
  std::vector<std::size_t> indices; // current particle indices, ascending
  double volume_m3 = 0.0;           // sum of 4/3 pi R^3
  double threshold_m = 0.0;         // displacement threshold used [m]
  std::size_t above_threshold = 0;  // particles above it, in any group
  std::size_t groups = 0;           // connected groups among those
  std::size_t size() const { return indices.size(); }
};

// The largest (by volume) connected group of particles displaced more than
// the threshold; d50_m scales the relative threshold.
SlidingMass find_sliding_mass(const World& world, const SlidingMassCriteria& criteria,
                              double d50_m);

enum class SlopeState { undecided, stable, failed };
std::string_view to_string(SlopeState state);

// What a trial reports (summary.json "failure"). Lengths in DEM metres unless
// the name says model.
struct FailureReport {
  SlopeState state = SlopeState::undecided;
  bool settled = false; // at rest (ratio below equilibrium_ratio) at the last checks
  int checks = 0;
  double time_s = 0.0; // trial time of the last check
  // At the last check: the mean unbalanced-force ratio of the slope body (the
  // particles above the foundation, z > toe height), which decides "at rest";
  // and of the whole model, for reference (the foundation below dilutes it:
  // at the paper's size the whole-model ratio fell below 1e-4 0.6 ms after
  // the cut, before the slope had begun to move).
  double unbalanced_force_ratio = 0.0;
  double model_unbalanced_force_ratio = 0.0;
  // Scales the thresholds were derived from (fixed at the first check).
  double d50_m = 0.0;
  double gravity_m_s2 = 0.0;
  double displacement_threshold_m = 0.0;
  double moving_speed_m_s = 0.0;
  std::size_t slope_particles = 0; // at the first check (after the cut)
  double slope_volume_m3 = 0.0;

  std::optional<double> onset_time_s; // first check of the failing streak
  std::optional<ZoneId> start_zone;   // where the failing mass started (at onset)

  // The sliding mass (the largest group when it is significant, else empty).
  // After failure it is re-measured at every check, so the last report
  // describes the deposit.
  bool sliding_mass = false;
  std::size_t particles = 0;
  double volume_m3 = 0.0;
  double particle_share = 0.0; // of slope_particles
  double volume_share = 0.0;   // of slope_volume_m3
  double mean_speed_m_s = 0.0;
  double mean_displacement_m = 0.0;
  double max_displacement_m = 0.0;
  std::vector<int> benches_crossed; // bench numbers whose columns the mass spans (old or new x)
  std::vector<int> source_benches;  // benches (0 = toe floor) giving >= bench_share of the mass
  std::vector<std::size_t> particles_from_bench; // [0..N]: mass particles by original column
  std::vector<SectionPoint> slip_surface;        // lowest original centre z per x bin
  double front_x_m = 0.0;                        // largest current x of the mass's centres
  double runout_m = 0.0;                         // max(0, front_x - toe_x)
  double runout_model_m = 0.0;                   // runout_m / s

  std::size_t largest_group_particles = 0; // diagnostics: largest group, significant or not
  std::size_t above_threshold = 0;         // diagnostics: all particles above the threshold
};

nlohmann::json to_json(const FailureReport& report);

// One check, for the trial's time series.
struct FailureCheck {
  double time_s = 0.0;
  std::size_t above_threshold = 0;
  std::size_t mass_particles = 0; // largest group
  double mass_mean_speed_m_s = 0.0;
  double unbalanced_force_ratio = 0.0;
  bool significant = false, moving = false;
};

// Called every N steps of a trial (after the cut and the displacement reset)
// with the World and the trial time; decides stable / failed.
class FailureMonitor {
public:
  FailureMonitor(SlopeGeometry geometry, FailureCriteria criteria = {});

  // Measures the World and updates the state; returns it.
  SlopeState update(const World& world, double time_s);

  SlopeState state() const { return report_.state; }
  bool failed() const { return report_.state == SlopeState::failed; }
  bool stable() const { return report_.state == SlopeState::stable; }
  // Nothing left to watch: stable, or failed and the slide has come to rest.
  bool finished() const { return stable() || (failed() && report_.settled); }
  const FailureReport& report() const { return report_; }
  const std::vector<FailureCheck>& history() const { return history_; }
  const SlopeGeometry& geometry() const { return geometry_; }
  const FailureCriteria& criteria() const { return criteria_; }

  // The monitor's whole state (report, history, streaks, first crossings) for
  // checkpoints; restore() on a monitor made with the same geometry and
  // criteria continues exactly where save() was taken (doubles round-trip).
  nlohmann::json save() const;
  void restore(const nlohmann::json& state);

private:
  void describe_mass(const World& world, const SlidingMass& mass, double mean_speed);
  ZoneId start_zone(const World& world, const SlidingMass& mass) const;

  SlopeGeometry geometry_;
  FailureCriteria criteria_;
  FailureReport report_;
  std::vector<FailureCheck> history_;
  std::unordered_map<std::int64_t, int> first_check_above_; // particle id -> check index
  int moving_streak_ = 0, stable_streak_ = 0, settled_streak_ = 0;
  std::optional<double> streak_start_time_;
  std::optional<ZoneId> streak_start_zone_;
  std::size_t previous_group_ = 0;
};

} // namespace centridem
