#include "procedures/direct_shear.hpp"
#include "procedures/specimen.hpp"

#include "base/errors.hpp"
#include "io/checkpoint.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <numbers>

namespace centridem {

using json = nlohmann::json;

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
  require(s.servo_integral_time_s >= 0, "shear.servo_integral_time_s", s.servo_integral_time_s,
          "must be >= 0 [s] (0: proportional only)");
  require(s.servo_max_speed_m_per_s > 0, "shear.servo_max_speed_m_per_s", s.servo_max_speed_m_per_s,
          "must be > 0 [m/s]");
  require(s.consolidation_ratio > 0, "shear.consolidation_ratio", s.consolidation_ratio,
          "must be > 0");
  require(s.consolidation_stress_tolerance > 0, "shear.consolidation_stress_tolerance",
          s.consolidation_stress_tolerance, "must be > 0");
  require(s.consolidation_max_steps > 0, "shear.consolidation_max_steps",
          static_cast<double>(s.consolidation_max_steps), "must be > 0");
  require(s.unload_reload_fraction >= 0 && s.unload_reload_fraction < 1,
          "shear.unload_reload_fraction", s.unload_reload_fraction,
          "in [0, 1): 0 for no unload-reload loop, else the fraction of the normal stress the "
          "loop unloads to [-]");
  require(s.record_interval_steps > 0, "shear.record_interval_steps",
          static_cast<double>(s.record_interval_steps), "must be > 0");
  validate(s.ball_wall, "shear.ball_wall");
  if (s.ball_ball_during_shear) validate(*s.ball_ball_during_shear, "shear.ball_ball_during_shear");
  if (s.ball_ball_during_consolidation) {
    validate(*s.ball_ball_during_consolidation, "preparation.during_compaction");
    validate(s.ball_ball, "contact.ball_ball");
  }
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

namespace {

// The test's progress, kept in the checkpoint's procedure blob.
struct ShearProgressState {
  int phase = 0;                       // 0: consolidation; 1: shearing
  long consolidation_first_step = 0;   // world step when consolidation cycling began
  long fit_steps = 0;                  // calm steps that fitted the specimen into the box
  long shear_first_step = 0;           // world step when shearing began
  long switch_step = -1;               // prepared specimens: world step when the material came in
  int unload_reload_leg = 0;           // 0: not begun; 1: unloading; 2: reloading
  long leg_first_step = -1;            // world step when the current unload-reload leg began
  double shear_reference_height_m = 0; // height when shearing began [m]
  double x0 = 0;                       // top wall x at the start of shearing [m]
  double t_start = 0;                  // world time at the start of shearing [s]
  double sum_sigma = 0, sum_fx = 0;    // sums over the current record interval
  long samples = 0;
  double wall_seconds = 0;                        // spent before the last resume [s]
  double particle_steps = 0, cycling_seconds = 0; // before the last resume
  DirectShearResult r;
};

std::string save_state(const ShearProgressState& p, double wall_seconds_now,
                       const CheckpointedCycling& cyc) {
  json curve = json::array();
  for (const ShearPoint& q : p.r.curve)
    curve.push_back({q.step, q.time_s, q.shear_displacement_m, q.shear_strain, q.shear_stress_Pa,
                     q.normal_stress_Pa, q.vertical_displacement_m, q.porosity});
  const DirectShearResult& r = p.r;
  return json{{"format", "centridem-direct-shear"},
              {"version", 1},
              {"phase", p.phase},
              {"consolidation_first_step", p.consolidation_first_step},
              {"fit_steps", p.fit_steps},
              {"shear_first_step", p.shear_first_step},
              {"switch_step", p.switch_step},
              {"x0", p.x0},
              {"t_start", p.t_start},
              {"sum_sigma", p.sum_sigma},
              {"sum_fx", p.sum_fx},
              {"samples", p.samples},
              {"wall_seconds", p.wall_seconds + wall_seconds_now},
              {"particle_steps", p.particle_steps + cyc.particle_steps()},
              {"cycling_seconds", p.cycling_seconds + cyc.cycling_seconds()},
              {"consolidation_steps", r.consolidation_steps},
              {"consolidated_height_m", r.consolidated_height_m},
              {"consolidated_normal_stress_Pa", r.consolidated_normal_stress_Pa},
              {"consolidated_porosity", r.consolidated_porosity},
              {"consolidated_coordination_number", r.consolidated_coordination_number},
              {"consolidated_affine_modulus_Pa", r.consolidated_affine_modulus_Pa},
              {"settling_steps", r.settling_steps},
              {"unload_reload_leg", p.unload_reload_leg},
              {"leg_first_step", p.leg_first_step},
              {"shear_reference_height_m", p.shear_reference_height_m},
              {"unload_reload",
               {r.unload_reload.done, r.unload_reload.loaded_height_m,
                r.unload_reload.loaded_normal_stress_Pa, r.unload_reload.unloaded_height_m,
                r.unload_reload.unloaded_normal_stress_Pa, r.unload_reload.reloaded_height_m,
                r.unload_reload.reloaded_normal_stress_Pa, r.unload_reload.steps}},
              {"peak_shear_stress_Pa", r.peak_shear_stress_Pa},
              {"peak_strain", r.peak_strain},
              {"worst_normal_stress_deviation", r.worst_normal_stress_deviation},
              {"curve", curve}}
      .dump();
}

ShearProgressState load_state(const std::string& blob, const std::string& path) {
  ShearProgressState p;
  try {
    const json j = json::parse(blob);
    if (j.at("format") != "centridem-direct-shear")
      throw InputError(path + ": not a direct-shear checkpoint");
    p.phase = j.at("phase");
    p.consolidation_first_step = j.at("consolidation_first_step");
    p.fit_steps = j.at("fit_steps");
    p.shear_first_step = j.at("shear_first_step");
    p.switch_step = j.value("switch_step", -1L); // absent before 2026-12
    p.x0 = j.at("x0");
    p.t_start = j.at("t_start");
    p.sum_sigma = j.at("sum_sigma");
    p.sum_fx = j.at("sum_fx");
    p.samples = j.at("samples");
    p.wall_seconds = j.at("wall_seconds");
    p.particle_steps = j.at("particle_steps");
    p.cycling_seconds = j.at("cycling_seconds");
    DirectShearResult& r = p.r;
    r.consolidation_steps = j.at("consolidation_steps");
    r.consolidated_height_m = j.at("consolidated_height_m");
    r.consolidated_normal_stress_Pa = j.at("consolidated_normal_stress_Pa");
    r.consolidated_porosity = j.value("consolidated_porosity", 0.0); // absent before 2026-12
    r.consolidated_coordination_number = j.value("consolidated_coordination_number", 0.0);
    r.consolidated_affine_modulus_Pa = j.value("consolidated_affine_modulus_Pa", 0.0);
    r.settling_steps = j.value("settling_steps", 0L);
    // Absent before the unload-reload loop (2026-12-03): none, and shearing
    // measured from the consolidated height.
    p.unload_reload_leg = j.value("unload_reload_leg", 0);
    p.leg_first_step = j.value("leg_first_step", -1L);
    p.shear_reference_height_m = j.value("shear_reference_height_m", r.consolidated_height_m);
    if (j.contains("unload_reload")) {
      const json& u = j.at("unload_reload");
      UnloadReload& ur = r.unload_reload;
      ur.done = u.at(0);
      ur.loaded_height_m = u.at(1);
      ur.loaded_normal_stress_Pa = u.at(2);
      ur.unloaded_height_m = u.at(3);
      ur.unloaded_normal_stress_Pa = u.at(4);
      ur.reloaded_height_m = u.at(5);
      ur.reloaded_normal_stress_Pa = u.at(6);
      ur.steps = u.at(7);
    }
    r.peak_shear_stress_Pa = j.at("peak_shear_stress_Pa");
    r.peak_strain = j.at("peak_strain");
    r.worst_normal_stress_deviation = j.at("worst_normal_stress_deviation");
    for (const json& q : j.at("curve"))
      r.curve.push_back({q.at(0), q.at(1), q.at(2), q.at(3), q.at(4), q.at(5), q.at(6), q.at(7)});
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: the direct shear test's progress record is unreadable ({})",
                                 path, e.what()));
  }
  return p;
}

} // namespace

