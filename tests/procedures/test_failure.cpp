// Failure detection (src/procedures/failure.hpp): the sliding mass on
// hand-made displacement fields, the monitor's decisions on a scripted
// sequence of checks, and two small DEM slopes cut from one settled
// foundation: a gentle (20-degree) frictional slope must be reported stable
// with no sliding mass, a 45-degree frictionless one failed with a slide that
// starts at the face and runs out beyond the toe. The two guard each other: a
// monitor that always said "failed" (or "stable") fails one of them.
#include "base/errors.hpp"
#include "engine/world.hpp"
#include "procedures/failure.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/slope_geometry.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

namespace centridem {
namespace {

constexpr double pi = std::numbers::pi;

// ------------------------------------------------------- sliding mass --

// Particles of radius r on a line along x with spacing a, ids 1..n.
World line_world(int n, double r, double a) {
  WorldSettings ws;
  ws.threads = 1;
  World w(ws);
  for (int k = 0; k < n; ++k) w.add_particle({k * a, 0, 0}, r, 2633);
  return w;
}

TEST(SlidingMass, ThresholdAndLinksPickTheLargestGroup) {
  const double r = 0.2e-3;
  World w = line_world(20, r, 2.1 * r); // gaps of 0.05 (Ri + Rj)
  auto& P = w.particles_mut();
  // Displaced: 0..4 (a group of 5), 8..9 (a group of 2), 12..18 (7, but 15 is
  // below the threshold: groups of 3 and 3).
  for (int k : {0, 1, 2, 3, 4, 8, 9, 12, 13, 14, 16, 17, 18}) P.displacement[k] = {0, 0, -1e-3};
  P.displacement[15] = {0, 0, -0.1e-3};
  SlidingMassCriteria c;
  c.displacement_threshold_m = 0.5e-3;
  SlidingMass m = find_sliding_mass(w, c, 0.4e-3);
  EXPECT_DOUBLE_EQ(m.threshold_m, 0.5e-3);
  EXPECT_EQ(m.above_threshold, 13u);
  EXPECT_EQ(m.groups, 4u);
  ASSERT_EQ(m.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(m.indices[k], k);
  EXPECT_NEAR(m.volume_m3, 5 * 4.0 / 3.0 * pi * r * r * r, 1e-20);
  // Relative threshold: 0.5 d50 = 0.075 mm lets particle 15 in, joining 12..18.
  c.displacement_threshold_m = 0;
  m = find_sliding_mass(w, c, 0.15e-3);
  EXPECT_DOUBLE_EQ(m.threshold_m, 0.075e-3);
  EXPECT_EQ(m.size(), 7u);
  EXPECT_EQ(m.indices.front(), 12u);
  // Links: with gaps of 0.05 (Ri + Rj) a factor of 1.04 separates everything.
  c.link_distance_factor = 1.04;
  m = find_sliding_mass(w, c, 0.15e-3);
  EXPECT_EQ(m.size(), 1u);
  EXPECT_EQ(m.groups, 14u);
  // Nothing moved: an empty mass.
  for (Vec3& d : P.displacement) d = {};
  m = find_sliding_mass(w, c, 0.4e-3);
  EXPECT_EQ(m.size(), 0u);
  EXPECT_EQ(m.groups, 0u);
}

TEST(SlidingMass, GroupsIn3DMatchBruteForce) {
  // Random loose particles, random displacements: the cell search must find
  // the same largest group as an all-pairs flood fill.
  WorldSettings ws;
  ws.threads = 1;
  World w(ws);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const int n = 1500;
  for (int k = 0; k < n; ++k)
    w.add_particle({6e-3 * u(rng), 6e-3 * u(rng), 6e-3 * u(rng)}, 0.2e-3 + 0.2e-3 * u(rng), 2633);
  auto& P = w.particles_mut();
  for (int k = 0; k < n; ++k) P.displacement[k] = {u(rng) * 1e-3, 0, 0};
  SlidingMassCriteria c;
  c.displacement_threshold_m = 0.3e-3;
  c.link_distance_factor = 1.1;
  const SlidingMass m = find_sliding_mass(w, c, 0.5e-3);
  // Brute force.
  std::vector<int> comp(n, -1);
  double best_v = 0;
  std::vector<int> best;
  for (int s = 0; s < n; ++s) {
    if (comp[s] >= 0 || norm(P.displacement[s]) <= 0.3e-3) continue;
    std::vector<int> stack{s}, members;
    comp[s] = s;
    double v = 0;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      members.push_back(i);
      v += std::pow(P.radius[i], 3);
      for (int j = 0; j < n; ++j)
        if (comp[j] < 0 && norm(P.displacement[j]) > 0.3e-3 &&
            norm(P.position[j] - P.position[i]) <= 1.1 * (P.radius[i] + P.radius[j]))
          comp[j] = s, stack.push_back(j);
    }
    if (v > best_v) best_v = v, best = members;
  }
  std::sort(best.begin(), best.end());
  ASSERT_EQ(m.size(), best.size());
  ASSERT_GT(m.size(), 10u);
  for (std::size_t k = 0; k < best.size(); ++k) EXPECT_EQ(m.indices[k], std::size_t(best[k]));
}

TEST(SlidingMass, MedianDiameterIsVolumeWeighted) {
  WorldSettings ws;
  ws.threads = 1;
  World w(ws);
  // One big sphere holds 8/9 of the volume: the volume median is its size.
  w.add_particle({0, 0, 0}, 2e-3, 2633);
  w.add_particle({1, 0, 0}, 1e-3, 2633);
  EXPECT_DOUBLE_EQ(median_diameter(w.particles()), 4e-3);
  EXPECT_DOUBLE_EQ(median_diameter(World{}.particles()), 0.0);
}

TEST(FailureCriteria, ValidationNamesTheKey) {
  auto key = [](auto change) {
    FailureCriteria c;
    change(c);
    try {
      validate(c);
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string();
  };
  EXPECT_EQ(key([](FailureCriteria&) {}), "");
  EXPECT_EQ(key([](FailureCriteria& c) { c.mass.displacement_threshold_d50 = 0; }),
            "failure.displacement_threshold_d50");
  EXPECT_EQ(key([](FailureCriteria& c) { c.mass.displacement_threshold_m = -1; }),
            "failure.displacement_threshold_m");
  EXPECT_EQ(key([](FailureCriteria& c) { c.mass.link_distance_factor = 0.9; }),
            "failure.link_distance_factor");
  EXPECT_EQ(key([](FailureCriteria& c) { c.min_volume_fraction = 1.5; }),
            "failure.min_volume_fraction");
  EXPECT_EQ(key([](FailureCriteria& c) { c.min_particles = 0; }), "failure.min_particles");
  EXPECT_EQ(key([](FailureCriteria& c) { c.moving_speed_factor = 0; }),
            "failure.moving_speed_factor");
  EXPECT_EQ(key([](FailureCriteria& c) { c.consecutive_checks = 0; }),
            "failure.consecutive_checks");
  EXPECT_EQ(key([](FailureCriteria& c) { c.equilibrium_ratio = NAN; }),
            "failure.equilibrium_ratio");
  EXPECT_EQ(key([](FailureCriteria& c) { c.slip_surface_bin_d50 = -1; }),
            "failure.slip_surface_bin_d50");
  EXPECT_THROW(FailureMonitor(SlopeGeometry(BenchedSlope::paper_lower_first_bench()),
                              FailureCriteria{.consecutive_checks = -1}),
               InputError);
}

// ------------------------------------------- the monitor, scripted checks --

// The paper's lower-bench slope (DEM scale) filled with a lattice of
// particles (no cycling: displacements and velocities are set by hand).
struct LatticeSlope {
  SlopeGeometry g{BenchedSlope::paper_lower_first_bench()};
  World w{[] {
    WorldSettings ws;
    ws.threads = 1;
    return ws;
  }()};
  double a = 0.5e-3;  // lattice spacing
  double r = 0.24e-3; // radius: neighbours on the lattice are linked (0.5 < 1.2 x 0.48)
  LatticeSlope() {
    for (double x = a / 2; x < g.length(); x += a)
      for (double y = a / 2; y < g.breadth(); y += a)
        for (double z = a / 2; z < g.height(); z += a)
          if (g.is_soil({x, y, z})) w.add_particle({x, y, z}, r, 2633);
    w.set_body_field(BodyField::scaled_gravity(40, g.scale()));
  }
  // Moves particle i by d (displacement and position together) at velocity v.
  void move(std::size_t i, const Vec3& d, const Vec3& v) {
    auto& P = w.particles_mut();
    P.position[i] += d - P.displacement[i];
    P.displacement[i] = d;
    P.velocity[i] = v;
  }
};

TEST(FailureMonitor, ScriptedSlideFromTheCrest) {
  LatticeSlope s;
  const SlopeGeometry& g = s.g;
  const std::size_t n = s.w.particles().size();
  ASSERT_GT(n, 5000u);
  // The streak logic alone (no minimum mass displacement; see the next test).
  FailureCriteria speed_only;
  speed_only.failure_displacement_d50 = 0.0;
  FailureMonitor mon(g, speed_only);
  // Nothing moves: stable after two checks (the unbuilt World's ratio is 0).
  EXPECT_EQ(mon.update(s.w, 0.001), SlopeState::undecided);
  EXPECT_EQ(mon.update(s.w, 0.002), SlopeState::stable);
  EXPECT_FALSE(mon.report().sliding_mass);
  EXPECT_NEAR(mon.report().d50_m, 2 * s.r, 1e-15);
  EXPECT_NEAR(mon.report().gravity_m_s2, 40 * standard_gravity_m_s2 / 0.063, 1e-9 * 6226.4);

  // The slip surface: from the crest plateau (3 mm behind the crest edge,
  // DEM) under the first bench's inner corner (1.5 mm below it) to the toe;
  // the wedge above it slides, all by one displacement along the chord.
  const double xa = g.crest_x() - 3e-3, za = g.height();
  const double xm = g.bench_column(1).first, zm = g.z_surface(xm) - 1.5e-3;
  const double xb = g.toe_x(), zb = g.toe_height();
  auto slip_z = [&](double x) {
    return x < xm ? za + (zm - za) * (x - xa) / (xm - xa) : zm + (zb - zm) * (x - xm) / (xb - xm);
  };
  const double max_slope = std::max((za - zm) / (xm - xa), (zm - zb) / (xb - xm));
  const Vec3 dir = Vec3{xb - xa, 0, zb - za} / std::hypot(xb - xa, zb - za);
  auto above_line = [&](const Vec3& x) {
    return x.x >= xa && x.x <= xb && x.z > slip_z(x.x) + 1e-9;
  };
  const auto origin = s.w.particles().position;
  // Check 3: only the crest corner has moved (0.4 mm), at 0.2 m/s.
  std::size_t corner = 0, wedge = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!above_line(origin[i])) continue;
    ++wedge;
    if (origin[i].x > g.crest_x() - 2e-3 && origin[i].x <= g.crest_x() &&
        origin[i].z > g.height() - 1e-3)
      s.move(i, 0.4e-3 * dir, 0.2 * dir), ++corner;
  }
  ASSERT_GT(corner, 50u);
  ASSERT_GT(wedge, 1000u);
  EXPECT_EQ(mon.update(s.w, 0.003), SlopeState::undecided); // moving, but once only
  // Check 4: the whole wedge has moved 2 mm at 0.5 m/s: failed, onset at 0.003.
  for (std::size_t i = 0; i < n; ++i)
    if (above_line(origin[i])) s.move(i, 2e-3 * dir, 0.5 * dir);
  EXPECT_EQ(mon.update(s.w, 0.004), SlopeState::failed);
  const FailureReport& r = mon.report();
  ASSERT_TRUE(r.onset_time_s.has_value());
  EXPECT_DOUBLE_EQ(*r.onset_time_s, 0.003);
  ASSERT_TRUE(r.start_zone.has_value());
  EXPECT_EQ(*r.start_zone, (ZoneId{SlopeZone::crest, 2})); // the corner moved first
  EXPECT_TRUE(r.sliding_mass);
  EXPECT_EQ(r.particles, wedge);
  EXPECT_NEAR(r.volume_m3, double(wedge) * 4.0 / 3.0 * pi * std::pow(s.r, 3), 1e-15);
  EXPECT_NEAR(r.particle_share, double(wedge) / double(n), 1e-12);
  EXPECT_NEAR(r.mean_speed_m_s, 0.5, 1e-9);
  EXPECT_NEAR(r.mean_displacement_m, 2e-3, 1e-12);
  EXPECT_EQ(r.benches_crossed, (std::vector<int>{1, 2}));
  EXPECT_EQ(r.source_benches, (std::vector<int>{1, 2}));
  // Runout: the front moved 2 mm along the chord from just behind the toe.
  EXPECT_LE(r.runout_m, 2e-3 * dir.x + 1e-12);
  EXPECT_GT(r.runout_m, 2e-3 * dir.x - 1.5e-3);
  EXPECT_DOUBLE_EQ(r.runout_model_m, r.runout_m / 0.063);
  // Slip surface: the lowest original centres follow the line within a
  // lattice step and half the line's drop across a bin (2 d50 wide).
  ASSERT_GT(r.slip_surface.size(), 5u);
  const double half_drop = max_slope * 0.5 * 2 * r.d50_m;
  for (const SectionPoint& p : r.slip_surface) {
    const double line = slip_z(p.x);
    EXPECT_GT(p.z, line - half_drop - 1e-9) << p.x;
    EXPECT_LT(p.z, line + half_drop + s.a) << p.x;
  }
  // The report survives a JSON round.
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["state"], "failed");
  EXPECT_EQ(j["start_zone"], "crest");
  EXPECT_EQ(j["benches_crossed"], nlohmann::json({1, 2}));
  EXPECT_DOUBLE_EQ(j["onset_time_s"].get<double>(), 0.003);
  EXPECT_EQ(j["slip_surface_xz_m"].size(), r.slip_surface.size());

