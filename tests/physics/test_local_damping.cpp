// Acceptance 5: Cundall local damping (PFC `damp`; DESIGN.md "Physics"):
// F_d = -alpha |F| sign(v) per component, F the full unbalanced force
// (gravity included). A ball in free fall has F = m g parallel to v, so from
// the second step on (v = 0 at the start gives sign 0) it accelerates at
// exactly (1 - alpha) g; a velocity component with no force on it is
// untouched. Source: PFC 7 manual, "Local Damping".
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

namespace centridem {
namespace {
using namespace phys_test;

// Free fall with alpha = 0, 0.3, 0.7: a = (1 - alpha) g within 1e-6
// relative; the horizontal velocity (no force) stays exactly as set.
TEST(PhysicsLocalDamping, FreeFallAcceleratesAtOneMinusAlphaG) {
  const double g = 9.81;
  for (double alpha : {0.0, 0.3, 0.7}) {
    WorldSettings s;
    s.threads = 1;
    s.local_damping = alpha;
    s.timestep_s = 1e-5;
    World w(s);
    w.add_particle({0, 0, 0}, 0.01, 2650, 0, 1);
    w.particles_mut().velocity[0] = {0.2, 0, 0};
    w.set_body_field(gravity({0, 0, -g}));
    w.cycle(10);
    const double v1 = w.particles().velocity[0].z, t1 = w.time();
    w.cycle(1000);
    const double v2 = w.particles().velocity[0].z, t2 = w.time();
    const double a = (v2 - v1) / (t2 - t1);
    EXPECT_NEAR(a / (-(1.0 - alpha) * g), 1.0, 1e-6) << "alpha " << alpha << " a " << a;
    EXPECT_EQ(w.particles().velocity[0].x, 0.2);
  }
}

} // namespace
} // namespace centridem
