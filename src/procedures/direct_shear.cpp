#include "procedures/direct_shear.hpp"
#include "procedures/specimen.hpp"

#include "core/errors.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace centridem {

namespace {
constexpr const char* kUpperWalls[] = {"top",      "upper_x0", "upper_x1",
                                       "upper_y0", "upper_y1", "plate_upper"};

void require(bool ok, const char* key, double v, const char* allowed) {
  if (!ok || !std::isfinite(v)) throw InputError(key, fmt::format("{:g}", v), allowed);
}

double plate_length(const ShearBox& b, double max_disp) {
  return b.plate_length_m > 0 ? b.plate_length_m : 1.1 * max_disp + 1e-9;
}
} // namespace

void validate(const DirectShearSpec& s) {
  require(s.box.length_m > 0, "shear.box.length_m", s.box.length_m, "must be > 0 [m]");
  require(s.box.width_m > 0, "shear.box.width_m", s.box.width_m, "must be > 0 [m]");
  require(s.box.height_m > 0, "shear.box.height_m", s.box.height_m, "must be > 0 [m]");
  require(s.box.plate_length_m >= 0, "shear.box.plate_length_m", s.box.plate_length_m,
          "must be >= 0 [m] (0 = automatic)");
  require(s.normal_stress_Pa > 0, "shear.normal_stresses_Pa", s.normal_stress_Pa,
          "must be > 0 [Pa]");
  require(s.shear_rate_m_per_s > 0, "shear.shear_rate_m_per_s", s.shear_rate_m_per_s,
          "must be > 0 [m/s]");
  require(s.max_shear_displacement_m > 0 && s.max_shear_displacement_m < s.box.length_m,
          "shear.max_shear_displacement_m", s.max_shear_displacement_m,
          "must be > 0 and below the box length [m]");
  if (s.box.plate_length_m > 0)
    require(s.box.plate_length_m >= s.max_shear_displacement_m, "shear.box.plate_length_m",
            s.box.plate_length_m, "must be at least shear.max_shear_displacement_m [m]");
  require(s.servo_gain_factor > 0 && s.servo_gain_factor <= 1, "shear.servo_gain_factor",
          s.servo_gain_factor, "must be in (0, 1]");
  require(s.servo_max_speed_m_per_s > 0, "shear.servo_max_speed_m_per_s", s.servo_max_speed_m_per_s,
          "must be > 0 [m/s]");
  require(s.consolidation_ratio > 0, "shear.consolidation_ratio", s.consolidation_ratio,
          "must be > 0");
  require(s.consolidation_stress_tolerance > 0, "shear.consolidation_stress_tolerance",
          s.consolidation_stress_tolerance, "must be > 0");
  require(s.consolidation_max_steps > 0, "shear.consolidation_max_steps",
          static_cast<double>(s.consolidation_max_steps), "must be > 0");
  require(s.record_interval_steps > 0, "shear.record_interval_steps",
          static_cast<double>(s.record_interval_steps), "must be > 0");
  validate(s.ball_wall, "shear.ball_wall");
  if (s.ball_ball_during_shear) validate(*s.ball_ball_during_shear, "shear.ball_ball_during_shear");
}