  // It comes to rest: still failed (latched), now settled and finished.
  for (std::size_t i = 0; i < n; ++i) s.w.particles_mut().velocity[i] = {};
  EXPECT_EQ(mon.update(s.w, 0.005), SlopeState::failed);
  EXPECT_EQ(mon.update(s.w, 0.006), SlopeState::failed);
  EXPECT_TRUE(mon.finished());
  EXPECT_EQ(mon.report().particles, wedge);
  EXPECT_EQ(mon.history().size(), 6u);
}

TEST(FailureMonitor, NeedsASignificantMassMovingOnConsecutiveChecks) {
  LatticeSlope s;
  const std::size_t n = s.w.particles().size();
  const auto origin = s.w.particles().position;
  FailureMonitor mon(s.g);
  // A handful of grains rolling fast: not significant (< 100 particles).
  std::size_t rolled = 0;
  for (std::size_t i = 0; i < n && rolled < 40; ++i)
    if (s.g.classify(origin[i].x, origin[i].z).zone == SlopeZone::upper_face &&
        origin[i].z > s.g.z_surface(origin[i].x) - s.a)
      s.move(i, {1e-3, 0, -1e-3}, {1, 0, -1}), ++rolled;
  for (int k = 0; k < 4; ++k) mon.update(s.w, 0.001 * k);
  EXPECT_FALSE(mon.failed());
  EXPECT_FALSE(mon.report().sliding_mass);
  EXPECT_GT(mon.report().above_threshold, 0u);
  // A large mass displaced but at rest (deformed, not moving): not failed.
  for (std::size_t i = 0; i < n; ++i)
    if (origin[i].x > s.g.crest_x() - 3e-3 && origin[i].x < s.g.toe_x())
      s.move(i, {0.5e-3, 0, -0.5e-3}, {});
  for (int k = 4; k < 8; ++k) mon.update(s.w, 0.001 * k);
  EXPECT_FALSE(mon.failed());
  EXPECT_TRUE(mon.report().sliding_mass); // significant, reported, but not failing
  EXPECT_EQ(mon.state(), SlopeState::stable);
  // Moving on one check only (a jolt), then at rest: still not failed.
  for (std::size_t i = 0; i < n; ++i)
    if (norm(s.w.particles().displacement[i]) > 0) s.w.particles_mut().velocity[i] = {0.3, 0, 0};
  mon.update(s.w, 0.009);
  for (std::size_t i = 0; i < n; ++i) s.w.particles_mut().velocity[i] = {};
  mon.update(s.w, 0.010);
  EXPECT_FALSE(mon.failed());
  // Moving on two checks: failed, onset at the first of them.
  for (std::size_t i = 0; i < n; ++i)
    if (norm(s.w.particles().displacement[i]) > 0) s.w.particles_mut().velocity[i] = {0.3, 0, 0};
  mon.update(s.w, 0.011);
  mon.update(s.w, 0.012);
  EXPECT_TRUE(mon.failed());
  EXPECT_DOUBLE_EQ(*mon.report().onset_time_s, 0.011);
}

