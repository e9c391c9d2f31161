// The contact pass: for each particle row, the forces and moments of its
// ball-ball (j > i) and ball-wall contacts from the contact law
// (physics/contact_law.hpp), the body force, and the instability guard.
//
// Contacts go through the law in SIMD batches (ContactLanes: 8 contacts at
// once with AVX-512). Each thread walks its block of rows downwards (from
// its last row to its first), a few rows at a time, in three passes over a
// small stage of contacts (one for ball-ball, one for ball-wall):
//   1. find: for each neighbour entry, the squared distance; contacts born;
//      the ones with a contact copied into the stage (structure of arrays);
//      then the same for the row's ball-wall entries;
//   2. law: each stage in batches of one property set, lane by lane the same
//      IEEE operations as the scalar law (physics/lanes.hpp); the batch also
//      takes the square root of the distance and says which contacts ended
//      and which overlap too deeply;
//   3. apply: in flat loops (not one per row: its exit at a varying count
//      mispredicts), each row's sums started from its body and applied
//      loads, then its ball-wall results subtracted, then its ball-ball
//      results in entry order; each ball-ball result is added at once to the
//      sums of its second end j (j > i: a row already started, in this
//      stage or an earlier one), unless j lies beyond the thread's block:
//      then it waits in the entry's record (force_on_2, moment_on_2) for
//      integrate().
// So each particle's sums run: body and applied loads, its walls, its own
// ball-ball contacts in entry order, then its contacts as second end from
// the highest first end down, whoever makes them: the bits do not depend on
// the batching or the thread count.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include "physics/lanes.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <omp.h>

namespace centridem {

// ------------------------------------------------------------------- cycle --

void World::compute_contacts() {
  if (periodic_.any())
    compute_contacts_impl<true>();
  else
    compute_contacts_impl<false>();
}

// The property set of a ball-ball contact born at mean centre height z when
// the defaults are graded by height (set_ball_ball_defaults_by_height). Out
// of line: called once per contact born, kept out of the contact loop's code.
[[gnu::noinline]] std::uint16_t World::graded_default(double z_m) const {
  return band_props_[height_band(z_m, band_z0_, band_height_,
                                 static_cast<int>(band_props_.size()))];
}

namespace {

constexpr std::size_t kLanes = ContactLanes::size;
constexpr std::uint32_t kStage = kContactStageSize; // engine/contacts.hpp

// The touching ball-ball contacts of a few consecutive rows, structure of
// arrays, padded to whole batches. Inputs are copied in by the find pass;
// the law overwrites the state and fills the results.
struct ContactStage {
  static constexpr std::size_t kCap = kStage + kLanes;
  std::uint32_t count = 0;
  alignas(64) std::uint32_t entry[kCap];
  alignas(64) std::uint32_t row[kCap]; // particle i (end 1)
  alignas(64) std::uint16_t props[kCap];
  // Inputs: centre-to-centre vector [m] and its squared length [m^2]; radii
  // [m]; masses [kg]; v_j - v_i [m/s]; spins [rad/s].
  alignas(64) double dx[kCap], dy[kCap], dz[kCap], dist2[kCap];
  alignas(64) double r1[kCap], r2[kCap], m1[kCap], m2[kCap];
  alignas(64) double vx[kCap], vy[kCap], vz[kCap];
  alignas(64) double w1x[kCap], w1y[kCap], w1z[kCap], w2x[kCap], w2y[kCap], w2z[kCap];
  // State in, new state out: shear force [N] and rolling moment [N m] on end 2.
  alignas(64) double fsx[kCap], fsy[kCap], fsz[kCap], mrx[kCap], mry[kCap], mrz[kCap];
  // Results: force on end 2 [N]; total moment on end 2 [N m]; what end 1's
  // moment loses, a1 (n x F) + M [N m].
  alignas(64) double fx[kCap], fy[kCap], fz[kCap], m2x[kCap], m2y[kCap], m2z[kCap];
  alignas(64) double m1x[kCap], m1y[kCap], m1z[kCap];
  // What the law found of the contact (kInForce, kEnded, kTooDeep).
  alignas(64) double status[kCap];

