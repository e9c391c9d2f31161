// The World: particles, walls, contacts, body field and contact defaults, and
// the cycle that advances them. Procedures drive a World only through these
// public calls; they never reach into the loops.
#pragma once

#include "engine/contacts.hpp"
#include "engine/particles.hpp"
#include "engine/walls.hpp"
#include "engine/work_split.hpp"
#include "physics/body_field.hpp"
#include "physics/contact_properties.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace centridem {

struct WorldSettings {
  double local_damping = 0.0;          // alpha, Cundall local damping (PFC `damp`) [-]
  double timestep_s = 0.0;             // fixed timestep; 0 = automatic [s]
  double timestep_safety_factor = 0.8; // automatic dt = factor x critical estimate [-]
  double timestep_growth_limit = 0.05; // automatic dt grows at most this fraction per step [-]
  int timestep_update_interval = 100;  // steps between critical-timestep estimates
  double neighbour_skin_m = 0.0;       // Verlet skin; 0 = half the smallest radius [m]
  double max_overlap_fraction =
      0.5; // instability guard: overlap / smaller radius [-] (> 0; > 1 tolerates deep overlaps)
  int threads = 0; // OpenMP threads; 0 = the OpenMP default
};

void validate(const WorldSettings& s);

// A box region [lo, hi] (axis aligned) [m].
struct Box {
  Vec3 lo, hi;
  bool contains(const Vec3& x) const {
    return x.x >= lo.x && x.x <= hi.x && x.y >= lo.y && x.y <= hi.y && x.z >= lo.z && x.z <= hi.z;
  }
  double volume() const { return (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z); }
};

// Periodic boundaries: along each flagged axis, space repeats with period
// hi - lo; a particle leaving at hi re-enters at lo (positions are wrapped at
// neighbour rebuilds). Each period must be at least 3 neighbour cells
// (3 x (largest diameter + skin)).
struct PeriodicBox {
  std::array<bool, 3> axis{false, false, false};
  Vec3 lo, hi; // [m]
  bool any() const { return axis[0] || axis[1] || axis[2]; }
  Vec3 length() const { return hi - lo; }
};

// An active contact, by particle ids, with everything needed to recreate it
// exactly (bricks, checkpoints).
struct ContactRecord {
  std::int64_t id1 = 0;               // first end (a ball)
  std::int64_t id2 = 0;               // second end: a ball id, or unused for a wall
  std::int32_t wall = -1;             // wall index for a ball-wall contact, else -1
  std::array<std::int8_t, 3> image{}; // periodic image of end 2 relative to end 1
  ContactProperties properties;
  ContactState state;
};

struct Energy {
  double kinetic_J = 0;        // 1/2 m v^2 summed
  double rotational_J = 0;     // 1/2 I w^2 summed
  double strain_normal_J = 0;  // 1/2 kn delta^2 over active contacts
  double strain_shear_J = 0;   // |Fs|^2 / (2 ks)
  double strain_rolling_J = 0; // |Mr|^2 / (2 kr)
  double attraction_J = 0;     // potential of the attraction (arrlinear), <= 0
  double total() const {
    return kinetic_J + rotational_J + strain_normal_J + strain_shear_J + strain_rolling_J +
           attraction_J;
  }
};

struct Measurements {
  long step = 0;
  double time_s = 0;
  double timestep_s = 0;
  std::size_t particles = 0;
  std::size_t ball_ball_contacts = 0;
  std::size_t ball_wall_contacts = 0;
  double coordination_number = 0;         // (2 Nbb + Nbw) / N
  double mean_unbalanced_force_ratio = 0; // PFC `mech.ratio.avg`
  double kinetic_energy_J = 0;            // translational + rotational
  double max_overlap_ratio = 0;           // largest overlap / smaller radius
};

struct RegionMeasurement {
  std::size_t particles = 0;         // particles whose centre is in the box
  double porosity = 0;               // 1 - (their volume)/(box volume), centre-based
  std::array<double, 9> stress_Pa{}; // mean stress tensor, row major, tension positive
  double mean_pressure_Pa = 0;       // -trace/3 (compression positive)
};

// One active ball-ball contact, for output (force chains) and tests.
struct ContactView {
  std::uint32_t i, j; // particle indices (current order)
  Vec3 point;         // contact point [m]
  Vec3 normal;        // i -> j
  Vec3 force_on_j;    // [N]
  double overlap_m;
  std::uint16_t properties;
};

class World {
public:
  explicit World(WorldSettings settings = {});