// "At rest" is the slope body's: the mean unbalanced-force ratio of the
// particles above the foundation, not of the whole model, whose foundation
// dilutes it (at the paper's size the whole-model ratio fell below 1e-4 0.6 ms
// after the cut and two trials were called stable before anything moved).
// Closed form: the lattice has no contacts; each foundation grain is held by
// an applied force -m g (unbalanced 0, applied 2 m g), each slope grain falls
// freely (unbalanced m g, applied m g). So the slope's ratio is 1 and the
// model's is sum_s m / (sum_s m + 2 sum_f m). With equilibrium_ratio between
// the two, the slope is not at rest and never called stable.
TEST(FailureMonitor, AtRestIsJudgedOnTheSlopeAboveTheFoundation) {
  LatticeSlope s;
  auto& P = s.w.particles_mut();
  const double toe = s.g.toe_height();
  double m_slope = 0, m_found = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vec3 g = s.w.body_field().acceleration(P.position[i], {});
    if (P.position[i].z > toe) {
      m_slope += P.mass[i];
    } else {
      P.applied_force[i] = -P.mass[i] * g;
      m_found += P.mass[i];
    }
  }
  ASSERT_GT(m_found, 0.0);
  s.w.cycle(1);
  const double model = s.w.mean_unbalanced_force_ratio();
  const double slope = s.w.mean_unbalanced_force_ratio(
      [&](std::size_t i) { return s.w.particles().position[i].z > toe; });
  EXPECT_NEAR(slope, 1.0, 1e-9);
  EXPECT_NEAR(model, m_slope / (m_slope + 2 * m_found), 1e-6);
  FailureCriteria c;
  c.equilibrium_ratio = 0.5 * (model + 1.0);
  FailureMonitor mon(s.g, c);
  for (int k = 0; k < 4; ++k) mon.update(s.w, 0.001 * k);
  EXPECT_NEAR(mon.report().unbalanced_force_ratio, 1.0, 1e-9);
  EXPECT_NEAR(mon.report().model_unbalanced_force_ratio, model, 1e-12);
  EXPECT_EQ(mon.state(), SlopeState::undecided) << "a falling slope is not at rest";
  EXPECT_FALSE(mon.report().settled);
}

