// The timestep (docs/ARCHITECTURE.md "One step", World::critical_timestep):
// central differences are stable for dt < 2/omega_max, omega_max^2 bounded
// over the current contacts by the Gershgorin column sums of M^-1 K (closed
// forms in critical_timestep_s below); viscous dashpots lower the limit by
// sqrt(1 + beta^2) - beta (Belytschko & Hughes 1983, ch. 2). The automatic
// timestep is the safety factor x that estimate and grows at most
// timestep_growth_limit per step; a fixed timestep above the estimate is
// refused, at the start (InputError) and when the contacts stiffen during a
// run (InstabilityError, so the command line exits with 3).
#include "base/errors.hpp"
#include "physics_test_util.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 0.01, rho = 2650, E = 1e8;

// Critical timestep of the two closed-form systems [s] (source: the
// undamped oscillator x'' = -w^2 x under central differences is stable for
// w dt < 2; e.g. Belytschko & Hughes 1983, ch. 2):
//  * a single spring-mass, stiffness k [N/m] and mass m [kg]: 2 sqrt(m/k);
//  * a ball (m, I = 2/5 m R^2) on a wall, linear model: the normal mode
//    w^2 = kn/m and the shear mode, the spring ks at the contact point
//    coupling translation and rotation, whose only non-zero eigenvalue of
//    M^-1 K is ks (1/m + R^2/I) = 3.5 ks/m: 2/sqrt(max(kn, 3.5 ks)/m).
double spring_mass_critical_s(double m, double k) {
  return 2.0 * std::sqrt(m / k);
}
double ball_on_wall_critical_s(double m, double kn, double ks) {
  return 2.0 / std::sqrt(std::max(kn, 3.5 * ks) / m);
}
// Dashpot factor (same source): stability limit x (sqrt(1 + beta^2) - beta).
double dashpot_factor(double beta) {
  return std::sqrt(1.0 + beta * beta) - beta;
}

ContactProperties direct(double kn, double ks) {
  ContactProperties p;
  p.model = ContactModel::linear;
  p.stiffness_method = StiffnessMethod::direct;
  p.normal_stiffness_N_per_m = kn;
  p.shear_stiffness_N_per_m = ks;
  return p;
}

// Estimated every step (interval 1) unless stated.
WorldSettings auto_settings(double safety = 0.8, double growth = 0.05, int interval = 1) {
  WorldSettings s;
  s.threads = 1;
  s.timestep_safety_factor = safety;
  s.timestep_growth_limit = growth;
  s.timestep_update_interval = interval;
  return s;
}

// A single spring-mass: two balls, masses m1 and m2 (reduced mass mc), in
// contact through kn with ks = 0 (only the normal spring), and one ball on a
// wall through kn with ks = 0: 2 sqrt(mc/kn) and 2 sqrt(m/kn) within 1e-12.
// The automatic timestep is then 0.8 (the default safety factor) of it.
TEST(PhysicsTimestep, SpringMassEstimateIsTwoOverOmega) {
  const double kn = 1e6;
  {
    World w(auto_settings());
    w.set_ball_ball_defaults(direct(kn, 0.0));
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    w.add_particle({1.5 * R - 1e-7, 0, 0}, 0.5 * R, rho, 0, 2); // unequal masses
    w.particles_mut().flags[0] = w.particles_mut().flags[1] = fix_translation | fix_rotation;
    w.cycle(100); // the contact is born in the first step; dt settles on the new estimate
    ASSERT_EQ(w.ball_ball_contacts().size(), 1u);
    const double m1 = sphere_mass(R, rho), m2 = sphere_mass(0.5 * R, rho);
    const double expected = spring_mass_critical_s(m1 * m2 / (m1 + m2), kn);
    EXPECT_NEAR(w.critical_timestep() / expected, 1.0, 1e-12);
    EXPECT_NEAR(w.timestep() / (0.8 * expected), 1.0, 1e-12);
  }
  {
    World w(auto_settings());
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), direct(kn, 0.0));
    w.add_particle({0, 0, R - 1e-7}, R, rho, 0, 1);
    w.particles_mut().flags[0] = fix_translation | fix_rotation;
    w.cycle(100);
    ASSERT_EQ(w.walls()[0].contact_count, 1u);
    const double expected = spring_mass_critical_s(sphere_mass(R, rho), kn);
    EXPECT_NEAR(w.critical_timestep() / expected, 1.0, 1e-12);
  }
}