  const WorldSettings& settings() const { return settings_; }
  void set_local_damping(double alpha);
  void set_fixed_timestep(double dt_s); // 0 = automatic
  void set_max_overlap_fraction(double fraction);

  // --- particles -----------------------------------------------------------
  const ParticleStore& particles() const { return p_; }
  // Mutable access for set-up (velocities, flags, applied forces). After
  // moving particles or changing radii call particles_changed().
  ParticleStore& particles_mut() { return p_; }
  void particles_changed() { dirty_ = true; }
  std::size_t add_particle(const Vec3& x, double radius_m, double density_kg_m3,
                           std::int32_t group = 0, std::optional<std::int64_t> id = {});
  // Removes every particle for which remove(index) is true; returns how many.
  std::size_t remove_particles(const std::function<bool(std::size_t)>& remove);
  // Current index of a particle id (linear search; not for loops).
  std::optional<std::size_t> index_of(std::int64_t id) const;
  void reset_displacements();

  // --- walls -----------------------------------------------------------------
  std::size_t add_wall(Wall wall, const ContactProperties& defaults);
  void remove_wall(const std::string& name);
  std::size_t wall_index(const std::string& name) const; // throws InputError
  const std::vector<Wall>& walls() const { return walls_; }
  void set_wall_velocity(std::size_t wall, const Vec3& v) { walls_[wall].velocity = v; }
  void move_wall(std::size_t wall, const Vec3& displacement);
  // Servo control (see WallServo); pass servo.active = false to stop it.
  void set_wall_servo(std::size_t wall, const WallServo& servo);

  // --- periodic boundaries -------------------------------------------------
  void set_periodic(const PeriodicBox& box);
  const PeriodicBox& periodic() const { return periodic_; }

  // --- contact state for bricks and checkpoints -----------------------------
  std::vector<ContactRecord> contact_records() const;
  // Recreates contacts by particle id (matched at the next neighbour rebuild;
  // records whose particles are missing or too far apart are dropped).
  void restore_contacts(const std::vector<ContactRecord>& records);

  // --- body field and contact defaults (PFC contact model assignment table) --
  void set_body_field(const BodyField& f) { field_ = f; }
  const BodyField& body_field() const { return field_; }
  // New ball-ball contacts copy these; existing contacts keep theirs. Clears
  // any grading by height (below).
  void set_ball_ball_defaults(const ContactProperties& p);
  // Ball-ball defaults graded by height (the moisture of a centrifuge model,
  // procedures/moisture.hpp): a contact born with the mean height z of its two
  // centres in band b = clamp(floor((z - z0) / dz), 0, n - 1) copies
  // per_band[b] instead of the defaults; the bands below 0 and above n - 1
  // extend to infinity. Costs one division per contact born, nothing per
  // contact and step. An empty per_band removes the grading.
  struct HeightGradedDefaults {
    double z0_m = 0;                         // bottom of band 0 [m]
    double band_height_m = 0;                // dz [m] (> 0)
    std::vector<ContactProperties> per_band; // the defaults of each band, from the bottom
  };
  void set_ball_ball_defaults_by_height(const HeightGradedDefaults& g);
  // The band of height z among n bands of height dz from z0 (the rule above;
  // also what procedures use to grade existing contacts alike).
  static int height_band(double z_m, double z0_m, double band_height_m, int n) {
    const double b = std::floor((z_m - z0_m) / band_height_m);
    return !(b > 0) ? 0 : b >= n - 1 ? n - 1 : static_cast<int>(b);
  }
  HeightGradedDefaults ball_ball_defaults_by_height() const;
  const ContactProperties& ball_ball_defaults() const { return props_[ball_ball_default_]; }
  void set_wall_defaults(std::size_t wall, const ContactProperties& p);
  const ContactProperties& wall_defaults(std::size_t wall) const {
    return props_[walls_[wall].properties];
  }
  const ContactProperties& property_set(std::uint16_t index) const { return props_[index]; }
  // Changes the properties of existing ball-ball contacts for which
  // select(i, j) is true; returns how many contacts changed.
  std::size_t modify_ball_ball_contacts(const std::function<bool(std::size_t, std::size_t)>& select,
                                        const std::function<void(ContactProperties&)>& change);