// --------------------------------------------- small DEM slopes, cycled --
//
// A one-bench slope 4 mm high (DEM), 18 mm long and 5 mm across, on 1 mm of
// foundation, crest 3 mm from the back wall, under 40 g at s = 0.063
// (6,226 m/s^2). About 2,300 particles of radius 0.2-0.4 mm (d50 ~ 0.68 mm)
// with the paper's density, stiffness (E* = 300 MPa, kappa* = 1.5) and
// local damping (0.7); walls of friction 0.2 (the paper's) except the two
// side walls, frictionless so that a slice 7 grains across acts as part of a
// wide slope. The foundation is poured once (random non-overlapping lattice,
// settled to a mean unbalanced-force ratio of 1e-4 with mu = 0.2,
// mu_r = 0.05: dense and quick to settle); each trial then gives every
// ball-ball contact, old and new, its own friction, cuts the slope (which
// also levels the crest at 5 mm), resets displacements and cycles with the
// monitor checking every 200 steps.
//
// The frictionless trial uses a 45-degree face: a frictionless 20-degree
// face fails too, but slowly, as a whole-body spreading in which (in some
// packings) the soil behind the crest subsides first, so that its start
// zone is honestly "crest"; the steeper face slides from the face.

constexpr double s_red = 0.063, g_level = 40;
constexpr double L = 18e-3, B = 5e-3, H = 5e-3, H_toe = 1e-3; // DEM [m]

