// Servo-controlled wall: a lid pressed onto a granular layer holds the target
// force. PFC-style servo: v = alpha (F_target - F) / (sum kn dt).
#include "engine/world.hpp"
#include "procedures/paper_material.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <random>

using namespace centridem;

namespace {
// The paper's dry sand in a 4 mm x 4 mm box (floor at z = 0, four sides) and
// a servo lid at height lid_z_m, its target 100 kPa on the lid = 1.6 N;
// returns the lid's index; `servo` gets the target and direction.
std::size_t box_with_servo_lid(World& w, WallServo& servo, double lid_z_m) {
  w.set_ball_ball_defaults(paper::ball_ball(0.0));
  const double L = 0.004;
  for (auto [name, p, nrm] : {std::tuple{"floor", Vec3{0, 0, 0}, Vec3{0, 0, 1}},
                              std::tuple{"x0", Vec3{0, 0, 0}, Vec3{1, 0, 0}},
                              std::tuple{"x1", Vec3{L, 0, 0}, Vec3{-1, 0, 0}},
                              std::tuple{"y0", Vec3{0, 0, 0}, Vec3{0, 1, 0}},
                              std::tuple{"y1", Vec3{0, L, 0}, Vec3{0, -1, 0}}})
    w.add_wall(Wall::plane(name, p, nrm), paper::ball_wall());
  const std::size_t lid =
      w.add_wall(Wall::plane("lid", {0, 0, lid_z_m}, {0, 0, -1}), paper::ball_wall());
  servo.active = true;
  servo.direction = {0, 0, -1};
  servo.target_force_N = 100e3 * L * L;
  servo.max_speed_m_per_s = 0.5;
  w.set_wall_servo(lid, servo);
  return lid;
}

// A 648-sphere random layer under the lid. No gravity, so the floor carries
// the lid's force once the layer is in equilibrium.
std::size_t lid_on_layer(World& w, WallServo& servo) {
  const std::size_t lid = box_with_servo_lid(w, servo, 0.0036);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> rr(1.5e-4, 2.0e-4);
  const double a = 4.4e-4;
  for (int iz = 0; iz < 8; ++iz)
    for (int iy = 0; iy < 9; ++iy)
      for (int ix = 0; ix < 9; ++ix)
        w.add_particle({(ix + 0.55) * a, (iy + 0.55) * a, (iz + 0.55) * a}, rr(rng), 2633);
  return lid;
}
} // namespace

TEST(Servo, LidHoldsTargetStress) {
  WorldSettings s;
  s.local_damping = 0.7;
  World w(s);
  WallServo servo;
  const std::size_t lid = lid_on_layer(w, servo);
  const double target = servo.target_force_N;
  w.cycle(20000);
  double worst = 0;
  for (int k = 0; k < 20; ++k) {
    w.cycle(100);
    const double measured = -dot(w.walls()[lid].force, servo.direction);
    worst = std::max(worst, std::abs(measured - target) / target);
  }
  EXPECT_LT(worst, 0.01) << "servo force error over the last 2000 steps";
  const double floor = w.walls()[w.wall_index("floor")].force.z;
  EXPECT_NEAR(-floor, target, 0.02 * target);  // the floor carries the lid's load
  EXPECT_GE(w.walls()[lid].contact_count, 3u); // the lid rests on the layer
}

// The floor sinks at a steady speed v, so the lid must follow at v. A purely
// proportional servo (PFC's form) can only move while it sees an error: it
// lags by F_lag = v (sum kn) dt / alpha, the error that commands the speed v.
// The integral term (Ti > 0) removes that steady error.
//
// The specimen is nine equal spheres in a 3 x 3 monolayer, apart from each
// other and from the side walls, each pressed between the floor and the lid:
// the lid's contact stiffness does not change while it follows, so the
// proportional lag is exactly F_lag and the integral term brings the error
// to round-off. (Until 2026-12-05 the test used the 648-sphere random layer
// above, whose mean errors moved with the last bits of the run: -0.35 to 1.26
// of the lag for P with neighbour skins of 10-76 um, issue 18. This layer
// gives 1.000 and 1e-13 N with the default skin and with 20 um.)
namespace {
std::size_t lid_on_monolayer(World& w, WallServo& servo) {
  const double r = 1.75e-4, a = 4.4e-4; // spacing a > 2 r: the spheres never touch
  const std::size_t lid = box_with_servo_lid(w, servo, 2 * r + 5e-5);
  for (int iy = 0; iy < 3; ++iy)
    for (int ix = 0; ix < 3; ++ix) w.add_particle({(ix + 3.55) * a, (iy + 3.55) * a, r}, r, 2633);
  return lid;
}
} // namespace

TEST(Servo, IntegralTermRemovesTheLagBehindAMovingSpecimen) {
  const double v = 0.05; // [m/s], floor sinking
  auto mean_error_over_lag = [&](double integral_time_s) {
    WorldSettings s;
    s.local_damping = 0.7;
    World w(s);
    WallServo servo;
    servo.integral_time_s = integral_time_s;
    const std::size_t lid = lid_on_monolayer(w, servo);
    w.cycle(20000); // at rest under the target
    w.set_wall_velocity(w.wall_index("floor"), {0, 0, -v});
    w.cycle(20000); // into the steady motion
    double error = 0, lag = 0;
    const int n = 200;
    for (int k = 0; k < n; ++k) {
      w.cycle(50);
      const Wall& l = w.walls()[lid];
      EXPECT_EQ(l.contact_count, 9u) << "every sphere under the lid";
      error += servo.target_force_N - (-dot(l.force, servo.direction));
      lag += v * l.normal_stiffness_N_per_m * w.timestep() / servo.gain_factor;
    }
    return std::pair{error / n, lag / n};
  };
  const auto [p_error, p_lag] = mean_error_over_lag(0.0);
  const auto [pi_error, pi_lag] = mean_error_over_lag(1e-4); // Ti ~ 400 steps here
  ASSERT_GT(p_lag, 0.0);
  // Proportional: a steady error of the order of the predicted lag (the
  // bounds kept from the random layer, which gave 0.63 of it) ...
  EXPECT_GT(p_error, 0.4 * p_lag) << "P error " << p_error << " N, lag " << p_lag << " N";
  EXPECT_LT(p_error, 1.2 * p_lag) << "P error " << p_error << " N, lag " << p_lag << " N";
  // ... and here, with a constant lid stiffness, the lag itself (measured
  // 1.000; 1 % allows for the overlaps' small change as the lid follows).
  EXPECT_NEAR(p_error, p_lag, 0.01 * p_lag) << "P error " << p_error << " N, lag " << p_lag;
  // With the integral term the steady error is gone (below 10 % of P's).
  EXPECT_LT(std::abs(pi_error), 0.1 * p_error) << "PI error " << pi_error << " N";
}
