// Measurements of the World: the unbalanced-force ratio (in fixed blocks,
// thread-independent), energies, region porosity and stress, contact views,
// memory per particle.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include "base/errors.hpp"
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace centridem {

namespace {
// The sizes the stiffness rule reads for a ball-ball contact of radii r1, r2 at overlap ov [m]
// (as the contact pass forms them: contact radius min(R1, R2), length R1 + R2, rolling radius
// R1 R2 / (R1 + R2)); the vectors and the mass are left zero, as no measurement here reads them.
ContactGeometry ball_ball_geometry(double r1, double r2, double ov) {
  return {{}, ov, {}, {}, std::min(r1, r2), r1 + r2, r1 * r2 / (r1 + r2), 0.0};
}
} // namespace

// ------------------------------------------------------------ measurements --

// The magnitudes of every force applied to particle i: body, applied,
// contacts (PFC `mech.ratio.avg`'s denominator) [N].
double World::applied_force_magnitude(std::size_t i) const {
  double a = norm(p_.mass[i] * field_.acceleration(p_.position[i], p_.velocity[i])) +
             norm(p_.applied_force[i]);
  for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e)
    if (bb_.properties[e] != kNoContact) a += norm(bb_.force_on_2[e]);
  for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k)
    if (bb_.properties[bb_.incoming[k]] != kNoContact) a += norm(bb_.force_on_2[bb_.incoming[k]]);
  for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e)
    if (bw_.properties[e] != kNoContact) a += norm(bw_.force_on_wall[e]);
  return a;
}

double World::unbalanced_force_ratio_over(const std::function<bool(std::size_t)>* include) const {
  const std::size_t n = p_.size();
  if (n == 0 || bb_.row_offset.size() != n + 1) return 0.0;
  // PFC `mech.ratio.avg`: average unbalanced force magnitude over the average
  // magnitude of the forces applied to the balls (body, applied, contacts).
  // Blocks of kBlock particles in parallel, their sums added in block order:
  // the rounding does not depend on how the blocks were shared out.
  constexpr std::size_t kBlock = 512;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> unbalanced(blocks), applied(blocks); // once per check, not per step
#pragma omp parallel for schedule(static) num_threads(thread_count(settings_, n))
  for (std::size_t b = 0; b < blocks; ++b) {
    double u = 0.0, a = 0.0;
    for (std::size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      if ((p_.flags[i] & fix_translation) || (include && !(*include)(i))) continue;
      u += norm(p_.force[i]);
      a += applied_force_magnitude(i);
    }
    unbalanced[b] = u;
    applied[b] = a;
  }
  double u = 0.0, a = 0.0;
  for (std::size_t b = 0; b < blocks; ++b) {
    u += unbalanced[b];
    a += applied[b];
  }
  return a > 0 ? u / a : 0.0;
}

double World::mean_unbalanced_force_ratio() const {
  return unbalanced_force_ratio_over(nullptr);
}

double World::mean_unbalanced_force_ratio(const std::function<bool(std::size_t)>& include) const {
  return unbalanced_force_ratio_over(&include);
}

Measurements World::measure() const {
  Measurements out;
  out.step = step_;
  out.time_s = time_;
  out.timestep_s = dt_;
  out.particles = p_.size();
  const std::size_t n = p_.size();
  if (bb_.row_offset.size() != n + 1) return out;
  double max_ratio = 0.0;
  std::size_t nbb = 0, nbw = 0;
  double ke = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      ++nbb;
      const std::uint32_t j = bb_.other[e];
      const double ov = p_.radius[i] + p_.radius[j] - norm(pair_vector(e, i, j));
      max_ratio = std::max(max_ratio, ov / std::min(p_.radius[i], p_.radius[j]));
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      ++nbw;
      const double ov = p_.radius[i] - wall_proximity(walls_[bw_.wall[e]], p_.position[i]).distance;
      max_ratio = std::max(max_ratio, ov / p_.radius[i]);
    }
    ke += 0.5 * p_.mass[i] * norm2(p_.velocity[i]) + 0.5 * p_.inertia[i] * norm2(p_.spin[i]);
  }
  out.ball_ball_contacts = nbb;
  out.ball_wall_contacts = nbw;
  out.coordination_number =
      n ? (2.0 * static_cast<double>(nbb) + static_cast<double>(nbw)) / static_cast<double>(n)
        : 0.0;
  out.mean_unbalanced_force_ratio = mean_unbalanced_force_ratio();
  out.kinetic_energy_J = ke;
  out.max_overlap_ratio = max_ratio;
  return out;
}