BenchedSlope slope_with_face(double face_angle_deg) {
  BenchedSlope b;
  b.size_reduction_factor = s_red;
  b.total_height_m = H / s_red;
  b.foundation_height_m = H_toe / s_red;
  b.breadth_m = B / s_red;
  b.length_m = L / s_red;
  b.crest_to_wall_m = 3e-3 / s_red;
  b.benches = {Bench{(H - H_toe) / s_red, std::nullopt, face_angle_deg}};
  return b;
}

ContactProperties soil(double friction, double rolling_friction) {
  ContactProperties p = paper::ball_ball(0.0); // no adhesion
  p.model = ContactModel::rrlinear;
  p.friction = friction;
  p.rolling_friction = rolling_friction;
  return p;
}

struct Foundation {
  World world;
  double top_m = 0; // the lowest of the highest centres in 2 mm columns along x
};

// The settled foundation, made once for the tests of this file.
const Foundation& settled_foundation() {
  static const Foundation settled = [] {
    WorldSettings ws;
    ws.threads = 1;
    ws.local_damping = paper::local_damping;
    World w(ws);
    w.set_ball_ball_defaults(soil(0.2, 0.05));
    const ContactProperties wall = paper::ball_wall(0.2), side = paper::ball_wall(0.0);
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), wall);
    w.add_wall(Wall::plane("back", {0, 0, 0}, {1, 0, 0}), wall);
    w.add_wall(Wall::plane("end", {L, 0, 0}, {-1, 0, 0}), wall);
    w.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), side);
    w.add_wall(Wall::plane("y1", {0, B, 0}, {0, -1, 0}), side);
    // One particle per 1 mm cell, placed at random inside its cell (no
    // overlaps, no columns), radii uniform in [0.2, 0.4] mm.
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> u(0, 1);
    const double a = 1e-3;
    const int nx = static_cast<int>(L / a), ny = static_cast<int>(B / a), nz = 26;
    const double cx = L / nx, cy = B / ny;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const double r = 0.2e-3 + 0.2e-3 * u(rng);
          const double x = (i + 0.5) * cx + (0.5 * cx - r) * (2 * u(rng) - 1);
          const double y = (j + 0.5) * cy + (0.5 * cy - r) * (2 * u(rng) - 1);
          const double z = (k + 0.5) * a + (0.5 * a - r) * (2 * u(rng) - 1);
          w.add_particle({x, y, z}, r, paper::density_kg_m3);
        }
    w.set_body_field(BodyField::scaled_gravity(g_level, s_red));
    const long steps = w.cycle_until_equilibrium(1e-4, 200000, 200);
    double top = INFINITY; // lowest surface grain: the top of the soil everywhere
    {
      const auto& P = w.particles();
      for (double x0 = 0; x0 < L; x0 += 2e-3) {
        double col = 0;
        for (std::size_t i = 0; i < P.size(); ++i)
          if (P.position[i].x >= x0 && P.position[i].x < x0 + 2e-3)
            col = std::max(col, P.position[i].z);
        top = std::min(top, col);
      }
    }
    std::printf("foundation: %zu particles, %ld steps, dt %.3g s, ratio %.2g, top >= %.2f mm\n",
                w.particles().size(), steps, w.timestep(), w.mean_unbalanced_force_ratio(),
                top * 1e3);
    return Foundation{w, top};
  }();
  return settled;
}