void add_shear_box(World& w, const ShearBox& b, const ContactProperties& ball_wall,
                   double max_shear_displacement_m) {
  const double L = b.length_m, W = b.width_m, H = b.height_m, h = 0.5 * H;
  const double P = plate_length(b, max_shear_displacement_m);
  auto rect = [&](const char* name, Vec3 c, Vec3 n, Vec3 u, double lu, double lv) {
    w.add_wall(Wall::rectangle(name, c, n, u, lu, lv), ball_wall);
  };
  // Lower box: z in [0, H/2]; upper box: z in [H/2, H]. Side walls are
  // rectangles exactly as tall as their half, so the halves can slide.
  rect("bottom", {L / 2, W / 2, 0}, {0, 0, 1}, {1, 0, 0}, L, W);
  rect("lower_x0", {0, W / 2, h / 2}, {1, 0, 0}, {0, 1, 0}, W, h);
  rect("lower_x1", {L, W / 2, h / 2}, {-1, 0, 0}, {0, 1, 0}, W, h);
  rect("lower_y0", {L / 2, 0, h / 2}, {0, 1, 0}, {1, 0, 0}, L, h);
  rect("lower_y1", {L / 2, W, h / 2}, {0, -1, 0}, {1, 0, 0}, L, h);
  rect("top", {L / 2, W / 2, H}, {0, 0, -1}, {1, 0, 0}, L, W);
  rect("upper_x0", {0, W / 2, h + h / 2}, {1, 0, 0}, {0, 1, 0}, W, h);
  rect("upper_x1", {L, W / 2, h + h / 2}, {-1, 0, 0}, {0, 1, 0}, W, h);
  rect("upper_y0", {L / 2, 0, h + h / 2}, {0, 1, 0}, {1, 0, 0}, L, h);
  rect("upper_y1", {L / 2, W, h + h / 2}, {0, -1, 0}, {1, 0, 0}, L, h);
  // The upper box moves in -x: where it overhangs the lower box (x < 0) the
  // lower plate closes the shear plane; where the lower box is uncovered
  // (x > L - d) the upper plate, travelling with the upper box, closes it.
  rect("plate_lower", {-P / 2, W / 2, h}, {0, 0, 1}, {1, 0, 0}, P, W);
  rect("plate_upper", {L + P / 2, W / 2, h}, {0, 0, -1}, {1, 0, 0}, P, W);
}