  // --- cycling ---------------------------------------------------------------
  // Advances n steps. Throws InputError if a fixed timestep is above the
  // critical estimate, InstabilityError if the run goes unstable.
  void cycle(long steps);
  // Cycles until the mean unbalanced-force ratio is below `ratio` (checked
  // every `check_interval` steps) or max_steps; returns the steps taken.
  long cycle_until_equilibrium(double ratio, long max_steps, int check_interval = 100);
  long step_count() const { return step_; }
  double time() const { return time_; }
  double timestep() const { return dt_; }
  // Critical timestep estimate 2/omega_max over the current contacts [s].
  double critical_timestep();

  // --- measurements ----------------------------------------------------------
  Measurements measure() const;
  Energy energy() const;
  // PFC `mech.ratio.avg` over the free particles [-]. Summed in fixed blocks
  // of particles whose partial sums are added in block order, so the value,
  // and the step at which a run that waits for it stops, are the same bits on
  // any number of threads.
  double mean_unbalanced_force_ratio() const;
  // The same ratio over the particles for which include(i) is true (a part of
  // the model: the slope above its foundation, say); 0 when none [-].
  double mean_unbalanced_force_ratio(const std::function<bool(std::size_t)>& include) const;
  RegionMeasurement measure_region(const Box& box) const;
  // The contact network's affine (unrelaxed) modulus along `axis` (0 x, 1 y, 2 z) over the
  // particles whose centres lie in `box`: d sigma_aa / d eps_aa when every centre and wall moves
  // with one uniform strain eps_aa and no grain rearranges or slides [Pa]. Formula and source in
  // measurements.cpp.
  double affine_modulus_Pa(const Box& box, int axis) const;
  std::vector<ContactView> ball_ball_contacts() const;
  std::size_t bytes_per_particle() const; // all engine storage / particles
  std::size_t neighbour_entries() const { return bb_.entries(); }
  long neighbour_rebuilds() const { return rebuilds_; }
  // The Verlet skin of the lists [m]: neighbour_skin_m, or half the smallest
  // radius at the last rebuild.
  double skin() const;
  // Wall-clock seconds `cycle` has spent in each phase since construction:
  // the neighbour search (rebuilds and re-sorts, with the timestep estimate
  // after them), the contact pass, and the integration (forces gathered,
  // damping, motion, walls). Read by `centridem bench`; timing costs two
  // clock reads per phase and step, nothing per particle.
  struct PhaseSeconds {
    double neighbour_search = 0, contact_pass = 0, integration = 0;
    // Of the contact pass's and the integration's time, what the threads
    // spent waiting for the slowest at the end of each pass, averaged over
    // the team (engine/work_split.hpp, WorkSplit::waited_seconds; 0 with one
    // thread).
    double contact_pass_wait = 0, integration_wait = 0;
  };
  PhaseSeconds phase_seconds() const {
    PhaseSeconds s = phase_seconds_;
    s.contact_pass_wait = contact_split_.waited_seconds();
    s.integration_wait = integration_split_.waited_seconds();
    return s;
  }
  // OpenMP threads that ran the last step's integration (1 below 2,000
  // particles; see engine/thread_count.hpp).
  int threads_used() const { return threads_used_; }

  // Forces a rebuild of the neighbour lists (and re-sort) before the next step.
  void request_rebuild() { dirty_ = true; }
  // Whether the next step starts with a rebuild (a particle moved half the
  // skin, particles or walls changed, or one was requested).
  bool rebuild_pending() const { return dirty_; }

  // --- neighbour-list state (exact checkpoints) ------------------------------
  // What the neighbour lists were built from: with it (and the particles in
  // their current order, the walls and the contact records) a new World
  // rebuilds exactly the same lists, so a checkpoint need not force a rebuild
  // and a resumed run goes on bit for bit (io/checkpoint.hpp).
  struct BuildState {
    bool pending = true;           // a rebuild is due before the next step
    std::vector<Vec3> positions;   // particle positions at the last rebuild [m]
    std::vector<Vec3> wall_points; // wall reference points at the last rebuild [m]
    std::vector<Vec3> wall_motion; // wall displacement since the last rebuild [m]
    double cutoff_extra_m = 0;     // largest attraction range of any property set so far [m]
  };
  BuildState build_state() const;
  // Rebuilds the lists from `s` (call after the particles, walls and
  // restore_contacts); the next step then starts as it would have in the
  // World the state was taken from. Throws InputError if `s` does not fit.
  void restore_build_state(const BuildState& s);