struct Trial {
  FailureReport report;
  std::vector<FailureCheck> history;
  std::size_t slope_particles = 0;
  SlopeState state_at_decision = SlopeState::undecided;
};

// One trial: checks every 200 steps until the monitor decides; after a
// failure, cycles on until the slide's front has passed the toe, it has come
// to rest, or extra_steps.
Trial run_trial(double face_angle_deg, double friction, double rolling_friction, long max_steps,
                long extra_steps) {
  const Foundation& f = settled_foundation();
  // The soil reaches above the crest everywhere (the cut levels it).
  EXPECT_GT(f.top_m, H + 0.2e-3);
  World w = f.world;
  w.set_ball_ball_defaults(soil(friction, rolling_friction));
  w.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                              [&](ContactProperties& p) {
                                p.friction = friction;
                                p.rolling_friction = rolling_friction;
                              });
  const SlopeGeometry g(slope_with_face(face_angle_deg));
  g.excavate(w);
  w.reset_displacements();
  Trial t;
  t.slope_particles = w.particles().size();
  FailureMonitor mon(g);
  const double t0 = w.time();
  long done = 0;
  for (; done < max_steps && mon.state() == SlopeState::undecided; done += 200) {
    w.cycle(200);
    mon.update(w, w.time() - t0);
  }
  t.state_at_decision = mon.state();
  for (long extra = 0;
       mon.failed() && !mon.finished() && mon.report().runout_m <= 0 && extra < extra_steps;
       extra += 200) {
    w.cycle(200);
    mon.update(w, w.time() - t0);
  }
  t.report = mon.report();
  t.history = mon.history();
  std::printf("trial mu = %.2g: %zu particles, %d checks: %s\n", friction, t.slope_particles,
              t.report.checks, to_json(t.report).dump().c_str());
  return t;
}