DirectShearResult run_direct_shear(World& w, const DirectShearSpec& s,
                                   const ShearProgress& progress) {
  validate(s);
  const auto t0 = std::chrono::steady_clock::now();
  const double area = s.box.length_m * s.box.width_m;
  const double target = s.normal_stress_Pa * area;
  // Spheres whose centres lie in the box may poke through its faces; with
  // 1 GPa walls that would fire them out. Pull each centre at least its
  // radius inside first (ball-ball overlaps this makes are relaxed below).
  {
    auto& P = w.particles_mut();
    const Vec3 hi{s.box.length_m, s.box.width_m, s.box.height_m};
    for (std::size_t i = 0; i < P.size(); ++i)
      for (int a = 0; a < 3; ++a)
        P.position[i][a] =
            std::clamp(P.position[i][a], P.radius[i], std::max(P.radius[i], hi[a] - P.radius[i]));
    w.particles_changed();
  }
  add_shear_box(w, s.box, s.ball_wall, s.max_shear_displacement_m);
  const std::size_t bottom = w.wall_index("bottom"), top = w.wall_index("top");
  std::vector<std::size_t> upper;
  for (const char* name : kUpperWalls) upper.push_back(w.wall_index(name));

  WallServo servo;
  servo.active = true;
  servo.direction = {0, 0, 1}; // the bottom wall pushes up into the specimen
  servo.target_force_N = target;
  servo.gain_factor = s.servo_gain_factor;
  servo.max_speed_m_per_s = s.servo_max_speed_m_per_s;
  w.set_wall_servo(bottom, servo);

  DirectShearResult r;
  r.target_normal_stress_Pa = s.normal_stress_Pa;
  auto normal_stress = [&] { return -dot(w.walls()[bottom].force, servo.direction) / area; };

  // Fit the specimen into the box: centres inside the box leave spheres
  // poking through the walls; push them in with calm cycles (velocities
  // zeroed, PFC `calm`) under a tolerant overlap guard.
  r.consolidation_steps += calm_into_walls(w);

  // Consolidation: upper box fixed, servo on the bottom wall.
  const long check = std::max<long>(100, s.record_interval_steps / 4);
  while (r.consolidation_steps < s.consolidation_max_steps) {
    w.cycle(check);
    r.consolidation_steps += check;
    const double err = std::abs(normal_stress() - s.normal_stress_Pa) / s.normal_stress_Pa;
    if (err < s.consolidation_stress_tolerance &&
        w.mean_unbalanced_force_ratio() < s.consolidation_ratio)
      break;
  }
  auto height = [&] { return w.walls()[top].point.z - w.walls()[bottom].point.z; };
  r.consolidated_height_m = height();
  r.consolidated_normal_stress_Pa = normal_stress();
  const long steps_before = w.step_count();

  // Shearing: contact defaults for new contacts (paper: no adhesion for
  // contacts made while shearing), then the upper box moves in -x.
  if (s.ball_ball_during_shear) w.set_ball_ball_defaults(*s.ball_ball_during_shear);
  for (std::size_t k : upper) w.set_wall_velocity(k, {-s.shear_rate_m_per_s, 0, 0});
  const double x0 = w.walls()[top].point.x;
  const double t_start = w.time();
  const double strain_base = s.strain == StrainDefinition::height ? s.box.height_m : s.box.length_m;
  const long sample = std::min<long>(10, s.record_interval_steps);
  for (;;) {
    // Stresses are averaged over the record interval (sampled every 10 steps).
    double sum_sigma = 0, sum_fx = 0;
    long samples = 0;
    for (long done = 0; done < s.record_interval_steps; done += sample) {
      w.cycle(std::min(sample, s.record_interval_steps - done));
      sum_sigma += normal_stress();
      for (std::size_t k : upper) sum_fx += w.walls()[k].force.x; // particles resist the -x motion
      ++samples;
    }
    ShearPoint p;
    p.step = w.step_count();
    p.time_s = w.time() - t_start;
    p.shear_displacement_m = x0 - w.walls()[top].point.x;
    p.shear_strain = p.shear_displacement_m / strain_base;
    p.shear_stress_Pa = sum_fx / static_cast<double>(samples) / area;
    p.normal_stress_Pa = sum_sigma / static_cast<double>(samples);
    p.vertical_displacement_m = height() - r.consolidated_height_m;
    const double zb = w.walls()[bottom].point.z, zt = w.walls()[top].point.z;
    p.porosity = w.measure_region(Box{{0, 0, zb}, {s.box.length_m, s.box.width_m, zt}}).porosity;
    r.curve.push_back(p);
    r.worst_normal_stress_deviation =
        std::max(r.worst_normal_stress_deviation,
                 std::abs(p.normal_stress_Pa - s.normal_stress_Pa) / s.normal_stress_Pa);
    if (p.shear_stress_Pa > r.peak_shear_stress_Pa) {
      r.peak_shear_stress_Pa = p.shear_stress_Pa;
      r.peak_strain = p.shear_strain;
    }
    if (progress) progress(p, r);
    if (p.shear_displacement_m >= s.max_shear_displacement_m) break;
  }
  for (std::size_t k : upper) w.set_wall_velocity(k, {});

  // Residual: mean over the last 20 % of the displacement.
  const double d_end = r.curve.back().shear_displacement_m;
  double sum = 0;
  int count = 0;
  for (const ShearPoint& p : r.curve)
    if (p.shear_displacement_m >= 0.8 * d_end) sum += p.shear_stress_Pa, ++count;
  r.residual_shear_stress_Pa = count ? sum / count : 0.0;

  // Particles that left the box (beyond a radius of slack).
  const auto& P = w.particles();
  const double d = d_end, L = s.box.length_m, W = s.box.width_m;
  const double zb = w.walls()[bottom].point.z, zt = w.walls()[top].point.z;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vec3& x = P.position[i];
    const double rr = P.radius[i];
    if (x.x < -d - rr || x.x > L + rr || x.y < -rr || x.y > W + rr || x.z < zb - rr ||
        x.z > zt + rr)
      ++r.particles_lost;
  }
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.particle_steps_per_s =
      static_cast<double>(P.size()) *
      static_cast<double>(w.step_count() - steps_before + r.consolidation_steps) / r.wall_seconds;
  return r;
}

MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& sigma, const std::vector<double>& tau) {
  MohrCoulombFit f;
  const std::size_t n = std::min(sigma.size(), tau.size());
  if (n < 2) return f;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sx += sigma[k], sy += tau[k], sxx += sigma[k] * sigma[k], sxy += sigma[k] * tau[k];
  }
  const double dn = static_cast<double>(n);
  const double den = dn * sxx - sx * sx;
  if (den == 0) return f;
  const double slope = (dn * sxy - sx * sy) / den;
  const double c = (sy - slope * sx) / dn;
  double ss_res = 0, ss_tot = 0;
  const double mean = sy / dn;
  for (std::size_t k = 0; k < n; ++k) {
    const double e = tau[k] - (c + slope * sigma[k]);
    ss_res += e * e;
    ss_tot += (tau[k] - mean) * (tau[k] - mean);
  }
  f.cohesion_Pa = c;
  f.friction_angle_deg = std::atan(slope) * 180.0 / std::numbers::pi;
  f.r_squared = ss_tot > 0 ? 1.0 - ss_res / ss_tot : 1.0;
  return f;
}

} // namespace centridem
