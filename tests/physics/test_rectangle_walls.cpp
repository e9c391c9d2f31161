// Acceptance 11: finite rectangle walls (walls.hpp: two-sided plates whose
// faces, edges and corners all make contacts). For a ball of radius R at x,
// with q the closest point of the rectangle (clamp of x into the plate in
// its (u, v) coordinates), the contact normal (ball -> wall) is
// (q - x)/|q - x| and the overlap R - |q - x|, so with kn = pi R E*
// (ball-wall deformability, DESIGN.md) the force on the wall is
//   F = kn (R - |q - x|) (q - x)/|q - x|
// (frictionless, no dashpot, ball at rest). Source: closest-point
// sphere-rectangle geometry (Ericson, Real-Time Collision Detection, 5.1.4);
// DESIGN.md "Physics".
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 1e-3, rho = 2650, E = 1e8;

Vec3 unit(const Vec3& v) {
  return v / norm(v);
}

// A tilted 4R x 6R plate; the ball at centre + a u + b v + h n.
struct Plate {
  Vec3 c{0.3e-3, -0.2e-3, 0.5e-3};
  Vec3 n = unit({1, 2, 3});
  Vec3 u, v;
  double hu = 2 * R, hv = 3 * R;
  Plate() {
    const Wall w = Wall::rectangle("plate", c, n, {1, 0, 0}, 2 * hu, 2 * hv);
    u = w.axis_u;
    v = w.axis_v;
  }
  Vec3 at(double a, double b, double h) const { return c + a * u + b * v + h * n; }
};

// Force on the plate from one fixed ball at x after one step.
Vec3 wall_force(const Plate& pl, const Vec3& x, std::uint32_t* contacts = nullptr) {
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = 1e-7;
  World w(s);
  w.add_wall(Wall::rectangle("plate", pl.c, pl.n, {1, 0, 0}, 2 * pl.hu, 2 * pl.hv),
             props(ContactModel::linear, E, 0.0));
  w.add_particle(x, R, rho, 0, 1);
  w.particles_mut().flags[0] = fix_translation | fix_rotation;
  w.cycle(1);
  if (contacts) *contacts = w.walls()[0].contact_count;
  return w.walls()[0].force;
}

Vec3 expected_force(const Vec3& x, const Vec3& q) {
  const double d = norm(q - x);
  return kn_ball_wall(E, R) * (R - d) * ((q - x) / d);
}

TEST(PhysicsRectangleWalls, FaceEdgeCornerNormalsAndOverlap) {
  const Plate pl;
  const double d = R - 1e-3 * R; // centre-to-closest-point distance: overlap 1e-3 R
  struct Case {
    const char* name;
    Vec3 x, q;
  };
  const Vec3 e1 = unit(pl.u + pl.n), e2 = unit(-pl.v - 0.5 * pl.n);
  const Vec3 corner_dir = unit(pl.u + pl.v + pl.n), corner_dir2 = unit(-pl.u + pl.v - 2 * pl.n);
  const Case cases[] = {
      {"front face", pl.at(0.5 * R, -1.2 * R, d), pl.at(0.5 * R, -1.2 * R, 0)},
      {"back face", pl.at(-1.5 * R, 2.5 * R, -d), pl.at(-1.5 * R, 2.5 * R, 0)},
      {"edge +u", pl.at(pl.hu, 0.7 * R, 0) + d * e1, pl.at(pl.hu, 0.7 * R, 0)},
      {"edge -v", pl.at(-0.3 * R, -pl.hv, 0) + d * e2, pl.at(-0.3 * R, -pl.hv, 0)},
      {"edge +u in plane", pl.at(pl.hu + d, 0.2 * R, 0), pl.at(pl.hu, 0.2 * R, 0)},
      {"corner +u+v", pl.at(pl.hu, pl.hv, 0) + d * corner_dir, pl.at(pl.hu, pl.hv, 0)},
      {"corner -u+v back", pl.at(-pl.hu, pl.hv, 0) + d * corner_dir2, pl.at(-pl.hu, pl.hv, 0)},
  };
  for (const Case& c : cases) {
    std::uint32_t contacts = 0;
    const Vec3 f = wall_force(pl, c.x, &contacts);
    const Vec3 e = expected_force(c.x, c.q);
    EXPECT_EQ(contacts, 1u) << c.name;
    EXPECT_LT(rel(f, e, norm(e)), 1e-9) << c.name << ": force " << f.x << " " << f.y << " " << f.z
                                        << " expected " << e.x << " " << e.y << " " << e.z;
  }
}

// Just out of reach of an edge and a corner (distance 1.001 R), or beside
// the plate in its own plane beyond the edge: no contact, no force.
TEST(PhysicsRectangleWalls, NoContactBeyondTheEdges) {
  const Plate pl;
  const double d = 1.001 * R;
  const Vec3 xs[] = {pl.at(pl.hu, 0, 0) + d * unit(pl.u + pl.n),
                     pl.at(pl.hu, pl.hv, 0) + d * unit(pl.u + pl.v - pl.n), pl.at(0, -pl.hv - d, 0),
                     // above the face's plane extension, outside the plate:
                     // a plane would touch it, the rectangle must not
                     pl.at(pl.hu + 1.2 * R, 0, 0.5 * R)};
  for (const Vec3& x : xs) {
    std::uint32_t contacts = 7;
    const Vec3 f = wall_force(pl, x, &contacts);
    EXPECT_EQ(contacts, 0u);
    EXPECT_EQ(norm(f), 0.0);
  }
}

} // namespace
} // namespace centridem
