// Acceptance 6 and 12: conservation laws of the cycle.
//
// 6. An isolated packing (no gravity, no walls, no damping, frictionless
//    linear contacts: no slip, so no dissipation) conserves
//    * linear momentum exactly up to round-off: every contact force is added
//      to one end and subtracted from the other (Newton 3), so
//      sum m v changes only by rounding;
//    * angular momentum sum (m x cross v + I w): central forces at a shared
//      contact point give no net torque; with the central-difference
//      update x(t+dt) = x(t) + v dt, m x cross v is exactly conserved
//      between force updates (exact in exact arithmetic);
//    * total energy (kinetic + rotational + strain) within 1 %: the
//      leapfrog scheme is symplectic, energy errors are O((w dt)^2) and
//      bounded; dt = 0.1 x the critical estimate.
//    Source: Newton's laws; Hairer, Lubich & Wanner, Geometric Numerical
//    Integration (leapfrog energy behaviour); PFC 7 manual "Energy".
// 12. The sum of all contact forces on balls and walls is zero (each contact
//    force acts on both ends with opposite signs), and without walls the sum
//    of all contact moments about a point, sum (x_i cross F_i + M_i), is zero
//    too (shear and rolling moments included): both ends share the contact
//    point x_i + n (R_i - d/2) = x_j - n (R_j - d/2).
#include "physics_test_util.hpp"
#include "procedures/paper_material.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double Rm = 1e-3, rho = 2650;

struct Totals {
  Vec3 p, L;
  double p_scale = 0, L_scale = 0;
};

Totals totals(const World& w) {
  const auto& P = w.particles();
  Totals t;
  for (std::size_t i = 0; i < P.size(); ++i) {
    t.p += P.mass[i] * P.velocity[i];
    t.p_scale += P.mass[i] * norm(P.velocity[i]);
    const Vec3 l = P.mass[i] * cross(P.position[i], P.velocity[i]) + P.inertia[i] * P.spin[i];
    t.L += l;
    t.L_scale +=
        P.mass[i] * norm(P.position[i]) * norm(P.velocity[i]) + P.inertia[i] * norm(P.spin[i]);
  }
  return t;
}

// 2,000 spheres, radii 0.8-1.2 mm, 1 m/s random velocities in a gas of
// solid fraction ~0.27 that expands into empty space while colliding;
// 10,000 steps. Linear momentum: |p - p0| <= 1e-12 sum m|v|. Angular
// momentum: |L - L0| <= 1e-10 sum m |x||v|. Energy: |E - E0| <= 1 % E0.
TEST(PhysicsConservation, IsolatedPackingConservesMomentumAndEnergy) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  w.set_ball_ball_defaults(props(ContactModel::linear, 1e8, 0.0));
  add_lattice(w, 2000, 13, 13, 2.5 * Rm, 0.8 * Rm, 1.2 * Rm, rho, {0, 0, 0}, 1.0, true);
  w.set_fixed_timestep(0.1 * w.critical_timestep());
  const Totals t0 = totals(w);
  const double E0 = w.energy().total();
  double max_dE = 0, max_dp = 0, max_dL = 0, max_strain = 0;
  std::size_t max_contacts = 0;
  for (int chunk = 0; chunk < 100; ++chunk) {
    w.cycle(100);
    const Totals t = totals(w);
    const Energy e = w.energy();
    max_dE = std::max(max_dE, std::abs(e.total() - E0) / E0);
    max_dp = std::max(max_dp, norm(t.p - t0.p) / t0.p_scale);
    max_dL = std::max(max_dL, norm(t.L - t0.L) / t0.L_scale);
    max_strain = std::max(max_strain, e.strain_normal_J);
    max_contacts = std::max(max_contacts, w.measure().ball_ball_contacts);
  }
  EXPECT_EQ(w.step_count(), 10000);
  EXPECT_LT(max_dp, 1e-12);
  EXPECT_LT(max_dL, 1e-10);
  EXPECT_LT(max_dE, 0.01);
  // Not vacuous: collisions happened and stored energy.
  EXPECT_GT(max_contacts, 20u);
  EXPECT_GT(max_strain, 1e-4 * E0);
}