// A small ball held between two big ones, normal springs kn only: its
// Gershgorin row sums both contacts, kn (1/ms + 1/mb) each, so the estimate
// is 2 sqrt(mc / (2 kn)) with mc = ms mb / (ms + mb), within 1e-12. The
// particles sort as big, small, big, so the small ball is the second end of
// one contact and the first end of the other: the estimate takes each
// contact's share for both of its ends (its stiffness evaluated once, in the
// row of its first end; engine/timestep.cpp). Without the second end's share
// the small ball would see one contact, and the estimate would be sqrt(2)
// too long.
TEST(PhysicsTimestep, ParticleBetweenTwoSumsBothContactsWhicheverEndItIs) {
  const double kn = 1e6, Rs = 0.5 * R;
  World w(auto_settings());
  w.set_ball_ball_defaults(direct(kn, 0.0));
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({2 * (R + Rs) - 2e-7, 0, 0}, R, rho, 0, 2);
  w.add_particle({R + Rs - 1e-7, 0, 0}, Rs, rho, 0, 3); // between them, added last
  for (std::uint8_t& f : w.particles_mut().flags) f = fix_translation | fix_rotation;
  w.cycle(100);
  ASSERT_EQ(w.ball_ball_contacts().size(), 2u);
  const double ms = sphere_mass(Rs, rho), mb = sphere_mass(R, rho);
  const double expected = spring_mass_critical_s(0.5 * ms * mb / (ms + mb), kn);
  EXPECT_NEAR(w.critical_timestep() / expected, 1.0, 1e-12);
}

// A ball on a wall, linear model, deformability method (kn = pi R E*,
// ks = kn/kappa*): kappa* = 1.5 (shear mode governs, 3.5 ks > kn) and
// kappa* = 5 (normal mode governs): the estimate equals the closed form
// within 1e-12.
TEST(PhysicsTimestep, BallOnWallEstimate) {
  for (const double kratio : {1.5, 5.0}) {
    World w(auto_settings());
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}),
               props(ContactModel::linear, E, 0.5, 0.0, kratio));
    w.add_particle({0, 0, R - 1e-7}, R, rho, 0, 1);
    w.particles_mut().flags[0] = fix_translation | fix_rotation;
    w.cycle(1);
    ASSERT_EQ(w.walls()[0].contact_count, 1u);
    const double kn = kn_ball_wall(E, R);
    const double expected = ball_on_wall_critical_s(sphere_mass(R, rho), kn, kn / kratio);
    EXPECT_NEAR(w.critical_timestep() / expected, 1.0, 1e-12) << "kratio " << kratio;
  }
}

// Safety factor and dashpot factor: the automatic timestep of the ball on a
// wall is safety x dashpot_factor(beta) x the closed form (within 1e-12),
// for safety 0.8 and 0.3, beta 0 and 0.5 (normal) and 0.3 (shear).
TEST(PhysicsTimestep, SafetyAndDashpotFactors) {
  const double kn = kn_ball_wall(E, R), m = sphere_mass(R, rho);
  const double undamped = ball_on_wall_critical_s(m, kn, kn / 1.5);
  struct Case {
    double safety, beta_n, beta_s;
  };
  for (const Case c : {Case{0.8, 0.0, 0.0}, Case{0.3, 0.0, 0.0}, Case{0.8, 0.5, 0.0},
                       Case{0.3, 0.0, 0.3}, Case{0.5, 0.2, 0.4}}) {
    World w(auto_settings(c.safety));
    ContactProperties p = props(ContactModel::linear, E, 0.5);
    p.dashpot_normal_ratio = c.beta_n;
    p.dashpot_shear_ratio = c.beta_s;
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), p);
    w.add_particle({0, 0, R - 1e-7}, R, rho, 0, 1);
    w.particles_mut().flags[0] = fix_translation | fix_rotation;
    w.cycle(100);
    const double crit = undamped * dashpot_factor(std::max(c.beta_n, c.beta_s));
    EXPECT_NEAR(w.critical_timestep() / crit, 1.0, 1e-12)
        << "safety " << c.safety << " beta " << c.beta_n << " " << c.beta_s;
    EXPECT_NEAR(w.timestep() / (c.safety * crit), 1.0, 1e-12)
        << "safety " << c.safety << " beta " << c.beta_n << " " << c.beta_s;
  }
}

