// Direct shear regressions on a reduced box (~1,000 particles, 6 x 6 x 3 mm):
// the servo holds the normal stress, no particle leaves the box, the peak is
// positive, and a frictionless assembly's friction angle is far below that
// of mu = 0.5 with rolling resistance. The shear rate is raised to
// keep CI short (20 mm/s); the paper-size runs use 200 mm/min (ctest -L long).
#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "physics/contact_law.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/specimen.hpp"

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <gtest/gtest.h>
#include <numbers>
#include <unistd.h>

using namespace centridem;

namespace {

struct Outcome {
  DirectShearResult result;
  double peak_angle_deg;
};

void small_box(World& world, const ContactProperties& ball_ball, double porosity = 0.40) {
  SpecimenSpec spec;
  spec.bins = {{0.4e-3, 0.6e-3, 1.0}};
  spec.porosity = porosity;
  spec.density_kg_m3 = paper::density_kg_m3;
  spec.seed = 11;
  spec.brick_size_m = {3e-3, 3e-3, 3e-3};
  spec.region = Box{{0, 0, 0}, {6e-3, 6e-3, 3e-3}};
  build_specimen(spec, world);
  world.set_ball_ball_defaults(ball_ball);
  world.set_body_field(BodyField::scaled_gravity(1.0, 1.0));
}

DirectShearSpec small_test(double sigma) {
  DirectShearSpec s;
  s.box = {6e-3, 6e-3, 3e-3, 0.0};
  s.normal_stress_Pa = sigma;
  s.shear_rate_m_per_s = 0.02;
  s.max_shear_displacement_m = 0.45e-3; // 15 % of the height: past the peak
  s.ball_wall = paper::ball_wall(0.0);
  s.record_interval_steps = 500;
  s.servo_integral_time_s = 2e-4; // as the examples (docs/shear.md)
  return s;
}

Outcome shear(const ContactProperties& ball_ball, double sigma) {
  WorldSettings ws;
  ws.local_damping = paper::local_damping;
  World world(ws);
  small_box(world, ball_ball);
  const DirectShearSpec s = small_test(sigma);
  Outcome o{run_direct_shear(world, s), 0.0};
  o.peak_angle_deg = std::atan(o.result.peak_shear_stress_Pa / sigma) * 180.0 / std::numbers::pi;
  return o;
}

} // namespace

TEST(DirectShear, ServoHoldsStressAndFrictionRaisesStrength) {
  ContactProperties sand = paper::ball_ball(0.0);
  ContactProperties frictionless = sand;
  frictionless.friction = 0.0;
  frictionless.rolling_friction = 0.0;
  const Outcome a = shear(sand, 100e3);
  const Outcome b = shear(frictionless, 100e3);
  for (const Outcome* o : {&a, &b}) {
    ASSERT_GT(o->result.curve.size(), 10u);
    EXPECT_EQ(o->result.particles_lost, 0u);
    EXPECT_NEAR(o->result.consolidated_normal_stress_Pa, 100e3, 1e3) << "servo at rest: 1 %";
    // Interval means while shearing 6x faster than the paper with ~1,000
    // particles, worst deviations (sand / frictionless) at 20 mm/s: 5.2 % /
    // 5.2 % with the proportional servo, 1.4 % / 4.0 % with the integral term
    // (Ti = 2e-4 s); bound 6 %. The 13,284-particle paper box at 200 mm/min is
    // held to 2 % (ctest -L long).
    EXPECT_LT(o->result.worst_normal_stress_deviation, 0.06) << "servo during shearing";
    EXPECT_GT(o->result.peak_shear_stress_Pa, 0.0);
  }
  // Frictional sand: tan(phi_peak) well above the frictionless assembly's.
  EXPECT_GT(a.peak_angle_deg, 20.0);
  EXPECT_LT(b.peak_angle_deg, a.peak_angle_deg - 10.0);
  RecordProperty("peak_angle_sand_deg", std::to_string(a.peak_angle_deg));
  RecordProperty("peak_angle_frictionless_deg", std::to_string(b.peak_angle_deg));
  std::printf("peak friction angle: sand %.1f deg, frictionless %.1f deg; worst sigma deviation "
              "%.3f / %.3f\n",
              a.peak_angle_deg, b.peak_angle_deg, a.result.worst_normal_stress_deviation,
              b.result.worst_normal_stress_deviation);
}

