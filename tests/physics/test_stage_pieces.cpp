// A grain with more neighbours than the contact pass stages at once
// (kContactStageSize, engine/contacts.hpp): a large sphere among fine ones.
// Its row goes through the stage in pieces with its sums carried across them
// (contact_pass.cpp). Closed form: N small spheres at rest, each pressed onto
// the large one by the same overlap delta along its own outward normal n_k,
// linear law with kn given, no gravity, no walls, no damping. After one step
// every small sphere carries kn delta n_k, and the large one, by Newton's third
// law, -kn delta sum_k n_k. A piece whose results are not stored leaves its
// small spheres without force; a piece left out of (or added twice to) the
// row's sum moves the large one's force by about kn delta or more.
#include "physics_test_util.hpp"

#include "engine/contacts.hpp"

#include <gtest/gtest.h>

#include <map>

namespace centridem {
namespace {
using namespace phys_test;

// Too few particles for the World to use more than one thread: one thread.
// (No "Long" in the names: tests/CMakeLists.txt makes those opt-in.)
class RowPastTheStage : public ::testing::TestWithParam<int> {};

TEST_P(RowPastTheStage, LargeSphereAmongFineOnesCarriesTheSumOfItsContacts) {
  const int small_spheres = GetParam();
  constexpr double R = 5e-3, r = 0.2e-3, delta = 1e-6; // [m]
  constexpr double kn = 1e4, rho = 2650.0;             // [N/m], [kg/m^3]
  WorldSettings s;
  s.neighbour_skin_m = 0.05e-3;
  World w(s);
  ContactProperties cp;
  cp.model = ContactModel::linear;
  cp.stiffness_method = StiffnessMethod::direct;
  cp.normal_stiffness_N_per_m = kn;
  cp.shear_stiffness_N_per_m = kn / 1.5;
  cp.friction = 0.5;
  w.set_ball_ball_defaults(cp);
  w.set_fixed_timestep(1e-7);

  // Small spheres on a Fibonacci lattice over the large sphere's surface:
  // 400 of them are 0.9 mm apart (diameter 0.4 mm), so they touch only it.
  const Vec3 centre{0.02, 0.02, 0.02};
  constexpr std::int64_t big = 0;
  w.add_particle(centre, R, rho, 0, big);
  std::map<std::int64_t, Vec3> outward;
  const double golden = pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < small_spheres; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / small_spheres;
    const double rho_xy = std::sqrt(1.0 - z * z), phi = golden * k;
    const Vec3 n{rho_xy * std::cos(phi), rho_xy * std::sin(phi), z};
    const std::int64_t id = k + 1;
    w.add_particle(centre + (R + r - delta) * n, r, rho, 0, id);
    outward[id] = n;
  }
  w.cycle(1);

  const ParticleStore& P = w.particles();
  const std::size_t ib = *w.index_of(big);
  // The case is what it claims: every small sphere touches the large one, and
  // the large one's row (it is the first end of a contact with each sphere
  // sorted after it) is longer than the stage.
  const auto contacts = w.ball_ball_contacts();
  ASSERT_EQ(contacts.size(), static_cast<std::size_t>(small_spheres));
  std::size_t row = 0;
  for (const ContactView& v : contacts) row += v.i == ib;
  ASSERT_GT(row, kContactStageSize) << "the large sphere's row fits the stage: no pieces";

  const double f0 = kn * delta; // [N]
  Vec3 expected_on_big{};
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (i == ib) continue;
    const Vec3 want = f0 * outward.at(P.id[i]);
    expected_on_big -= want;
    ASSERT_LT(norm(P.force[i] - want), 1e-9 * f0) << "small sphere id " << P.id[i];
  }
  // Round-off only: each of the N terms is exact to about 1e-16 f0.
  EXPECT_LT(norm(P.force[ib] - expected_on_big), 1e-9 * f0)
      << "force on the large sphere " << P.force[ib].x << " " << P.force[ib].y << " "
      << P.force[ib].z;
}

INSTANTIATE_TEST_SUITE_P(ContactPass, RowPastTheStage,
                         // Rows of up to 300 and 400 entries: two to four pieces.
                         ::testing::Values(300, 400), [](const auto& info) {
                           return std::to_string(info.param) + "FineSpheres";
                         });

} // namespace
} // namespace centridem