// (a) 20-degree face, mu = 0.5, mu_r = 0.16: stable, no sliding mass.
TEST(FailureMonitor, GentleFrictionalSlopeIsStable) {
  const Trial t = run_trial(20, 0.5, 0.16, 40000, 0);
  EXPECT_GT(t.slope_particles, 1000u);
  EXPECT_EQ(t.report.state, SlopeState::stable);
  EXPECT_FALSE(t.report.sliding_mass);
  EXPECT_EQ(t.report.particles, 0u);
  EXPECT_FALSE(t.report.onset_time_s.has_value());
  EXPECT_FALSE(t.report.start_zone.has_value());
  EXPECT_LT(t.report.unbalanced_force_ratio, 1e-4);
  EXPECT_DOUBLE_EQ(t.report.runout_m, 0.0);
  // Sanity of the scales the thresholds came from.
  EXPECT_NEAR(t.report.d50_m, 0.68e-3, 0.05e-3);
  EXPECT_NEAR(t.report.displacement_threshold_m, 0.5 * t.report.d50_m, 1e-15);
  for (const FailureCheck& c : t.history) EXPECT_FALSE(c.significant && c.moving) << c.time_s;
}

// A fast but small adjustment (under a d50, as a face right after the
// cut) is not a failure however long it lasts; the same mass moving two d50
// is, from the first check at which it had moved one d50.
TEST(FailureMonitor, SmallFastAdjustmentIsNotAFailure) {
  LatticeSlope s;
  const SlopeGeometry& g = s.g;
  const std::size_t n = s.w.particles().size();
  FailureMonitor mon(g); // default: failure_displacement_d50 = 1
  EXPECT_EQ(mon.update(s.w, 0.001), SlopeState::undecided);
  const double d50 = mon.report().d50_m;
  const auto origin = s.w.particles().position;
  auto wedge = [&](const Vec3& x) { return x.x > g.crest_x() - 4e-3 && x.z > g.toe_height(); };
  const Vec3 dir{1, 0, 0};
  for (int k = 0; k < 5; ++k) { // five checks at 0.5 m/s, displaced 0.6 .. 0.68 d50
    for (std::size_t i = 0; i < n; ++i)
      if (wedge(origin[i])) s.move(i, (0.6 + 0.02 * k) * d50 * dir, 0.5 * dir);
    EXPECT_NE(mon.update(s.w, 0.002 + 0.001 * k), SlopeState::failed) << k;
  }
  for (int k = 0; k < 2; ++k) {
    for (std::size_t i = 0; i < n; ++i)
      if (wedge(origin[i])) s.move(i, (1.5 + k) * d50 * dir, 0.5 * dir);
    mon.update(s.w, 0.010 + 0.001 * k);
  }
  EXPECT_EQ(mon.state(), SlopeState::failed);
  ASSERT_TRUE(mon.report().onset_time_s.has_value());
  EXPECT_DOUBLE_EQ(*mon.report().onset_time_s, 0.010);
}