// Preparation (docs/shear.md): a loose specimen (porosity 0.50 ignoring
// overlaps, no contacts) consolidated with the material itself stays loose;
// consolidated frictionless it packs denser, and then shears as the material:
// every contact carries mu = 0.5 and mu_r = 0.16 from the start of shearing,
// and the denser specimen is stronger. Measured (100 kPa, 0.25 mm of shear):
// porosity 0.499 / 0.421, height 2.99 / 2.59 mm, peak tau 0.51 / 1.10 sigma.
TEST(DirectShear, FrictionlessConsolidationPacksDenserThenShearsAsTheMaterial) {
  const ContactProperties sand = paper::ball_ball(0.0);
  ContactProperties smooth = sand;
  smooth.friction = 0.0;
  smooth.rolling_friction = 0.0;
  WorldSettings ws;
  ws.local_damping = paper::local_damping;
  DirectShearSpec s = small_test(100e3);
  s.max_shear_displacement_m = 0.25e-3;
  World loose(ws), dense(ws);
  small_box(loose, sand, 0.50);
  small_box(dense, sand, 0.50);
  const DirectShearResult a = run_direct_shear(loose, s);
  s.ball_ball = sand;
  s.ball_ball_during_consolidation = smooth;
  const DirectShearResult b = run_direct_shear(dense, s);
  std::printf("consolidated porosity %.4f (material) / %.4f (frictionless); height %.3f / %.3f mm; "
              "peak tau / sigma %.3f / %.3f; worst sigma deviation %.3f / %.3f\n",
              a.consolidated_porosity, b.consolidated_porosity, a.consolidated_height_m * 1e3,
              b.consolidated_height_m * 1e3, a.peak_shear_stress_Pa / 100e3,
              b.peak_shear_stress_Pa / 100e3, a.worst_normal_stress_deviation,
              b.worst_normal_stress_deviation);
  EXPECT_GT(a.consolidated_porosity, 0.0);
  EXPECT_LT(b.consolidated_porosity, a.consolidated_porosity - 0.02);
  EXPECT_LT(b.consolidated_height_m, a.consolidated_height_m);
  EXPECT_EQ(b.particles_lost, 0u);
  EXPECT_EQ(a.settling_steps, 0);
  EXPECT_GT(b.settling_steps, 0) << "settles with the material before shearing";
  EXPECT_LT(b.worst_normal_stress_deviation, 0.06);
  EXPECT_GT(b.peak_shear_stress_Pa, 1.1 * a.peak_shear_stress_Pa);
  EXPECT_EQ(dense.ball_ball_defaults().friction, sand.friction);
  const auto contacts = dense.ball_ball_contacts();
  ASSERT_GT(contacts.size(), 100u);
  for (const ContactView& c : contacts) {
    ASSERT_EQ(dense.property_set(c.properties).friction, sand.friction);
    ASSERT_EQ(dense.property_set(c.properties).rolling_friction, sand.rolling_friction);
  }
}