Energy World::energy() const {
  Energy en;
  const std::size_t n = p_.size();
  for (std::size_t i = 0; i < n; ++i) {
    en.kinetic_J += 0.5 * p_.mass[i] * norm2(p_.velocity[i]);
    en.rotational_J += 0.5 * p_.inertia[i] * norm2(p_.spin[i]);
  }
  if (bb_.row_offset.size() != n + 1) return en;
  auto strain = [&](const ContactProperties& cp, const ContactGeometry& g, const ContactState& s) {
    const ContactStiffness k = contact_stiffness(cp, g);
    const double ov = std::max(g.overlap_m, 0.0);
    en.strain_normal_J += 0.5 * k.kn * ov * ov;
    if (k.ks > 0) en.strain_shear_J += norm2(s.shear_force) / (2.0 * k.ks);
    if (k.kr > 0) en.strain_rolling_J += norm2(s.rolling_moment) / (2.0 * k.kr);
    en.attraction_J += attraction_potential(cp, g.overlap_m);
  };
  const auto& r = p_.radius;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const double ov = r[i] + r[j] - norm(pair_vector(e, i, j));
      strain(props_[bb_.properties[e]], ball_ball_geometry(r[i], r[j], ov), bb_.state[e]);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const double ov = r[i] - wall_proximity(walls_[bw_.wall[e]], p_.position[i]).distance;
      strain(props_[bw_.properties[e]], {{}, ov, {}, {}, r[i], r[i], r[i], 0.0}, bw_.state[e]);
    }
  }
  return en;
}

RegionMeasurement World::measure_region(const Box& box) const {
  RegionMeasurement out;
  const std::size_t n = p_.size();
  const double volume = box.volume();
  if (!(volume > 0)) throw InputError("region", "empty box", "hi must exceed lo on every axis");
  double solid = 0.0;
  std::array<double, 9> s{};
  auto add = [&](const Vec3& arm, const Vec3& f) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s[3 * a + b] += arm[a] * f[b];
  };
  const bool built = bb_.row_offset.size() == n + 1;
  const auto& x = p_.position;
  const auto& r = p_.radius;
  for (std::size_t i = 0; i < n; ++i) {
    if (!box.contains(x[i])) continue;
    ++out.particles;
    solid += 4.0 / 3.0 * std::numbers::pi * r[i] * r[i] * r[i];
    if (!built) continue;
    // Love-Weber: sigma = (1/V) sum_p sum_c (x_c - x_p) (x) F_c.
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const Vec3 d = pair_vector(e, i, j);
      const double dist = norm(d);
      const double ov = r[i] + r[j] - dist;
      add(d * ((r[i] - 0.5 * ov) / dist), -bb_.force_on_2[e]);
    }
    for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
      const std::uint32_t e = bb_.incoming[k];
      if (bb_.properties[e] == kNoContact) continue;
      const std::size_t a = first_end(e);
      const Vec3 d = -pair_vector(e, a, i);
      const double dist = norm(d);
      const double ov = r[i] + r[a] - dist;
      add(d * ((r[i] - 0.5 * ov) / dist), bb_.force_on_2[e]);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const Wall& wl = walls_[bw_.wall[e]];
      const WallProximity prox = wall_proximity(wl, x[i]);
      const double ov = r[i] - prox.distance;
      add(ball_to_wall_normal(wl, prox) * (r[i] - 0.5 * ov), -bw_.force_on_wall[e]);
    }
  }
  for (double& v : s) v /= volume;
  out.stress_Pa = s;
  out.porosity = 1.0 - solid / volume;
  out.mean_pressure_Pa = -(s[0] + s[4] + s[8]) / 3.0;
  return out;
}