// (b) A 45-degree face with mu = mu_r = 0: failed, a slide that starts at
// the face and runs out beyond the toe.
TEST(FailureMonitor, FrictionlessSlopeFails) {
  // (The mass must also have moved one d50 on average: these grains are
  // large, d50 ~ 0.68 mm against a 4 mm face, so that takes a while.)
  const Trial t = run_trial(45, 0.0, 0.0, 100000, 40000);
  const FailureReport& r = t.report;
  ASSERT_EQ(t.state_at_decision, SlopeState::failed);
  EXPECT_EQ(r.state, SlopeState::failed);
  ASSERT_TRUE(r.onset_time_s.has_value());
  EXPECT_GT(*r.onset_time_s, 0.0);
  ASSERT_TRUE(r.start_zone.has_value());
  EXPECT_EQ(*r.start_zone, (ZoneId{SlopeZone::upper_face, 1}));
  EXPECT_TRUE(r.sliding_mass);
  EXPECT_GE(r.particles, 100u);
  EXPECT_GT(r.volume_share, 0.1);
  EXPECT_GT(r.volume_m3, 0.0);
  EXPECT_EQ(r.benches_crossed, (std::vector<int>{1}));
  EXPECT_GT(r.runout_m, 0.0);
  EXPECT_DOUBLE_EQ(r.runout_model_m, r.runout_m / s_red);
  EXPECT_GT(r.max_displacement_m, r.displacement_threshold_m);
  // The slip surface lies within the soil, under the original surface.
  ASSERT_FALSE(r.slip_surface.empty());
  const SlopeGeometry g(slope_with_face(45));
  for (const SectionPoint& p : r.slip_surface) {
    EXPECT_GE(p.z, 0.0);
    EXPECT_LE(p.z, g.z_surface(p.x) + 1e-9);
  }
}

} // namespace
} // namespace centridem
