// Servo-controlled wall: a lid pressed onto a granular layer holds the target
// force. PFC-style servo: v = alpha (F_target - F) / (sum kn dt).
#include "core/world.hpp"
#include "procedures/paper_material.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <random>

using namespace centridem;

TEST(Servo, LidHoldsTargetStress) {
  WorldSettings s;
  s.local_damping = 0.7;
  World w(s);
  w.set_ball_ball_defaults(paper::ball_ball(0.0));
  const double L = 0.004;
  for (auto [name, p, nrm] : {std::tuple{"floor", Vec3{0, 0, 0}, Vec3{0, 0, 1}},
                              std::tuple{"x0", Vec3{0, 0, 0}, Vec3{1, 0, 0}},
                              std::tuple{"x1", Vec3{L, 0, 0}, Vec3{-1, 0, 0}},
                              std::tuple{"y0", Vec3{0, 0, 0}, Vec3{0, 1, 0}},
                              std::tuple{"y1", Vec3{0, L, 0}, Vec3{0, -1, 0}}})
    w.add_wall(Wall::plane(name, p, nrm), paper::ball_wall());
  const std::size_t lid =
      w.add_wall(Wall::plane("lid", {0, 0, 0.0036}, {0, 0, -1}), paper::ball_wall());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> rr(1.5e-4, 2.0e-4);
  const double a = 4.4e-4;
  for (int iz = 0; iz < 8; ++iz)
    for (int iy = 0; iy < 9; ++iy)
      for (int ix = 0; ix < 9; ++ix)
        w.add_particle({(ix + 0.55) * a, (iy + 0.55) * a, (iz + 0.55) * a}, rr(rng), 2633);
  // Target: 100 kPa on the 4 mm x 4 mm lid = 1.6 N; no gravity, so the floor
  // carries the same force once the layer is in equilibrium.
  const double target = 100e3 * L * L;
  WallServo servo;
  servo.active = true;
  servo.direction = {0, 0, -1};
  servo.target_force_N = target;
  servo.max_speed_m_per_s = 0.5;
  w.set_wall_servo(lid, servo);
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