// The humid example packs without adhesion (examples/paper/shear_humid.toml,
// docs/shear.md "Preparation"): its specimen is then the dry one, step for
// step, and F0 arrives on every contact at the switch, before shearing. The
// dry and the humid sets differ only by the adhesion (a paired comparison).
TEST(DirectShear, HumidSpecimenPackedWithoutAdhesionIsTheDrySpecimen) {
  ContactProperties dry = paper::ball_ball(0.0);
  dry.model = ContactModel::rrlinear;
  const ContactProperties humid = paper::ball_ball(1.2e-4);
  WorldSettings ws;
  ws.local_damping = paper::local_damping;
  DirectShearSpec s = small_test(100e3);
  s.max_shear_displacement_m = 0.02e-3;
  World a(ws), b(ws);
  small_box(a, dry);
  small_box(b, humid);
  s.ball_ball = dry;
  s.ball_ball_during_consolidation = dry;
  s.ball_ball_during_consolidation->friction = 0.2;
  s.ball_ball_during_consolidation->rolling_friction = 0.0;
  // Every consolidation check (steps, bottom-wall stress, unbalanced-force ratio).
  std::vector<ConsolidationState> ca, cb;
  DirectShearCheckpoints cka, ckb; // no checkpoint files
  cka.consolidation_progress = [&](const ConsolidationState& c) { ca.push_back(c); };
  ckb.consolidation_progress = [&](const ConsolidationState& c) { cb.push_back(c); };
  const DirectShearResult ra = run_direct_shear(a, s, {}, cka);
  s.ball_ball = humid;
  s.ball_ball_during_shear = paper::ball_ball(0.0); // F0 only for contacts made before shearing
  s.ball_ball_during_consolidation = humid;
  s.ball_ball_during_consolidation->friction = 0.2;
  s.ball_ball_during_consolidation->rolling_friction = 0.0;
  s.ball_ball_during_consolidation->attraction_force_N = 0.0;
  const DirectShearResult rb = run_direct_shear(b, s, {}, ckb);
  const long packed = ra.consolidation_steps - ra.settling_steps;
  std::printf("packed in %ld / %ld steps, then settled in %ld / %ld; porosity %.5f / %.5f (dry / "
              "humid)\n",
              packed, rb.consolidation_steps - rb.settling_steps, ra.settling_steps,
              rb.settling_steps, ra.consolidated_porosity, rb.consolidated_porosity);
  // The same packing, bit for bit, up to the switch: the same stress and
  // unbalanced-force ratio at every check.
  EXPECT_GT(ra.settling_steps, 0);
  EXPECT_EQ(packed, rb.consolidation_steps - rb.settling_steps);
  std::size_t checks = 0;
  for (std::size_t k = 0; k < std::min(ca.size(), cb.size()) && ca[k].steps <= packed; ++k) {
    ++checks;
    ASSERT_EQ(ca[k].steps, cb[k].steps);
    ASSERT_EQ(ca[k].normal_stress_Pa, cb[k].normal_stress_Pa) << "step " << ca[k].steps;
    ASSERT_EQ(ca[k].unbalanced_force_ratio, cb[k].unbalanced_force_ratio) << "step " << ca[k].steps;
  }
  EXPECT_GT(checks, 10u);
  // Then the adhesion: every contact that existed at the switch carries F0.
  std::size_t adhesive = 0;
  for (const ContactView& c : b.ball_ball_contacts())
    if (b.property_set(c.properties).attraction_force_N == humid.attraction_force_N) ++adhesive;
  EXPECT_GT(adhesive, 100u);
  EXPECT_EQ(b.ball_ball_defaults().attraction_force_N, 0.0)
      << "none on contacts made while shearing";
  ASSERT_FALSE(ra.curve.empty());
  ASSERT_FALSE(rb.curve.empty());
  EXPECT_NE(ra.curve.front().shear_stress_Pa, rb.curve.front().shear_stress_Pa);
}

TEST(DirectShear, MohrCoulombFitRecoversALine) {
  const std::vector<double> s{40e3, 60e3, 80e3, 100e3, 120e3};
  std::vector<double> t;
  for (double v : s) t.push_back(5e3 + v * std::tan(32.0 * std::numbers::pi / 180.0));
  const MohrCoulombFit f = fit_mohr_coulomb(s, t);
  EXPECT_NEAR(f.cohesion_Pa, 5e3, 1e-6);
  EXPECT_NEAR(f.friction_angle_deg, 32.0, 1e-9);
  EXPECT_NEAR(f.r_squared, 1.0, 1e-12);
}