// Sum of contact forces on balls (unbalanced force minus gravity and applied
// force) plus the forces on the walls: zero within 1e-12 of the sum of their
// magnitudes, at 20 instants of a collapsing, adhesive, frictional packing in
// a box whose lid moves down.
TEST(PhysicsConservation, ContactForcesSumToZeroWithWalls) {
  WorldSettings s;
  s.threads = 1;
  s.local_damping = 0.0;
  World w(s);
  w.set_ball_ball_defaults(paper::ball_ball(1e-3));
  const double L = 10 * 2.5 * Rm;
  const ContactProperties wall = props(ContactModel::rrlinear, 1e8, 0.3, 0.1);
  w.add_wall(Wall::plane("floor", {0, 0, -Rm * 1.5}, {0, 0, 1}), wall);
  w.add_wall(Wall::plane("x0", {-1.5 * Rm, 0, 0}, {1, 0, 0}), wall);
  w.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), wall);
  w.add_wall(Wall::plane("y0", {0, -1.5 * Rm, 0}, {0, 1, 0}), wall);
  w.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), wall);
  w.add_wall(Wall::rectangle("lid", {L / 2, L / 2, 8 * 2.5 * Rm}, {0, 0, -1}, {1, 0, 0}, L, L),
             wall);
  w.set_wall_velocity(w.wall_index("lid"), {0, 0, -0.5});
  add_lattice(w, 500, 10, 10, 2.5 * Rm, 0.8 * Rm, 1.2 * Rm, rho, {0, 0, 0}, 0.5, false);
  const Vec3 g{0, 0, -9.81 * 100};
  w.set_body_field(gravity(g));
  w.particles_mut().applied_force[3] = {1e-4, 2e-4, 0};
  int checked = 0;
  for (int chunk = 0; chunk < 20; ++chunk) {
    w.cycle(200);
    const auto& P = w.particles();
    Vec3 sum{};
    double scale = 0;
    for (std::size_t i = 0; i < P.size(); ++i) {
      const Vec3 fc = P.force[i] - P.mass[i] * g - P.applied_force[i];
      sum += fc;
      scale += norm(fc);
    }
    for (const Wall& wl : w.walls()) {
      sum += wl.force;
      scale += norm(wl.force);
    }
    if (scale == 0) continue;
    ++checked;
    EXPECT_LT(norm(sum), 1e-12 * scale) << "chunk " << chunk;
  }
  EXPECT_GT(checked, 10);
  EXPECT_GT(w.measure().ball_wall_contacts, 10u);
  EXPECT_GT(w.measure().ball_ball_contacts, 100u);
}

// No walls, no gravity: sum of contact forces and sum of contact moments
// about the centroid, sum (x_i - c) cross F_i + M_i (x_i: the positions the
// forces were computed at), both zero within 1e-12
// of the sum of magnitudes, with friction, rolling resistance and adhesion
// (paper material) and random spins.
TEST(PhysicsConservation, ContactMomentsSumToZero) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  ContactProperties bb = paper::ball_ball(1e-2);
  bb.attraction_range_m = 0.05 * Rm; // a bound, vibrating cluster
  w.set_ball_ball_defaults(bb);
  add_lattice(w, 500, 8, 8, 2.0 * Rm, 0.97 * Rm, 1.0 * Rm, rho, {0, 0, 0}, 0.05, true);
  {
    auto& P = w.particles_mut();
    for (std::size_t i = 0; i < P.size(); ++i) {
      const double k = static_cast<double>(i);
      P.spin[i] = {500.0 * std::sin(k), 500.0 * std::cos(2.0 * k), 300.0 * std::sin(3.0 * k)};
    }
  }
  int checked = 0;
  for (int chunk = 0; chunk < 20; ++chunk) {
    w.cycle(100);
    const auto& P = w.particles();
    // The forces of the last step were computed at the positions before its
    // position update x += v dt: undo it.
    std::vector<Vec3> x(P.size());
    Vec3 c{};
    for (std::size_t i = 0; i < P.size(); ++i) {
      x[i] = P.position[i] - P.velocity[i] * w.timestep();
      c += x[i];
    }
    c = c / static_cast<double>(P.size());
    Vec3 F{}, M{};
    double fscale = 0, mscale = 0;
    for (std::size_t i = 0; i < P.size(); ++i) {
      F += P.force[i];
      fscale += norm(P.force[i]);
      M += cross(x[i] - c, P.force[i]) + P.moment[i];
      mscale += norm(cross(x[i] - c, P.force[i])) + norm(P.moment[i]);
    }
    if (fscale == 0) continue;
    ++checked;
    EXPECT_LT(norm(F), 1e-12 * fscale) << "chunk " << chunk;
    EXPECT_LT(norm(M), 1e-12 * mscale) << "chunk " << chunk;
  }
  EXPECT_GT(checked, 10);
  EXPECT_GT(w.measure().ball_ball_contacts, 100u);
}

} // namespace
} // namespace centridem
