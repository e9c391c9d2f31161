// Periodic boundaries and contact records.
#include "engine/world.hpp"

#include <gtest/gtest.h>
#include <random>

using namespace centridem;

namespace {
ContactProperties stiff_frictional() {
  ContactProperties p;
  p.model = ContactModel::rrlinear;
  p.effective_modulus_Pa = 1e8;
  p.friction = 0.5;
  p.rolling_friction = 0.1;
  return p;
}
} // namespace

// Two spheres that touch only through the periodic boundary along x push each
// other apart with equal and opposite forces (Newton's third law through the
// image), and the overlap is R1 + R2 - (L - |dx|).
TEST(Periodic, PairAcrossBoundaryInteracts) {
  World w;
  w.set_ball_ball_defaults(stiff_frictional());
  PeriodicBox pb;
  pb.axis = {true, false, false};
  pb.lo = {0, 0, 0};
  pb.hi = {0.01, 0.01, 0.01};
  w.set_periodic(pb);
  const double R = 1e-3;
  w.add_particle({0.0005, 0.005, 0.005}, R, 2600);
  w.add_particle({0.0085, 0.005, 0.005}, R, 2600);        // image at -0.0015: gap 0.002, overlap 0
  w.add_particle({0.0088, 0.005, 0.005 + 5e-3}, R, 2600); // far away in z
  w.set_fixed_timestep(1e-7); // contact duration pi sqrt(mc/kn) = 1.9e-5 s = 185 steps
  w.cycle(1);
  const auto contacts = w.ball_ball_contacts();
  ASSERT_EQ(contacts.size(), 0u);                           // exactly touching: no overlap yet
  w.particles_mut().velocity[*w.index_of(2)] = {0.1, 0, 0}; // moves towards the image
  w.cycle(50);                                              // inside the contact duration
  const auto c2 = w.ball_ball_contacts();
  ASSERT_EQ(c2.size(), 1u);
  const auto& p = w.particles();
  const std::size_t a = *w.index_of(1), b = *w.index_of(2);
  EXPECT_NEAR(p.force[a].x + p.force[b].x, 0.0, 1e-12 * std::abs(p.force[a].x));
  EXPECT_GT(p.force[a].x, 0.0); // pushed to +x, away from the image of 2 at its left
  // Momentum conserved: m v0 = m (va + vb).
  EXPECT_NEAR(p.velocity[a].x + p.velocity[b].x, 0.1, 1e-12);
}

// A dense random periodic assembly: linear momentum stays zero to round-off,
// and wrapped positions stay inside the box at every rebuild.
TEST(Periodic, MomentumConservedInDensePeriodicAssembly) {
  World w;
  w.set_ball_ball_defaults(stiff_frictional());
  PeriodicBox pb;
  pb.axis = {true, true, true};
  pb.hi = {0.01, 0.01, 0.01};
  w.set_periodic(pb);
  // A jittered 12^3 lattice (spacing 0.83 mm) of radii 0.30-0.45 mm: slightly
  // overlapping at the start, so the assembly expands and collides.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jit(-5e-5, 5e-5), rr(3e-4, 4.5e-4);
  const double a = 0.01 / 12;
  for (int ix = 0; ix < 12; ++ix)
    for (int iy = 0; iy < 12; ++iy)
      for (int iz = 0; iz < 12; ++iz)
        w.add_particle(
            {(ix + 0.5) * a + jit(rng), (iy + 0.5) * a + jit(rng), (iz + 0.5) * a + jit(rng)},
            rr(rng), 2600);
  w.cycle(1);
  EXPECT_GT(w.measure().ball_ball_contacts, 100u);
  w.cycle(3000);
  Vec3 mom{};
  double scale = 0;
  const auto& p = w.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    mom += p.mass[i] * p.velocity[i];
    scale += p.mass[i] * norm(p.velocity[i]);
  }
  ASSERT_GT(scale, 0);
  EXPECT_LT(norm(mom), 1e-12 * scale);
  EXPECT_GT(w.neighbour_rebuilds(), 1);
  w.request_rebuild();
  w.cycle(1);
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(p.position[i][a], -0.01 * 0.01);
      EXPECT_LE(p.position[i][a], 0.01 * 1.01);
    }
}

// contact_records() / restore_contacts(): a world rebuilt from the records of
// another gives the same forces on the next step.
TEST(ContactRecords, RestoreReproducesHistory) {
  auto make = [] {
    World w;
    w.set_ball_ball_defaults(stiff_frictional());
    w.add_particle({0, 0, 0}, 1e-3, 2600);
    w.add_particle({1.99e-3, 0, 0}, 1e-3, 2600);
    return w;
  };
  World a = make();
  a.particles_mut().velocity[1] = {0, 0.01, 0}; // shear the pair
  a.set_fixed_timestep(1e-7);
  a.cycle(50);
  const auto recs = a.contact_records();
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_GT(norm(recs[0].state.shear_force), 0.0);

  World b = make();
  b.set_fixed_timestep(1e-7);
  auto& pb = b.particles_mut();
  const auto& pa = a.particles();
  for (std::size_t i = 0; i < 2; ++i) {
    const std::size_t k = *b.index_of(pa.id[i]);
    pb.position[k] = pa.position[i];
    pb.velocity[k] = pa.velocity[i];
    pb.spin[k] = pa.spin[i];
  }
  b.particles_changed();
  b.restore_contacts(recs);
  a.cycle(1);
  b.cycle(1);
  const auto ca = a.ball_ball_contacts(), cb = b.ball_ball_contacts();
  ASSERT_EQ(cb.size(), 1u);
  EXPECT_NEAR(norm(ca[0].force_on_j - cb[0].force_on_j), 0.0, 1e-12 * norm(ca[0].force_on_j));
}