// The unload-reload loop on a simple cubic lattice (8 x 8 columns of 6 equal
// spheres, frictionless walls, no gravity): every column is a chain of 5
// ball-ball and 2 ball-wall linear springs carrying sigma (2R)^2, so the
// constrained modulus is exactly h / ((2R)^2 (5/kn_bb + 2/kn_bw)) on both legs
// (about 267 MPa), with no hysteresis. Measured: within 0.15 % (bound 1 %). The affine
// modulus at consolidation is the ball-ball springs' alone (below).
TEST(DirectShear, UnloadReloadOfACubicLatticeGivesItsSpringChainModulus) {
  const double R = 0.25e-3, sigma = 50e3;
  const int columns = 8, layers = 6;
  WorldSettings ws;
  ws.local_damping = paper::local_damping;
  World world(ws);
  for (int i = 0; i < columns; ++i)
    for (int j = 0; j < columns; ++j)
      for (int k = 0; k < layers; ++k)
        world.add_particle({R * (1 + 2 * i), R * (1 + 2 * j), R * (1 + 2 * k)}, R,
                           paper::density_kg_m3);
  const ContactProperties ball_ball = paper::ball_ball(0.0);
  world.set_ball_ball_defaults(ball_ball);
  DirectShearSpec s = small_test(sigma);
  s.box = {2 * R * columns, 2 * R * columns, 2 * R * layers, 0.0};
  s.max_shear_displacement_m = 1e-6;
  s.unload_reload_fraction = 0.5;
  const DirectShearResult r = run_direct_shear(world, s);
  const UnloadReload& u = r.unload_reload;
  ASSERT_TRUE(u.done);
  // The springs, from the law's own stiffness rule (kn = pi r^2 E* / L).
  ContactGeometry g{};
  g.contact_radius_m = R, g.contact_length_m = 2 * R, g.rolling_radius_m = R / 2;
  const double kn_bb = contact_stiffness(ball_ball, g).kn;
  g.contact_length_m = R, g.rolling_radius_m = R;
  const double kn_bw = contact_stiffness(s.ball_wall, g).kn;
  const double compliance = 4 * R * R * ((layers - 1) / kn_bb + 2 / kn_bw); // [m/Pa]
  const double expected_unloading = u.loaded_height_m / compliance;
  const double expected_reloading = u.unloaded_height_m / compliance;
  EXPECT_NEAR(u.unloaded_normal_stress_Pa, 0.5 * sigma, 0.01 * sigma);
  EXPECT_NEAR(u.reloaded_normal_stress_Pa, sigma, 0.01 * sigma);
  EXPECT_NEAR(u.unloading_modulus_Pa(), expected_unloading, 0.01 * expected_unloading);
  EXPECT_NEAR(u.reloading_modulus_Pa(), expected_reloading, 0.01 * expected_reloading);
  // Elastic: the loop closes (heights at the two loaded states within 1 % of
  // the rebound, after correcting for their stresses' difference).
  const double rebound = u.unloaded_height_m - u.loaded_height_m;
  const double closure = u.reloaded_height_m - u.loaded_height_m +
                         (u.reloaded_normal_stress_Pa - u.loaded_normal_stress_Pa) * compliance;
  EXPECT_LT(std::abs(closure), 0.01 * rebound);
  // The affine modulus when consolidated: the 5 x 64 vertical ball-ball springs, each of
  // branch 2R - delta (delta = sigma (2R)^2 / kn_bb), over the specimen's volume; the walls'
  // springs are left out, the horizontal contacts have n_z = 0.
  const double branch = 2 * R - sigma * 4 * R * R / kn_bb;
  const double expected_affine = columns * columns * (layers - 1) * kn_bb * branch * branch /
                                 (s.box.length_m * s.box.width_m * r.consolidated_height_m);
  EXPECT_NEAR(r.consolidated_affine_modulus_Pa, expected_affine, 0.01 * expected_affine);
  std::printf("lattice affine modulus: %.2f MPa measured, %.2f MPa expected\n",
              r.consolidated_affine_modulus_Pa / 1e6, expected_affine / 1e6);
  std::printf("lattice unload-reload: %.2f / %.2f MPa measured, %.2f MPa expected; rebound "
              "%.3f um, closure %.4f um\n",
              u.unloading_modulus_Pa() / 1e6, u.reloading_modulus_Pa() / 1e6,
              expected_unloading / 1e6, rebound * 1e6, closure * 1e6);
}

TEST(DirectShear, BadSpecIsRejected) {
  DirectShearSpec s;
  s.ball_wall = paper::ball_wall();
  s.max_shear_displacement_m = 0.02; // longer than the 13.2 mm box
  EXPECT_THROW(validate(s), InputError);
}

