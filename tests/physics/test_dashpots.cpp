// Viscous contact dashpots (PFC 7 manual, "Linear Model": dp_nratio,
// dp_sratio, dp_mode; contact_law.hpp), against their definitions
// (dashpot_coefficient in physics_test_util.hpp):
//   normal  Fd_n = -c_n vn,  c_n = 2 beta_n sqrt(mc kn)  (vn > 0 separating)
//   shear   Fd_s = -c_s vt,  c_s = 2 beta_s sqrt(mc ks)
//   dp_mode 0: both in full; 1: the normal force kn d + Fd_n is never tensile
//   (clipped at 0); 2: no shear dashpot while the contact slides; 3: 1 and 2.
// First the kernel, exactly, in every mode; then through a World: the tension
// at the end of a heavily damped impact (mode 0) and its absence (mode 1),
// and a block sliding on a floor, whose shear dashpot brakes it to the
// terminal speed (P - mu N)/c_s in modes 0 and 1 and is off in modes 2 and 3
// (acceleration (P - mu N)/m).
#include "physics/contact_law.hpp"
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 0.01, rho = 2650, E = 1e8, g = 9.81;

ContactProperties dashpot_props(int mode, double beta_n, double beta_s, double mu) {
  ContactProperties p = props(ContactModel::linear, E, mu);
  p.dashpot_normal_ratio = beta_n;
  p.dashpot_shear_ratio = beta_s;
  p.dashpot_mode = mode;
  return p;
}

// Kernel, two equal spheres (kn = pi R^2 E/(2R), mc = m/2), normal +z, every
// mode: (a) approaching and sticking: both dashpots in full; (b) separating
// fast (c_n vn > kn d): normal force kn d - c_n vn < 0 in modes 0 and 2, and
// exactly 0 in modes 1 and 3; (c) sliding (stored shear force above
// mu kn d): tangential force mu kn d - c_s vt in modes 0 and 1, mu kn d alone
// in modes 2 and 3. Relative tolerance 1e-12.
TEST(PhysicsDashpots, KernelMatchesDefinitionInEveryMode) {
  const double beta_n = 0.4, beta_s = 0.3, mu = 0.5, dt = 1e-6;
  const double m = sphere_mass(R, rho), mc = 0.5 * m;
  const double kn = kn_ball_ball(E, R, R), ks = kn / 1.5;
  const double cn = dashpot_coefficient(beta_n, mc, kn), cs = dashpot_coefficient(beta_s, mc, ks);
  const double d = 1e-6; // overlap [m]
  const Vec3 n{0, 0, 1};
  auto geometry = [&](double vn, double vt) {
    return ContactGeometry{n, d, {vt, 0, vn}, {}, R, 2 * R, 0.5 * R, mc};
  };
  auto tangential = [&](const ContactResult& r) { return r.force - dot(r.force, n) * n; };
  for (int mode = 0; mode <= 3; ++mode) {
    const ContactProperties p = dashpot_props(mode, beta_n, beta_s, mu);
    const bool no_tension = mode == 1 || mode == 3, off_when_sliding = mode >= 2;
    SCOPED_TRACE(testing::Message() << "dp_mode " << mode);
    { // (a) approaching at 1 mm/s, tangential 1 mm/s, fresh contact: sticks
      const double vn = -1e-3, vt = 1e-3;
      ContactState st{};
      const ContactResult r = contact_law(p, geometry(vn, vt), st, dt);
      EXPECT_FALSE(r.sliding);
      EXPECT_NEAR(r.normal_force_N / (kn * d - cn * vn), 1.0, 1e-12);
      EXPECT_NEAR(tangential(r).x / (-ks * vt * dt - cs * vt), 1.0, 1e-12);
      EXPECT_NEAR(st.shear_force.x / (-ks * vt * dt), 1.0, 1e-12) << "dashpot not in the history";
    }
    { // (b) separating at vn with c_n vn = 3 kn d: the dashpot would pull
      const double vn = 3.0 * kn * d / cn;
      ContactState st{};
      const ContactResult r = contact_law(p, geometry(vn, 0.0), st, dt);
      if (no_tension) {
        EXPECT_EQ(r.normal_force_N, 0.0) << "no tension: spring + dashpot clipped at 0";
      } else {
        EXPECT_NEAR(r.normal_force_N / (kn * d - cn * vn), 1.0, 1e-12);
        EXPECT_LT(r.normal_force_N, 0.0);
      }
    }
    { // (c) sliding: stored shear force 2 mu kn d along +x, moving along -x
      const double vt = -1e-3;
      ContactState st{{2.0 * mu * kn * d, 0, 0}, {}};
      const ContactResult r = contact_law(p, geometry(0.0, vt), st, dt);
      EXPECT_TRUE(r.sliding);
      const double coulomb = mu * kn * d;
      EXPECT_NEAR(st.shear_force.x / coulomb, 1.0, 1e-12);
      const double expected = off_when_sliding ? coulomb : coulomb - cs * vt;
      EXPECT_NEAR(tangential(r).x / expected, 1.0, 1e-12);
    }
    { // (d) sticking with mode 2/3 too: the shear dashpot acts
      const double vt = 1e-3;
      ContactState st{{0.1 * mu * kn * d, 0, 0}, {}};
      const ContactResult r = contact_law(p, geometry(0.0, vt), st, dt);
      EXPECT_FALSE(r.sliding);
      EXPECT_NEAR(tangential(r).x / (0.1 * mu * kn * d - ks * vt * dt - cs * vt), 1.0, 1e-12);
    }
  }
}

