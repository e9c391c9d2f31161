// The contact pass: for each particle row, the forces and moments of its
// ball-ball (j > i) and ball-wall contacts from the contact law
// (physics/contact_law.hpp), the body force, and the instability guard.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include <algorithm>
#include <cmath>

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
  std::uint32_t unstable = UINT32_MAX;

  // Each row i is handled by one thread: it computes the contacts (i, j > i)
  // and its ball-wall contacts, sums its own side in registers and leaves the
  // force and moment on j in the entry; integrate() gathers those in a fixed
  // order. No two threads write the same memory, and sums do not depend on
  // the thread count. Each thread takes one contiguous block of rows: the
  // particles are in cell order, so most neighbours j of a row i lie in the
  // same block and their cache lines stay with one core (chunks of 256 rows
  // dealt in turn gave 1.6x from 1 to 2 threads; contiguous blocks 1.9x).
#pragma omp parallel for schedule(static) num_threads(thread_count(settings_, n))                  \
    reduction(min                                                                                  \
              : unstable)
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 fi = P.mass[i] * field_.acceleration(x[i], v[i]) + P.applied_force[i];
    Vec3 mi = P.applied_moment[i];
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      const std::uint32_t j = bb_.other[e];
      Vec3 d = x[j] - x[i];
      if constexpr (Periodic) d += image_shift_[bb_.image[e]];
      const double dist2 = norm2(d);
      std::uint16_t pr = bb_.properties[e];
      if (pr == kNoContact) {
        const double reach = r[i] + r[j] + bb_default_range;
        if (dist2 >= reach * reach) continue; // not touching: nothing to do
        // Contact is born: copy the defaults (of the band of its height).
        pr = graded ? graded_default(x[i].z + 0.5 * d.z) : bb_default;
        bb_.state[e] = ContactState{};
      }
      const double dist = std::sqrt(dist2);
      const double overlap = r[i] + r[j] - dist;
      const ContactProperties& cp = props[pr];
      if (!contact_active(cp, overlap) || dist == 0.0) { // contact ends
        bb_.properties[e] = kNoContact;
        bb_.state[e] = ContactState{};
        bb_.force_on_2[e] = {};
        bb_.moment_on_2[e] = {};
        continue;
      }
      bb_.properties[e] = pr;
      const Vec3 nrm = d * (1.0 / dist);
      // Lever arms from the centres to the contact point: a1 n and -a2 n [m].
      // With them, the relative velocity at the contact point
      // (v_j + w_j x (-a2 n)) - (v_i + w_i x a1 n) is (v_j - v_i) - (a1 w_i + a2 w_j) x n,
      // and the moments of a force F about the centres are a1 (n x F) on i and
      // -a2 (n x F) on j: one cross product each instead of two.
      const double a1 = r[i] - 0.5 * overlap, a2 = r[j] - 0.5 * overlap;
      const ContactGeometry g{nrm,
                              overlap,
                              (v[j] - v[i]) - cross(a1 * w[i] + a2 * w[j], nrm),
                              w[j] - w[i],
                              std::min(r[i], r[j]),
                              r[i] + r[j],
                              r[i] * r[j] / (r[i] + r[j]),
                              has_dashpot(cp) ? m[i] * m[j] / (m[i] + m[j]) : 0.0};
      const ContactResult res = contact_law(cp, g, bb_.state[e], dt);
      const Vec3 nxf = cross(nrm, res.force);
      bb_.force_on_2[e] = res.force;
      bb_.moment_on_2[e] = res.moment - a2 * nxf;
      fi -= res.force;
      mi -= a1 * nxf + res.moment;
      if (overlap > max_overlap * std::min(r[i], r[j])) unstable = std::min(unstable, e);
    }
    // Ball-wall contacts of ball i (end 1 = ball, end 2 = wall).
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      const Wall& wl = walls_[bw_.wall[e]];
      const WallProximity prox = wall_proximity(wl, x[i]);
      const double overlap = r[i] - prox.distance;
      std::uint16_t pr = bw_.properties[e];
      if (pr == kNoContact) {
        if (!contact_active(props[wl.properties], overlap)) continue;
        pr = wl.properties;
        bw_.state[e] = ContactState{};
      }
      const ContactProperties& cp = props[pr];
      if (!contact_active(cp, overlap)) {
        bw_.properties[e] = kNoContact;
        bw_.state[e] = ContactState{};
        bw_.force_on_wall[e] = {};
        continue;
      }
      bw_.properties[e] = pr;
      const Vec3 nrm = ball_to_wall_normal(wl, prox);
      const double a = r[i] - 0.5 * overlap; // lever arm a n to the contact point [m]
      const ContactGeometry g{
          nrm, overlap, wl.velocity - v[i] + a * cross(nrm, w[i]), -w[i], r[i], r[i], r[i], m[i]};
      const ContactResult res = contact_law(cp, g, bw_.state[e], dt);
      bw_.force_on_wall[e] = res.force;
      fi -= res.force;
      mi -= a * cross(nrm, res.force) + res.moment;
      if (overlap > max_overlap * r[i])
        unstable = std::min(unstable, UINT32_MAX - 1 - static_cast<std::uint32_t>(i));
    }
    P.force[i] = fi;
    P.moment[i] = mi;
  }
  unstable_entry_ = unstable;
}

} // namespace centridem