DirectShearResult run_direct_shear(World& w, const DirectShearSpec& s,
                                   const ShearProgress& progress,
                                   const DirectShearCheckpoints& ck) {
  validate(s);
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const double area = s.box.length_m * s.box.width_m;
  ShearProgressState pr;
  const bool resume = !ck.path.empty() && std::filesystem::exists(ck.path);
  if (resume) {
    pr = load_state(read_checkpoint(w, ck.path).procedure_state, ck.path);
    pr.r.resumed = true;
  } else {
    // Spheres whose centres lie in the box may poke through its faces; with
    // 1 GPa walls that would fire them out. Pull each centre at least its
    // radius inside first (ball-ball overlaps this makes are relaxed below).
    auto& P = w.particles_mut();
    const Vec3 hi{s.box.length_m, s.box.width_m, s.box.height_m};
    for (std::size_t i = 0; i < P.size(); ++i)
      for (int a = 0; a < 3; ++a)
        P.position[i][a] =
            std::clamp(P.position[i][a], P.radius[i], std::max(P.radius[i], hi[a] - P.radius[i]));
    w.particles_changed();
    add_shear_box(w, s.box, s.ball_wall, s.max_shear_displacement_m);
  }
  const std::size_t bottom = w.wall_index("bottom"), top = w.wall_index("top");
  std::vector<std::size_t> upper;
  for (const char* name : kUpperWalls) upper.push_back(w.wall_index(name));
  const Vec3 servo_direction{0, 0, 1}; // the bottom wall pushes up into the specimen
  auto normal_stress = [&] { return -dot(w.walls()[bottom].force, servo_direction) / area; };
  auto height = [&] { return w.walls()[top].point.z - w.walls()[bottom].point.z; };
  auto porosity_now = [&] {
    return w
        .measure_region(Box{{0, 0, w.walls()[bottom].point.z},
                            {s.box.length_m, s.box.width_m, w.walls()[top].point.z}})
        .porosity;
  };
  DirectShearResult& r = pr.r;

  if (!resume) {
    WallServo servo;
    servo.active = true;
    servo.direction = servo_direction;
    servo.target_force_N = s.normal_stress_Pa * area;
    servo.gain_factor = s.servo_gain_factor;
    servo.max_speed_m_per_s = s.servo_max_speed_m_per_s;
    servo.integral_time_s = s.servo_integral_time_s;
    w.set_wall_servo(bottom, servo);
    r.target_normal_stress_Pa = s.normal_stress_Pa;
    if (s.ball_ball_during_consolidation)
      assign_ball_ball_contacts(w, *s.ball_ball_during_consolidation);
    // Fit the specimen into the box: centres inside the box leave spheres
    // poking through the walls; push them in with calm cycles (velocities
    // zeroed, PFC `calm`) under a tolerant overlap guard.
    pr.fit_steps = r.consolidation_steps = calm_into_walls(w);
    pr.consolidation_first_step = w.step_count();
  }
  r.target_normal_stress_Pa = s.normal_stress_Pa;

  // Every decision is taken at a check, a fixed number of steps into its
  // phase, so a resume mid-chunk finishes the chunk first.
  const long check = std::max<long>(100, s.record_interval_steps / 4);
  CheckpointedCycling cyc(w, ck.path, ck.policy, [&] { return save_state(pr, seconds(), cyc); });

  // Consolidation: upper box fixed, servo on the bottom wall.
  if (pr.phase == 0) {
    const long fit_steps = pr.fit_steps;
    const bool prepared = s.ball_ball_during_consolidation.has_value();
    const bool loop = s.unload_reload_fraction > 0;
    // The servo's target: the normal stress, or the loop's lowered one.
    auto set_target = [&](double sigma_Pa) {
      WallServo servo = w.walls()[bottom].servo;
      servo.target_force_N = sigma_Pa * area;
      servo.error_integral_N_s = 0;
      w.set_wall_servo(bottom, servo);
    };
    auto record_consolidated = [&] {
      r.settling_steps = pr.switch_step < 0 ? 0 : w.step_count() - pr.switch_step;
      r.consolidated_height_m = height();
      r.consolidated_porosity = porosity_now();
      r.consolidated_coordination_number = w.measure().coordination_number;
      r.consolidated_normal_stress_Pa = normal_stress();
      r.consolidated_affine_modulus_Pa =
          w.affine_modulus_Pa(Box{{0, 0, w.walls()[bottom].point.z},
                                  {s.box.length_m, s.box.width_m, w.walls()[top].point.z}},
                              2);
    };
    // Consolidation, then (prepared specimens) settling with the material,
    // then (optionally) the unload-reload loop's two legs.
    for (;;) {
      const long into = w.step_count() - pr.consolidation_first_step;
      const double target = pr.unload_reload_leg == 1
                                ? s.unload_reload_fraction * s.normal_stress_Pa
                                : s.normal_stress_Pa;
      const bool out_of_steps =
          pr.unload_reload_leg > 0 ? w.step_count() - pr.leg_first_step >= s.consolidation_max_steps
          : pr.switch_step < 0     ? fit_steps + into >= s.consolidation_max_steps
                                   : w.step_count() - pr.switch_step >= s.consolidation_max_steps;
      bool done = out_of_steps;
      if (!out_of_steps) {
        cyc.advance(check - into % check);
        const long so_far = fit_steps + (w.step_count() - pr.consolidation_first_step);
        if (pr.unload_reload_leg == 0) r.consolidation_steps = so_far;
        const double sigma = normal_stress();
        const double err = std::abs(sigma - target) / target;
        const double ratio = w.mean_unbalanced_force_ratio();
        if (ck.consolidation_progress) ck.consolidation_progress({so_far, sigma, ratio});
        done = err < s.consolidation_stress_tolerance && ratio < s.consolidation_ratio;
      }
      if (done && prepared && pr.switch_step < 0) {
        // Packed: every contact and the defaults become the material. The
        // servo's integral carried the packing's creep; it starts again from
        // zero, and the specimen settles with its own properties before
        // shearing (else the stiffer packing meets a servo still pushing).
        assign_ball_ball_contacts(w, s.ball_ball);
        WallServo servo = w.walls()[bottom].servo;
        servo.error_integral_N_s = 0;
        w.set_wall_servo(bottom, servo);
        pr.switch_step = w.step_count();
        done = false;
      } else if (done && loop && pr.unload_reload_leg < 2) {
        UnloadReload& ur = r.unload_reload;
        if (pr.unload_reload_leg == 0) { // consolidated: unload
          record_consolidated();
          ur.loaded_height_m = r.consolidated_height_m;
          ur.loaded_normal_stress_Pa = r.consolidated_normal_stress_Pa;
          set_target(s.unload_reload_fraction * s.normal_stress_Pa);
        } else { // unloaded: reload
          ur.unloaded_height_m = height();
          ur.unloaded_normal_stress_Pa = normal_stress();
          set_target(s.normal_stress_Pa);
        }
        ++pr.unload_reload_leg;
        pr.leg_first_step = w.step_count();
        done = false;
      }
      if (done) break;
      cyc.at_check();
    }
    if (loop) {
      UnloadReload& ur = r.unload_reload;
      ur.reloaded_height_m = height();
      ur.reloaded_normal_stress_Pa = normal_stress();
      ur.steps = w.step_count() - pr.consolidation_first_step - (r.consolidation_steps - fit_steps);
      ur.done = true;
    } else {
      record_consolidated();
    }
    pr.shear_reference_height_m = height();
    // Shearing: contact defaults for new contacts (paper: no adhesion for
    // contacts made while shearing), then the upper box moves in -x.
    if (s.ball_ball_during_shear) w.set_ball_ball_defaults(*s.ball_ball_during_shear);
    for (std::size_t k : upper) w.set_wall_velocity(k, {-s.shear_rate_m_per_s, 0, 0});
    pr.x0 = w.walls()[top].point.x;
    pr.t_start = w.time();
    pr.shear_first_step = w.step_count();
    pr.phase = 1;
    cyc.write_now();
  }

  // Shearing. Stresses are averaged over each record interval, sampled every
  // 10 steps.
  const double strain_base = s.strain == StrainDefinition::height ? s.box.height_m : s.box.length_m;
  const long rec = s.record_interval_steps;
  const long sample = std::min<long>(10, rec);
  const bool finished_before =
      !r.curve.empty() && r.curve.back().shear_displacement_m >= s.max_shear_displacement_m;
  while (!finished_before) {
    const long into = (w.step_count() - pr.shear_first_step) % rec;
    cyc.advance(std::min(rec, (into / sample + 1) * sample) - into);
    pr.sum_sigma += normal_stress();
    for (std::size_t k : upper) pr.sum_fx += w.walls()[k].force.x; // particles resist the -x motion
    ++pr.samples;
    if ((w.step_count() - pr.shear_first_step) % rec != 0) continue;
    ShearPoint p;
    p.step = w.step_count();
    p.time_s = w.time() - pr.t_start;
    p.shear_displacement_m = pr.x0 - w.walls()[top].point.x;
    p.shear_strain = p.shear_displacement_m / strain_base;
    p.shear_stress_Pa = pr.sum_fx / static_cast<double>(pr.samples) / area;
    p.normal_stress_Pa = pr.sum_sigma / static_cast<double>(pr.samples);
    p.vertical_displacement_m = height() - pr.shear_reference_height_m;
    const double zb = w.walls()[bottom].point.z, zt = w.walls()[top].point.z;
    p.porosity = w.measure_region(Box{{0, 0, zb}, {s.box.length_m, s.box.width_m, zt}}).porosity;
    pr.sum_sigma = pr.sum_fx = 0;
    pr.samples = 0;
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
    cyc.at_check();
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
  r.particles_lost = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vec3& x = P.position[i];
    const double rr = P.radius[i];
    if (x.x < -d - rr || x.x > L + rr || x.y < -rr || x.y > W + rr || x.z < zb - rr ||
        x.z > zt + rr)
      ++r.particles_lost;
  }
  r.wall_seconds = pr.wall_seconds + seconds();
  const double cyc_s = pr.cycling_seconds + cyc.cycling_seconds();
  r.particle_steps_per_s = cyc_s > 0 ? (pr.particle_steps + cyc.particle_steps()) / cyc_s : 0.0;
  if (!ck.path.empty()) {
    std::error_code ec;
    std::filesystem::remove(ck.path, ec); // finished: the result is the record
  }
  return r;
}

double UnloadReload::unloading_modulus_Pa() const {
  const double strain = (unloaded_height_m - loaded_height_m) / loaded_height_m;
  return strain > 0 ? (loaded_normal_stress_Pa - unloaded_normal_stress_Pa) / strain : 0.0;
}

double UnloadReload::reloading_modulus_Pa() const {
  const double strain = (unloaded_height_m - reloaded_height_m) / unloaded_height_m;
  return strain > 0 ? (reloaded_normal_stress_Pa - unloaded_normal_stress_Pa) / strain : 0.0;
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