// Two equal spheres meet head on at 0.1 m/s, beta_n = 0.7, no gravity, no
// friction. Mode 0: at the end of the contact (overlap back to 0) the force
// is -c_n v_rebound, a tension: the smallest normal force seen is at most
// -0.9 c_n v_rebound. Mode 1: never below 0 (exactly). The mode-1 pair
// separates too (the clipped dashpot does not hold it).
TEST(PhysicsDashpots, NoTensionModeClipsTheNormalForce) {
  const double beta = 0.7, v0 = 0.1;
  const double m = sphere_mass(R, rho), mc = 0.5 * m, kn = kn_ball_ball(E, R, R);
  const double T = pi * std::sqrt(mc / kn);
  const double cn = dashpot_coefficient(beta, mc, kn);
  for (const int mode : {0, 1}) {
    WorldSettings s;
    s.threads = 1;
    s.timestep_s = T / 2000.0;
    World w(s);
    w.set_ball_ball_defaults(dashpot_props(mode, beta, 0.0, 0.0));
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    w.add_particle({2 * R + 0.05 * v0 * T, 0, 0}, R, rho, 0, 2);
    w.particles_mut().velocity[0] = {0.5 * v0, 0, 0};
    w.particles_mut().velocity[1] = {-0.5 * v0, 0, 0};
    double min_fn = 0, max_fn = 0;
    bool touched = false, parted = false;
    for (int k = 0; k < 20000 && !parted; ++k) {
      w.cycle(1);
      const auto c = w.ball_ball_contacts();
      if (!c.empty()) {
        touched = true;
        const double fn = dot(c[0].force_on_j, c[0].normal);
        min_fn = std::min(min_fn, fn), max_fn = std::max(max_fn, fn);
      } else if (touched) {
        parted = true;
      }
    }
    ASSERT_TRUE(parted) << "mode " << mode;
    w.cycle(10);
    const double v_reb = w.particles().velocity[idx(w, 2)].x - w.particles().velocity[idx(w, 1)].x;
    EXPECT_GT(v_reb, 0.0) << "mode " << mode << ": separating";
    EXPECT_GT(max_fn, 0.0);
    if (mode == 0) {
      EXPECT_LE(min_fn, -0.9 * cn * v_reb) << "full dashpot: tension -c_n v at exit";
    } else {
      EXPECT_GE(min_fn, 0.0) << "no-tension mode: never tensile";
    }
  }
}

// A block (ball with rotation fixed) on a floor under gravity, undamped,
// pulled by P = 1.5 mu m g, shear dashpot beta_s = 0.3 (wall: mc = m).
// Modes 0 and 1: P = mu m g + c_s v at steady sliding, so v -> (P - mu m g)/c_s
// (within 1 %, after 300 relaxation times m/c_s). Modes 2 and 3: no shear
// dashpot while sliding: a = (P - mu m g)/m (within 1 %).
TEST(PhysicsDashpots, ShearDashpotWhileSlidingByMode) {
  const double mu = 0.4, beta_s = 0.3;
  const double m = sphere_mass(R, rho), N = m * g;
  const double kn = kn_ball_wall(E, R), ks = kn / 1.5;
  const double cs = dashpot_coefficient(beta_s, m, ks);
  const double P = 1.5 * mu * N;
  const double dt = 0.2 * 2.0 / std::sqrt(kn / m * 5.0);
  for (int mode = 0; mode <= 3; ++mode) {
    WorldSettings s;
    s.threads = 1;
    s.timestep_s = dt;
    World w(s);
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), dashpot_props(mode, 0.0, beta_s, mu));
    w.add_particle({0, 0, R - N / kn}, R, rho, 0, 1);
    w.set_body_field(gravity({0, 0, -g}));
    w.particles_mut().flags[0] = fix_rotation;
    w.particles_mut().applied_force[0] = {P, 0, 0};
    const long relax = static_cast<long>(300 * m / cs / dt);
    w.cycle(relax);
    const double v1 = w.particles().velocity[0].x, t1 = w.time();
    w.cycle(2000);
    const double v2 = w.particles().velocity[0].x, t2 = w.time();
    if (mode < 2) {
      EXPECT_NEAR(v2 / ((P - mu * N) / cs), 1.0, 0.01) << "mode " << mode << ": terminal speed";
    } else {
      EXPECT_NEAR((v2 - v1) / (t2 - t1) / ((P - mu * N) / m), 1.0, 0.01)
          << "mode " << mode << ": free sliding acceleration";
    }
  }
}

} // namespace
} // namespace centridem