// The affine (Voigt) estimate of a packing's stiffness (Walton 1987, J. Mech. Phys. Solids 35(2);
// Agnolin & Roux 2007, Phys. Rev. E 76, 061304, "affine" moduli): under a uniform strain eps_aa
// each ball-ball contact's branch vector l (centre to centre) changes by dl = eps_aa l_a e_a, its
// springs answer with df = kn (n . dl) n + ks (dl - (n . dl) n), and with the Love-Weber sum above
// (arm c from each centre p in the box to the contact point)
//     M_a = (1/V) sum_p sum_c c_a l_a [kn n_a^2 + ks (1 - n_a^2)]   [Pa]
// (n the unit normal, kn and ks in N/m from contact_stiffness, V the box volume; for a contact
// with both ends in the box the two arms add up to l, giving l_a^2). Only touching ball-ball
// contacts (overlap > 0) count: a gap's attraction has no spring, and the walls' springs belong to
// the apparatus, not the packing (with them, the calibration box's 1 GPa walls made about 40 % of
// the sum). Rolling springs do not enter (an affine strain turns no grain). In a packing large
// against its grains, an upper bound of the relaxed small-strain modulus (near a wall the box's
// volume holds half-grains without springs, so a thin box reads lower). It depends on E* and on
// the fabric (which contacts touch, their directions), not on how the grains would rearrange, so
// it is nearly free of the noise the rearrangement brings to a relaxed loop
// (docs/results/calibrate.md, section 7).
double World::affine_modulus_Pa(const Box& box, int axis) const {
  const std::size_t n = p_.size();
  const double volume = box.volume();
  if (!(volume > 0)) throw InputError("region", "empty box", "hi must exceed lo on every axis");
  if (axis < 0 || axis > 2) throw InputError("axis", fmt::format("{}", axis), "0, 1 or 2");
  if (bb_.row_offset.size() != n + 1) return 0.0;
  const auto& x = p_.position;
  const auto& r = p_.radius;
  double sum = 0.0;
  auto add = [&](const ContactProperties& cp, const ContactGeometry& g, const Vec3& normal,
                 double arm_m, double branch_m) {
    if (g.overlap_m <= 0) return;
    const ContactStiffness k = contact_stiffness(cp, g);
    const double na = normal[axis];
    sum += (arm_m * na) * (branch_m * na) * (k.kn * na * na + k.ks * (1.0 - na * na));
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!box.contains(x[i])) continue;
    auto ball_ball = [&](std::uint32_t e, std::size_t j, const Vec3& d) {
      const double dist = norm(d);
      const double ov = r[i] + r[j] - dist;
      add(props_[bb_.properties[e]], ball_ball_geometry(r[i], r[j], ov), d / dist, r[i] - 0.5 * ov,
          dist);
    };
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e)
      if (bb_.properties[e] != kNoContact)
        ball_ball(e, bb_.other[e], pair_vector(e, i, bb_.other[e]));
    for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
      const std::uint32_t e = bb_.incoming[k];
      if (bb_.properties[e] == kNoContact) continue;
      const std::size_t a = first_end(e);
      ball_ball(e, a, -pair_vector(e, a, i));
    }
  }
  return sum / volume;
}

std::vector<ContactView> World::ball_ball_contacts() const {
  std::vector<ContactView> out;
  const std::size_t n = p_.size();
  if (bb_.row_offset.size() != n + 1) return out;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const Vec3 d = pair_vector(e, i, j);
      const double dist = norm(d);
      const double ov = p_.radius[i] + p_.radius[j] - dist;
      const Vec3 nrm = d / dist;
      out.push_back({static_cast<std::uint32_t>(i), j,
                     p_.position[i] + nrm * (p_.radius[i] - 0.5 * ov), nrm, bb_.force_on_2[e], ov,
                     bb_.properties[e]});
    }
  }
  return out;
}

std::size_t World::bytes_per_particle() const {
  const std::size_t n = p_.size();
  if (n == 0) return 0;
  auto cap = [](const auto& v) {
    return v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type);
  };
  std::size_t bytes = 0;
  for (const auto* v :
       {&p_.position, &p_.velocity, &p_.spin, &p_.force, &p_.moment, &p_.applied_force,
        &p_.applied_moment, &p_.displacement, &position_at_build_})
    bytes += cap(*v);
  bytes +=
      cap(p_.radius) + cap(p_.mass) + cap(p_.inertia) + cap(p_.id) + cap(p_.group) + cap(p_.flags);
  bytes += cap(bb_.row_offset) + cap(bb_.other) + cap(bb_.properties) + cap(bb_.state) +
           cap(bb_.force_on_2) + cap(bb_.moment_on_2) + cap(bb_.incoming_offset) +
           cap(bb_.incoming) + cap(bb_.slot_row) + cap(bb_.record_waits);
  bytes += cap(bw_.row_offset) + cap(bw_.wall) + cap(bw_.properties) + cap(bw_.state) +
           cap(bw_.force_on_wall);
  bytes += cap(timestep_scratch_.end2_share) + cap(timestep_scratch_.row_sum) +
           cap(timestep_scratch_.row_any);
  return bytes / n;
}

} // namespace centridem