// Growth limit: two balls held in contact through a stiff spring; their
// contact (and the defaults) then become 100 x softer, so the estimate grows
// 10 x. Estimated every step (interval 1), the automatic timestep grows by
// exactly (1 + limit) per step until it reaches the new target, then stays
// there: limits 0.05 and 0.2 (ratios within 1e-12).
TEST(PhysicsTimestep, GrowthLimitPerStep) {
  const double kn = 1e6;
  for (const double limit : {0.05, 0.2}) {
    World w(auto_settings(0.8, limit, 1));
    w.set_ball_ball_defaults(direct(kn, 0.0));
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    w.add_particle({2 * R - 1e-7, 0, 0}, R, rho, 0, 2);
    w.particles_mut().flags[0] = w.particles_mut().flags[1] = fix_translation | fix_rotation;
    w.cycle(100);
    const double dt0 = w.timestep();
    const double target = 10.0 * dt0;
    w.set_ball_ball_defaults(direct(kn / 100.0, 0.0));
    EXPECT_EQ(w.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                                          [&](ContactProperties& p) { p = direct(kn / 100, 0.0); }),
              1u);
    double dt = dt0;
    int grown = 0;
    for (int k = 0; k < 200; ++k) {
      w.cycle(1);
      const double expected = std::min(target, dt * (1.0 + limit));
      ASSERT_NEAR(w.timestep() / expected, 1.0, 1e-12) << "limit " << limit << " step " << k;
      grown += expected < target;
      dt = w.timestep();
    }
    EXPECT_NEAR(w.timestep() / target, 1.0, 1e-12);
    // Not vacuous: the growth was limited for ln 10 / ln(1 + limit) steps.
    EXPECT_EQ(grown, static_cast<int>(std::floor(std::log(10.0) / std::log1p(limit))));
  }
}

// A fixed timestep above the estimate is refused at the start of a cycle
// (InputError naming simulation.timestep_s), and, when it was fine at the
// start, also when the contacts stiffen during the run: a ball between two
// others that approach at a prescribed speed; its Gershgorin sum doubles
// with the second contact, so dt = 0.9 x the free-particle estimate ends
// above the estimate. The refusal comes within one update interval (100
// steps) of the second contact, as an InstabilityError (exit code 3) whose
// message names the timestep, the critical estimate and the step.
TEST(PhysicsTimestep, FixedTimestepRefusedWhenContactsStiffen) {
  const double kn = 1e6;
  { // at the start
    WorldSettings s = auto_settings();
    World w(s);
    w.set_ball_ball_defaults(direct(kn, 0.0));
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    const double crit = w.critical_timestep();
    w.set_fixed_timestep(1.01 * crit);
    try {
      w.cycle(1);
      ADD_FAILURE() << "a fixed timestep above critical was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("simulation.timestep_s"), std::string::npos);
    }
    EXPECT_EQ(w.step_count(), 0);
  }
  World w(auto_settings(0.8, 0.05, 100)); // the default update interval
  w.set_ball_ball_defaults(direct(kn, 0.0));
  const double gap = 1e-4, v = 0.05;
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({-2 * R - gap, 0, 0}, R, rho, 0, 2);
  w.add_particle({2 * R + 2 * gap, 0, 0}, R, rho, 0, 3); // touches later than 2
  const double free_crit = w.critical_timestep();
  const double dt = 0.9 * free_crit;
  w.set_fixed_timestep(dt);
  for (const std::int64_t id : {2, 3}) {
    const std::size_t i = idx(w, id);
    w.particles_mut().flags[i] = fix_translation | fix_rotation;
    w.particles_mut().velocity[i] = {id == 2 ? v : -v, 0, 0};
  }
  const long second_contact = static_cast<long>(std::ceil(2 * gap / v / dt));
  try {
    w.cycle(5 * second_contact + 1000);
    ADD_FAILURE() << "stiffened contacts: the fixed timestep was not refused";
  } catch (const InstabilityError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fixed timestep"), std::string::npos) << what;
    EXPECT_NE(what.find("critical timestep"), std::string::npos) << what;
    EXPECT_NE(what.find(fmt::format("step {}", w.step_count())), std::string::npos) << what;
  }
  EXPECT_GT(w.step_count(), static_cast<long>(gap / v / dt)) << "refused after the first contact";
  EXPECT_LE(w.step_count(), second_contact + 100);
  EXPECT_EQ(w.ball_ball_contacts().size(), 2u);
  EXPECT_GT(w.timestep(), w.critical_timestep());
}

} // namespace
} // namespace centridem