// A test stopped by SIGINT (once in consolidation, once while shearing) and
// resumed each time in a fresh World from its checkpoint ends bit for bit like
// one that never stopped: same curve, same final positions. The specimen is
// prepared with other properties than it is sheared with, so the switch at
// the start of shearing happens after a resume, and it runs the unload-reload
// loop, stopped once in its unloading leg.
TEST(DirectShear, StoppedAndResumedTestEndsBitForBitLikeAnUninterruptedOne) {
  const ContactProperties sand = paper::ball_ball(1.2e-4);
  DirectShearSpec s = small_test(100e3);
  s.max_shear_displacement_m = 0.1e-3;
  s.ball_ball_during_shear = paper::ball_ball(0.0); // the humid rule: F0 only before shearing
  s.ball_ball = sand; // prepared with mu = 0.2, sheared as the material (crosses a resume)
  s.ball_ball_during_consolidation = sand;
  s.ball_ball_during_consolidation->friction = 0.2;
  s.unload_reload_fraction = 0.9;
  WorldSettings ws;
  ws.local_damping = paper::local_damping;

  World a(ws);
  small_box(a, sand);
  const DirectShearResult ra = run_direct_shear(a, s);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("centridem_shear_resume_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  DirectShearCheckpoints ck{(dir / "checkpoint.bin").string(), {}};
  ck.policy.interval_min = 0;
  install_stop_handlers();
  int stops = 0;
  DirectShearResult rb;
  std::vector<Vec3> final_b;
  for (int part = 0;; ++part) {
    World b(ws);
    if (part == 0) small_box(b, sand);
    // Stop 1: at the start of consolidation; stop 2: in the loop's unloading
    // leg; stop 3: while shearing.
    const long stop_at = part == 2 ? ra.curve[4].step : -1;
    const ShearProgress watch = [&](const ShearPoint& p, const DirectShearResult&) {
      if (stop_at > 0 && p.step >= stop_at) set_stop_signal(SIGINT);
    };
    ck.consolidation_progress = [&](const ConsolidationState& c) {
      if (part == 1 && c.steps > ra.consolidation_steps + 300) set_stop_signal(SIGINT);
    };
    if (part == 0) {
      // Consolidation has no progress callback: ask to stop from the start;
      // the test writes its checkpoint at the first pending rebuild.
      set_stop_signal(SIGINT);
    }
    try {
      rb = run_direct_shear(b, s, watch, ck);
      final_b = b.particles().position;
      set_stop_signal(0);
      break;
    } catch (const Interrupted& e) {
      set_stop_signal(0);
      ++stops;
      ASSERT_TRUE(std::filesystem::exists(ck.path)) << e.what();
    }
    ASSERT_LT(part, 5);
  }
  EXPECT_GE(stops, 3);
  EXPECT_TRUE(rb.resumed);
  EXPECT_FALSE(std::filesystem::exists(ck.path)) << "a finished test removes its checkpoint";
  ASSERT_EQ(ra.curve.size(), rb.curve.size());
  for (std::size_t k = 0; k < ra.curve.size(); ++k) {
    EXPECT_EQ(ra.curve[k].step, rb.curve[k].step);
    EXPECT_EQ(ra.curve[k].shear_stress_Pa, rb.curve[k].shear_stress_Pa) << k;
    EXPECT_EQ(ra.curve[k].normal_stress_Pa, rb.curve[k].normal_stress_Pa) << k;
    EXPECT_EQ(ra.curve[k].vertical_displacement_m, rb.curve[k].vertical_displacement_m) << k;
  }
  EXPECT_EQ(ra.consolidation_steps, rb.consolidation_steps);
  EXPECT_EQ(ra.peak_shear_stress_Pa, rb.peak_shear_stress_Pa);
  ASSERT_TRUE(ra.unload_reload.done && rb.unload_reload.done);
  EXPECT_EQ(ra.unload_reload.steps, rb.unload_reload.steps);
  EXPECT_EQ(ra.unload_reload.unloaded_height_m, rb.unload_reload.unloaded_height_m);
  EXPECT_EQ(ra.unload_reload.reloaded_normal_stress_Pa, rb.unload_reload.reloaded_normal_stress_Pa);
  // Final positions: the particle order is the same (both rebuilt at the
  // same steps), so compare array to array.
  ASSERT_EQ(a.particles().size(), final_b.size());
  EXPECT_EQ(
      0, std::memcmp(a.particles().position.data(), final_b.data(), final_b.size() * sizeof(Vec3)));
  std::filesystem::remove_all(dir);
}