  template <class T> static void put(double* a, double* b, double* c, std::uint32_t k, const T& v) {
    a[k] = v.x, b[k] = v.y, c[k] = v.z;
  }
};

// The touching ball-wall contacts of the same rows (end 1 = ball, end 2 =
// wall), with the geometry the scalar pass would form.
struct WallStage {
  static constexpr std::size_t kCap = kStage + kLanes;
  std::uint32_t count = 0;
  alignas(64) std::uint32_t entry[kCap];
  alignas(64) std::uint32_t row[kCap]; // the ball, particle i (end 1)
  alignas(64) std::uint16_t props[kCap];
  // Inputs: unit normal ball -> wall; overlap [m]; lever arm a = r - overlap/2
  // [m]; ball radius [m] and mass [kg]; velocity of the wall's contact point
  // relative to the ball's [m/s]; relative spin, -w_ball [rad/s].
  alignas(64) double nx[kCap], ny[kCap], nz[kCap], overlap[kCap], lever[kCap], r[kCap], m[kCap];
  alignas(64) double vx[kCap], vy[kCap], vz[kCap], sx[kCap], sy[kCap], sz[kCap];
  // State in, new state out (on the wall).
  alignas(64) double fsx[kCap], fsy[kCap], fsz[kCap], mrx[kCap], mry[kCap], mrz[kCap];
  // Results: force and pure moment on the wall [N, N m].
  alignas(64) double fx[kCap], fy[kCap], fz[kCap], mx[kCap], my[kCap], mz[kCap];
};

// A staged ball-ball contact's status after the law: in force; ended (the
// surfaces apart beyond the attraction's reach, or the centres coincide: the
// contact is removed, its results unused); or in force and overlapping by
// more than the guard allows (the run stops unstable).
constexpr double kInForce = 0.0, kEnded = 1.0, kTooDeep = 2.0;

using LaneV = LaneVec<ContactLanes>;
using LaneM = LaneMask<ContactLanes>;

inline ContactLanes stage_load(const double* a, std::uint32_t k) {
  return ContactLanes::load_aligned(a + k);
}
inline LaneV stage_load(const double* a, const double* b, const double* c, std::uint32_t k) {
  return {stage_load(a, k), stage_load(b, k), stage_load(c, k)};
}
// Store lanes k .. k + kLanes - 1; with a mask, only the lanes it holds.
inline void stage_store(double* a, std::uint32_t k, const ContactLanes& v, const LaneM* only) {
  (only ? select(*only, v, stage_load(a, k)) : v).store_aligned(a + k);
}
inline void stage_store(double* a, double* b, double* c, std::uint32_t k, const LaneV& v,
                        const LaneM* only) {
  stage_store(a, k, v.x, only), stage_store(b, k, v.y, only), stage_store(c, k, v.z, only);
}

// The law for the batch of stage indices k .. k + kLanes - 1 under
// properties cp; with a mask, only the lanes it holds are stored. The
// geometry is formed exactly as a scalar pass would form it.
void stage_law(ContactStage& s, std::uint32_t k, const ContactProperties& cp, double dt,
               double max_overlap, const LaneM* only = nullptr) {
  using T = ContactLanes;
  // The centre distance here, a batch at once, rather than in the find
  // pass, where each contact's square root delayed its own next steps.
  const T dist = sqrt(stage_load(s.dist2, k));
  const T r1 = stage_load(s.r1, k), r2 = stage_load(s.r2, k);
  const LaneV nrm = stage_load(s.dx, s.dy, s.dz, k) * (T(1.0) / dist);
  const T overlap = r1 + r2 - dist;
  const LaneM active = contact_active(cp, overlap) & (dist != T(0.0));
  const LaneM too_deep = overlap > T(max_overlap) * lane_min(r1, r2);
  stage_store(s.status, k, select(active, select(too_deep, T(kTooDeep), T(kInForce)), T(kEnded)),
              only);
  // Lever arms from the centres to the contact point: a1 n and -a2 n [m].
  // With them, the relative velocity at the contact point
  // (v_j + w_j x (-a2 n)) - (v_i + w_i x a1 n) is (v_j - v_i) - (a1 w_i + a2 w_j) x n,
  // and the moments of a force F about the centres are a1 (n x F) on i and
  // -a2 (n x F) on j: one cross product each instead of two.
  const T a1 = r1 - T(0.5) * overlap, a2 = r2 - T(0.5) * overlap;
  const LaneV w1 = stage_load(s.w1x, s.w1y, s.w1z, k);
  const LaneV w2 = stage_load(s.w2x, s.w2y, s.w2z, k);
  T mc(0.0);
  if (has_dashpot(cp)) {
    const T m1 = stage_load(s.m1, k), m2 = stage_load(s.m2, k);
    mc = m1 * m2 / (m1 + m2);
  }
  const ContactGeometryT<T> g{nrm,
                              overlap,
                              stage_load(s.vx, s.vy, s.vz, k) - cross(a1 * w1 + a2 * w2, nrm),
                              w2 - w1,
                              lane_min(r1, r2),
                              r1 + r2,
                              r1 * r2 / (r1 + r2),
                              mc};
  ContactStateT<T> state{stage_load(s.fsx, s.fsy, s.fsz, k), stage_load(s.mrx, s.mry, s.mrz, k)};
  const ContactResultT<T> res = contact_law(cp, g, state, dt);
  const LaneV nxf = cross(nrm, res.force);
  stage_store(s.fsx, s.fsy, s.fsz, k, state.shear_force, only);
  stage_store(s.mrx, s.mry, s.mrz, k, state.rolling_moment, only);
  stage_store(s.fx, s.fy, s.fz, k, res.force, only);
  stage_store(s.m2x, s.m2y, s.m2z, k, res.moment - a2 * nxf, only);
  stage_store(s.m1x, s.m1y, s.m1z, k, a1 * nxf + res.moment, only);
}

// The ball-wall law for the batch k .. k + kLanes - 1 (as stage_law).
void wall_stage_law(WallStage& s, std::uint32_t k, const ContactProperties& cp, double dt,
                    const LaneM* only = nullptr) {
  using T = ContactLanes;
  const T r = stage_load(s.r, k);
  const ContactGeometryT<T> g{stage_load(s.nx, s.ny, s.nz, k),
                              stage_load(s.overlap, k),
                              stage_load(s.vx, s.vy, s.vz, k),
                              stage_load(s.sx, s.sy, s.sz, k),
                              r,
                              r,
                              r,
                              stage_load(s.m, k)};
  ContactStateT<T> state{stage_load(s.fsx, s.fsy, s.fsz, k), stage_load(s.mrx, s.mry, s.mrz, k)};
  const ContactResultT<T> res = contact_law(cp, g, state, dt);
  stage_store(s.fsx, s.fsy, s.fsz, k, state.shear_force, only);
  stage_store(s.mrx, s.mry, s.mrz, k, state.rolling_moment, only);
  stage_store(s.fx, s.fy, s.fz, k, res.force, only);
  stage_store(s.mx, s.my, s.mz, k, res.moment, only);
}

// The law for a whole stage of n contacts with property sets props, in
// batches of kLanes (the caller pads the last batch with copies of the last
// contact, results unused): law(k0, properties, mask). A batch whose
// contacts have several property sets (graded defaults, properties changed
// between stages) runs once per set, each run storing only its own lanes: a
// lane reads only its own inputs, so the lanes a run does not store do not
// matter.
template <class Law>
void law_in_batches(std::uint32_t padded, const std::uint16_t* props_of,
                    const ContactProperties* props, Law&& law) {
  for (std::uint32_t k0 = 0; k0 < padded; k0 += kLanes) {
    const std::uint16_t* pr = props_of + k0;
    if (std::all_of(pr + 1, pr + kLanes, [&](std::uint16_t p) { return p == pr[0]; })) {
      law(k0, props[pr[0]], nullptr);
      continue;
    }
    alignas(64) double id[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) id[l] = pr[l];
    const ContactLanes ids = ContactLanes::load_aligned(id);
    for (std::size_t l = 0; l < kLanes; ++l) {
      if (std::find(pr, pr + l, pr[l]) != pr + l) continue; // this set has run
      const LaneM mine = ids == ContactLanes(id[l]);
      law(k0, props[pr[l]], &mine);
    }
  }
}

// Pads a stage of n contacts to whole batches with copies of the last one;
// returns the padded size.
template <class Stage> std::uint32_t pad_stage(Stage& s, std::initializer_list<double*> arrays) {
  const std::uint32_t n = s.count;
  const std::uint32_t padded = static_cast<std::uint32_t>((n + kLanes - 1) / kLanes * kLanes);
  for (std::uint32_t k = n; k < padded; ++k) {
    s.props[k] = s.props[n - 1];
    for (double* a : arrays) a[k] = a[n - 1];
  }
  return padded;
}

void stage_law_all(ContactStage& s, const ContactProperties* props, double dt, double max_overlap) {
  if (s.count == 0) return;
  const std::uint32_t padded = pad_stage(
      s, {s.dx,  s.dy,  s.dz,  s.dist2, s.r1,  s.r2,  s.m1,  s.m2,  s.vx,  s.vy,  s.vz, s.w1x,
          s.w1y, s.w1z, s.w2x, s.w2y,   s.w2z, s.fsx, s.fsy, s.fsz, s.mrx, s.mry, s.mrz});
  law_in_batches(padded, s.props, props,
                 [&](std::uint32_t k0, const ContactProperties& cp, const LaneM* only) {
                   stage_law(s, k0, cp, dt, max_overlap, only);
                 });
}

void wall_stage_law_all(WallStage& s, const ContactProperties* props, double dt) {
  if (s.count == 0) return;
  const std::uint32_t padded =
      pad_stage(s, {s.nx, s.ny, s.nz, s.overlap, s.lever, s.r, s.m, s.vx, s.vy, s.vz, s.sx, s.sy,
                    s.sz, s.fsx, s.fsy, s.fsz, s.mrx, s.mry, s.mrz});
  law_in_batches(padded, s.props, props,
                 [&](std::uint32_t k0, const ContactProperties& cp, const LaneM* only) {
                   wall_stage_law(s, k0, cp, dt, only);
                 });
}

} // namespace

template <bool Periodic> void World::compute_contacts_impl() {
  const std::size_t n = p_.size();
  const double dt = dt_;
  auto& P = p_;
  const auto& x = p_.position;
  const auto& v = p_.velocity;
  const auto& w = p_.spin;
  const auto& r = p_.radius;
  const auto& m = p_.mass;
  const ContactProperties* props = props_.data();
  const std::uint16_t bb_default = ball_ball_default_;
  const ContactProperties& bb_def = props_[bb_default];
  // Reach of a contact not yet made: the attraction range of the defaults
  // (and of the graded defaults, below).
  const double bb_default_range = [&] {
    double reach = bb_def.attraction_force_N > 0 ? bb_def.attraction_range_m : 0.0;
    for (std::uint16_t k : band_props_)
      if (props_[k].attraction_force_N > 0) reach = std::max(reach, props_[k].attraction_range_m);
    return reach;
  }();
  const bool graded = !band_props_.empty(); // defaults graded by height
  const double max_overlap = settings_.max_overlap_fraction;
  // Contacts whose second end is at or above this row keep their force on it
  // in force_on_2 (besides those beyond their block): all on the last step
  // of a cycle() call, none otherwise.
  const std::size_t keep_all = keep_contact_forces_ ? 0 : n;
  std::uint32_t unstable = UINT32_MAX;
  const int threads = thread_count(settings_, n);
  contact_split_.prepare(threads, n);
  int used_team = 1;

  // Each thread takes one contiguous block of rows: the particles are in cell
  // order, so most neighbours j of a row i lie in the same block and their
  // cache lines stay with one core (chunks of 256 rows dealt in turn gave
  // 1.6x from 1 to 2 threads; contiguous blocks 1.9x). The blocks follow the
  // measured time of each (engine/work_split.hpp). The row owner i sums
  // its own side and adds the force and moment on j to j's sums when j is in
  // its block, or leaves them in the entry's record, which integrate() adds
  // after the pass. No two threads write the same memory, and no sum depends
  // on the thread count.
#pragma omp parallel num_threads(threads) reduction(min : unstable)
  {
    const int team = omp_get_num_threads();
    const int me = omp_get_thread_num();
    const double t_start = team > 1 ? omp_get_wtime() : 0.0;
    const auto [first_row, end] = contact_split_.block(me, team, n);
    const std::size_t keep_from = std::min(end, keep_all);
    static thread_local ContactStage stage;
    static thread_local WallStage wall_stage;
    // The passes, defined in the parallel region so that `unstable` is this
    // thread's copy of the reduction variable.
    // Pass 1 for entries e_begin .. e_end - 1 of row i: the touching ball-ball
    // contacts into the stage.
    auto find = [&](std::size_t i, std::uint32_t e_begin, std::uint32_t e_end, ContactStage& s) {
      // Row i's own values, read once (the stage's stores could alias them).
      const Vec3 xi = x[i], vi = v[i], wi = w[i];
      const double ri = r[i], mi = m[i];
      std::uint32_t count = s.count;
      for (std::uint32_t e = e_begin; e < e_end; ++e) {
        const std::uint32_t j = bb_.other[e];
        Vec3 d = x[j] - xi;
        if constexpr (Periodic) d += image_shift_[bb_.image[e]];
        const double dist2 = norm2(d);
        std::uint16_t pr = bb_.properties[e];
        if (pr == kNoContact) {
          const double reach = ri + r[j] + bb_default_range;
          if (dist2 >= reach * reach) continue; // not touching: nothing to do
          // Contact is born: copy the defaults (of the band of its height).
          pr = graded ? graded_default(xi.z + 0.5 * d.z) : bb_default;
          bb_.state[e] = ContactState{};
        }
        // Staged; whether it still holds (its distance against the reach of
        // its property set) is the law's to say (stage_law: status).
        bb_.properties[e] = pr;
        const std::uint32_t k = count++;
        s.entry[k] = e;
        s.row[k] = static_cast<std::uint32_t>(i);
        s.props[k] = pr;
        ContactStage::put(s.dx, s.dy, s.dz, k, d);
        s.dist2[k] = dist2;
        s.r1[k] = ri, s.r2[k] = r[j], s.m1[k] = mi, s.m2[k] = m[j];
        ContactStage::put(s.vx, s.vy, s.vz, k, v[j] - vi);
        ContactStage::put(s.w1x, s.w1y, s.w1z, k, wi);
        ContactStage::put(s.w2x, s.w2y, s.w2z, k, w[j]);
        ContactStage::put(s.fsx, s.fsy, s.fsz, k, bb_.state[e].shear_force);
        ContactStage::put(s.mrx, s.mry, s.mrz, k, bb_.state[e].rolling_moment);
      }
      s.count = count;
    };

    // Pass 3, in flat loops (not one per row, whose exit at a varying count
    // mispredicts): the rows' sums start from the body and applied loads in
    // the arrays; each staged ball-ball result is subtracted from its row's
    // sums in stage order (per row, entry order), then each ball-wall result
    // (end 1 = ball, end 2 = wall): per row the order of a scalar pass, also
    // when a long row goes through the stages in pieces.
    struct RowSums {
      Vec3 force, moment;
    };
    // Without applied loads the sums start from the same +0.0 the arrays hold
    // (applied_loads_), without reading them.
    const bool applied = applied_loads_;
    auto start_row = [&](std::size_t i) {
      return applied ? RowSums{P.mass[i] * field_.acceleration(x[i], v[i]) + P.applied_force[i],
                               P.applied_moment[i]}
                     : RowSums{P.mass[i] * field_.acceleration(x[i], v[i]) + Vec3{}, Vec3{}};
    };
    // A staged contact the law did not find plainly in force: an ended one
    // is removed (false: its results are not used); one too deep is noted for
    // the instability report (true: it still acts).
    auto end_or_flag = [&](const ContactStage& s, std::uint32_t k) {
      const std::uint32_t e = s.entry[k];
      if (s.status[k] == kTooDeep) {
        unstable = std::min(unstable, e);
        return true;
      }
      bb_.properties[e] = kNoContact;
      bb_.state[e] = ContactState{};
      bb_.force_on_2[e] = {};
      bb_.moment_on_2[e] = {};
      return false;
    };
    auto start_rows = [&](std::size_t first, std::size_t last) {
      for (std::size_t row = first; row < last; ++row) {
        const RowSums sum = start_row(row);
        P.force[row] = sum.force;
        P.moment[row] = sum.moment;
      }
    };
    auto apply_staged = [&](const ContactStage& s) {
      for (std::uint32_t k = 0; k < s.count; ++k) {
        const std::uint32_t e = s.entry[k], row = s.row[k];
        if (s.status[k] != kInForce && !end_or_flag(s, k)) continue;
        const Vec3 f{s.fx[k], s.fy[k], s.fz[k]}, m2{s.m2x[k], s.m2y[k], s.m2z[k]};
        bb_.state[e] = {{s.fsx[k], s.fsy[k], s.fsz[k]}, {s.mrx[k], s.mry[k], s.mrz[k]}};
        P.force[row] -= f;
        P.moment[row] -= Vec3{s.m1x[k], s.m1y[k], s.m1z[k]};
        // End 2: its row was started in an earlier stage or this one (rows go
        // downwards, j > i), so it takes the load now; beyond the block, the
        // record waits for integrate(). The force is also kept on the last
        // step of a cycle() call, for the measurements.
        const std::uint32_t j = bb_.other[e];
        if (j >= keep_from) bb_.force_on_2[e] = f;
        if (j < end) {
          P.force[j] += f;
          P.moment[j] += m2;
        } else {
          bb_.moment_on_2[e] = m2;
          // Two threads of earlier blocks may flag the same j (atomic, so
          // that this is no data race; a plain byte store on x86).
          std::atomic_ref<std::uint8_t>(bb_.record_waits[j]).store(1, std::memory_order_relaxed);
        }
      }
    };
    // Pass 1 for ball-wall entries e_begin .. e_end - 1 of row i (end 1 =
    // ball, end 2 = wall): the touching ones into the wall stage.
    auto find_walls = [&](std::size_t i, std::uint32_t e_begin, std::uint32_t e_end, WallStage& s) {
      std::uint32_t count = s.count;
      for (std::uint32_t e = e_begin; e < e_end; ++e) {
        const Wall& wl = walls_[bw_.wall[e]];
        const WallProximity prox = wall_proximity(wl, x[i]);
        const double overlap = r[i] - prox.distance;
        std::uint16_t pr = bw_.properties[e];
        if (pr == kNoContact) {
          if (!contact_active(props[wl.properties], overlap)) continue;
          pr = wl.properties;
          bw_.state[e] = ContactState{};
        }
        if (!contact_active(props[pr], overlap)) {
          bw_.properties[e] = kNoContact;
          bw_.state[e] = ContactState{};
          bw_.force_on_wall[e] = {};
          continue;
        }
        bw_.properties[e] = pr;
        if (overlap > max_overlap * r[i])
          unstable = std::min(unstable, UINT32_MAX - 1 - static_cast<std::uint32_t>(i));
        const Vec3 nrm = ball_to_wall_normal(wl, prox);
        const double a = r[i] - 0.5 * overlap; // lever arm a n to the contact point [m]
        const std::uint32_t k = count++;
        s.entry[k] = e;
        s.row[k] = static_cast<std::uint32_t>(i);
        s.props[k] = pr;
        ContactStage::put(s.nx, s.ny, s.nz, k, nrm);
        s.overlap[k] = overlap, s.lever[k] = a, s.r[k] = r[i], s.m[k] = m[i];
        ContactStage::put(s.vx, s.vy, s.vz, k, wl.velocity - v[i] + a * cross(nrm, w[i]));
        ContactStage::put(s.sx, s.sy, s.sz, k, -w[i]);
        ContactStage::put(s.fsx, s.fsy, s.fsz, k, bw_.state[e].shear_force);
        ContactStage::put(s.mrx, s.mry, s.mrz, k, bw_.state[e].rolling_moment);
      }
      s.count = count;
    };
    auto apply_wall_staged = [&](const WallStage& s) {
      for (std::uint32_t k = 0; k < s.count; ++k) {
        const std::uint32_t e = s.entry[k], row = s.row[k];
        const Vec3 f{s.fx[k], s.fy[k], s.fz[k]};
        const Vec3 nrm{s.nx[k], s.ny[k], s.nz[k]};
        bw_.state[e] = {{s.fsx[k], s.fsy[k], s.fsz[k]}, {s.mrx[k], s.mry[k], s.mrz[k]}};
        bw_.force_on_wall[e] = f;
        P.force[row] -= f;
        P.moment[row] -= s.lever[k] * cross(nrm, f) + Vec3{s.mx[k], s.my[k], s.mz[k]};
      }
    };

    std::size_t top = end; // rows top .. end - 1 are done
    while (top > first_row) {
      const std::size_t i = top - 1;
      const std::uint32_t row_length = bb_.row_offset[i + 1] - bb_.row_offset[i];
      if (row_length > kStage || bw_.row_offset[i + 1] - bw_.row_offset[i] > kStage) {
        --top;
        // A row longer than the stage (a large grain among fine ones): its
        // entries go through the stage kStage at a time, its sums carried on
        // across the pieces in entry order; then its ball-wall entries alike.
        start_rows(i, i + 1);
        for (std::uint32_t e0 = bw_.row_offset[i]; e0 < bw_.row_offset[i + 1]; e0 += kStage) {
          const std::uint32_t e1 = std::min(bw_.row_offset[i + 1], e0 + kStage);
          wall_stage.count = 0;
          find_walls(i, e0, e1, wall_stage);
          wall_stage_law_all(wall_stage, props, dt);
          apply_wall_staged(wall_stage);
        }
        for (std::uint32_t e0 = bb_.row_offset[i]; e0 < bb_.row_offset[i + 1]; e0 += kStage) {
          const std::uint32_t e1 = std::min(bb_.row_offset[i + 1], e0 + kStage);
          stage.count = 0;
          find(i, e0, e1, stage);
          stage_law_all(stage, props, dt, max_overlap);
          apply_staged(stage);
        }
        continue;
      }
      // Stage whole rows while they surely fit (a row stages at most its
      // entries), run the law on them, then apply them.
      stage.count = 0;
      wall_stage.count = 0;
      const std::size_t last = top;
      while (top > first_row) {
        const std::size_t row = top - 1;
        if (stage.count + (bb_.row_offset[row + 1] - bb_.row_offset[row]) > kStage ||
            wall_stage.count + (bw_.row_offset[row + 1] - bw_.row_offset[row]) > kStage)
          break;
        find(row, bb_.row_offset[row], bb_.row_offset[row + 1], stage);
        if (bw_.row_offset[row] != bw_.row_offset[row + 1])
          find_walls(row, bw_.row_offset[row], bw_.row_offset[row + 1], wall_stage);
        --top;
      }
      stage_law_all(stage, props, dt, max_overlap);
      wall_stage_law_all(wall_stage, props, dt);
      start_rows(top, last);
      apply_wall_staged(wall_stage);
      apply_staged(stage);
    }
    if (team > 1) contact_split_.record(me, omp_get_wtime() - t_start);
    if (me == 0) used_team = team;
  }
  contact_split_.bounds(used_team, n, contact_blocks_);
  contact_split_.rebalance();
  unstable_entry_ = unstable;
}

} // namespace centridem