  // --- clock (checkpoints) -----------------------------------------------------
  struct Clock {
    long step = 0;
    double time_s = 0;
    double timestep_s = 0;        // timestep of the last step
    double timestep_target_s = 0; // automatic-timestep target
    std::int64_t next_id = 1;     // id the next added particle gets
  };
  Clock clock() const { return {step_, time_, dt_, dt_target_, next_id_}; }
  void set_clock(const Clock& c) {
    step_ = c.step, time_ = c.time_s, dt_ = c.timestep_s, dt_target_ = c.timestep_target_s;
    next_id_ = c.next_id;
  }

private:
  double applied_force_magnitude(std::size_t i) const; // the ratio's denominator term [N]
  // The mean unbalanced-force ratio over the free particles (include: those of
  // them it accepts; nullptr: all), in fixed blocks summed in order.
  double unbalanced_force_ratio_over(const std::function<bool(std::size_t)>* include) const;
  void rebuild(std::vector<std::uint32_t> new_to_old);
  void rebuild_sorted();
  void ensure_built();
  void compute_contacts();
  template <bool Periodic> void compute_contacts_impl();
  // Vector from particle i to the (image of) particle j of ball-ball entry e.
  Vec3 pair_vector(std::uint32_t e, std::size_t i, std::size_t j) const {
    Vec3 d = p_.position[j] - p_.position[i];
    if (!bb_.image.empty()) d += image_shift_[bb_.image[e]];
    return d;
  }
  std::size_t first_end(std::uint32_t e) const;   // row that holds entry e
  std::uint16_t graded_default(double z_m) const; // defaults of the band of height z
  void integrate();
  void update_timestep(bool force_estimate);
  std::uint16_t register_properties(const ContactProperties& p);

  WorldSettings settings_;
  ParticleStore p_;
  std::vector<Vec3> position_at_build_;
  std::vector<Wall> walls_;
  std::vector<Vec3> wall_motion_since_build_;
  std::vector<Vec3> wall_point_at_build_;
  BodyField field_;
  std::vector<ContactProperties> props_;
  std::uint16_t ball_ball_default_ = 0;
  double band_z0_ = 0, band_height_ = 0;  // grading of the defaults by height [m]
  std::vector<std::uint16_t> band_props_; // property set of each band; empty: not graded
  BallBallContacts bb_;
  BallWallContacts bw_;
  std::int64_t next_id_ = 1;
  long step_ = 0;
  double time_ = 0;
  double dt_ = 0;
  double dt_target_ = 0;
  long rebuilds_ = 0;
  PhaseSeconds phase_seconds_;
  int threads_used_ = 1;
  bool dirty_ = true;
  double cutoff_extra_ = 0; // largest attraction range among property sets [m]
  PeriodicBox periodic_;
  std::array<Vec3, 27> image_shift_{};  // shift of image code c = (sx+1) + 3(sy+1) + 9(sz+1)
  std::vector<ContactRecord> restored_; // waiting for the next rebuild
  // Scratch of critical_timestep (kept to spare the allocations): each
  // contact's share for its second end, and each row's sum and whether it
  // had a ball-ball contact.
  struct TimestepScratch {
    std::vector<double> end2_share, row_sum;
    std::vector<std::uint8_t> row_any;
  } timestep_scratch_;
  double skin_cached_ = 0; // automatic skin at the last rebuild [m]
  // Whether any particle carries an applied force or moment, found at the
  // start of each cycle() call (the store changes only between calls): when
  // none does, the contact pass does not stream the two arrays of zeros.
  bool applied_loads_ = true;
  // An upper bound on how far any particle moved since the lists were built
  // [m] (kUnknownMove: not known, measure), and the largest move of the last
  // step [m] (integrate()). The distances are measured once the bound, grown
  // by twice the last step's move, no longer fits in kMoveBoundRoom of the
  // half skin.
  static constexpr double kUnknownMove = 1e300, kMoveBoundRoom = 0.9;
  double move_bound_m_ = kUnknownMove, last_step_move_m_ = 0.0;
  // Whether the contact pass keeps every contact's force on its second end
  // in force_on_2 (the measurements read them between cycle() calls): on the
  // last step of each call only.
  bool keep_contact_forces_ = true;
  // Instability report from the contact pass (first offending entry).
  std::uint32_t unstable_entry_ = UINT32_MAX;
  // The threads' blocks of rows in the contact pass and the integration,
  // moved towards equal measured time (engine/work_split.hpp; no effect on
  // the results).
  WorkSplit contact_split_, integration_split_;
  // The row blocks the last contact pass ran in (team + 1 boundaries): a
  // contact whose second end lies beyond its row's block leaves its load on
  // that end in the entry's record, which integrate() adds.
  std::vector<std::size_t> contact_blocks_;
};

} // namespace centridem
