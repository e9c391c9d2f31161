#include "procedures/foundation.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "io/toml_read.hpp"
#include "physics/body_field.hpp"
#include "procedures/failure.hpp"
#include "procedures/gsd.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/slope_trial.hpp"
#include "procedures/specimen.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <unistd.h>

namespace centridem {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Volume of a sphere (centre height zc, radius r) between heights z0 < z1
// [m^3]: the integral of pi (r^2 - (z - zc)^2) over the overlap.
double sphere_slab_volume(double zc, double r, double z0, double z1) {
  const double a = std::max(z0, zc - r) - zc, b = std::min(z1, zc + r) - zc;
  if (b <= a) return 0.0;
  return std::numbers::pi * (r * r * (b - a) - (b * b * b - a * a * a) / 3.0);
}

} // namespace

std::pair<double, double> foundation_surface(const ParticleStore& P, double length_m, double d50) {
  const double w = std::max(2 * d50, length_m / 1000);
  const int n = std::max(1, static_cast<int>(length_m / w));
  std::vector<double> top(static_cast<std::size_t>(n), 0.0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const int k = std::clamp(static_cast<int>(P.position[i].x / length_m * n), 0, n - 1);
    top[static_cast<std::size_t>(k)] =
        std::max(top[static_cast<std::size_t>(k)], P.position[i].z + P.radius[i]);
  }
  double mn = top[0], sum = 0;
  for (double t : top) mn = std::min(mn, t), sum += t;
  return {mn, sum / n};
}

json to_json(const FoundationResult& f) {
  return {{"particles", f.particles},
          {"steps", f.steps},
          {"ratio", f.ratio},
          {"kinetic_ratio", f.kinetic_ratio},
          {"converged", f.converged},
          {"box_top_m", f.box_top_m},
          {"surface_min_m", f.surface_min_m},
          {"surface_mean_m", f.surface_mean_m},
          {"settlement_m", f.box_top_m - f.surface_mean_m},
          {"porosity_before", f.porosity_before},
          {"porosity_after", f.porosity_after},
          {"coordination_number", f.coordination_number},
          {"brick_particles", f.brick_particles},
          {"brick_from_cache", f.brick_from_cache},
          {"brick_file", f.brick_file},
          {"prepared", f.prepared},
          {"generated_particles", f.generated_particles},
          {"compaction_steps", f.compaction_steps},
          {"settle_steps", f.settle_steps},
          {"compaction_g_level", f.compaction_g_level},
          {"prepared_surface_min_m", f.prepared_surface_min_m},
          {"trimmed", f.trimmed},
          {"layer_porosity", f.layer_porosity},
          {"from_cache", f.from_cache},
          {"cache_file", f.cache_file}};
}

FoundationResult foundation_from_json(const json& j) {
  FoundationResult f;
  f.particles = j.at("particles");
  f.steps = j.at("steps");
  f.ratio = j.at("ratio");
  f.kinetic_ratio = j.value("kinetic_ratio", 0.0);
  f.converged = j.at("converged");
  f.box_top_m = j.at("box_top_m");
  f.surface_min_m = j.at("surface_min_m");
  f.surface_mean_m = j.at("surface_mean_m");
  f.porosity_before = j.at("porosity_before");
  f.porosity_after = j.at("porosity_after");
  f.coordination_number = j.value("coordination_number", 0.0);
  f.brick_particles = j.at("brick_particles");
  f.brick_from_cache = j.at("brick_from_cache");
  f.brick_file = j.at("brick_file");
  f.prepared = j.value("prepared", false);
  f.generated_particles = j.value("generated_particles", std::size_t{0});
  f.compaction_steps = j.value("compaction_steps", 0L);
  f.settle_steps = j.value("settle_steps", 0L);
  f.compaction_g_level = j.value("compaction_g_level", 0.0);
  f.prepared_surface_min_m = j.value("prepared_surface_min_m", 0.0);
  f.trimmed = j.value("trimmed", std::size_t{0});
  if (j.contains("layer_porosity")) f.layer_porosity = j.at("layer_porosity");
  f.from_cache = j.value("from_cache", false);
  f.cache_file = j.value("cache_file", std::string());
  return f;
}

std::vector<double> porosity_layers(const World& w, const Box& box, double margin, int layers) {
  const ParticleStore& P = w.particles();
  const double x0 = box.lo.x + margin, x1 = box.hi.x - margin;
  const double y0 = box.lo.y + margin, y1 = box.hi.y - margin;
  const double z0 = box.lo.z + margin, dz = (box.hi.z - box.lo.z - 2 * margin) / layers;
  std::vector<double> solid(static_cast<std::size_t>(layers), 0.0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vec3& c = P.position[i];
    if (c.x < x0 || c.x > x1 || c.y < y0 || c.y > y1) continue;
    for (int k = 0; k < layers; ++k)
      solid[static_cast<std::size_t>(k)] +=
          sphere_slab_volume(c.z, P.radius[i], z0 + k * dz, z0 + (k + 1) * dz);
  }
  for (double& v : solid) v = 1.0 - v / ((x1 - x0) * (y1 - y0) * dz);
  return solid;
}

std::array<double, 3> layer_porosities(const World& w, const Box& box, double margin) {
  const std::vector<double> n = porosity_layers(w, box, margin, 3);
  return {n[0], n[1], n[2]};
}

PorosityProfile foundation_porosity_profile(const World& w, const Box& box) {
  PorosityProfile p;
  double dmax = 0;
  for (double r : w.particles().radius) dmax = std::max(dmax, 2 * r);
  const double d50 = median_diameter(w.particles());
  const double span = box.hi.z - box.lo.z - 2 * dmax;
  if (!(span > 0) || !(d50 > 0)) return p;
  const int layers = std::max(3, static_cast<int>(std::floor(span / (2 * d50))));
  p.margin_m = dmax;
  p.layer_m = span / layers;
  p.porosity = porosity_layers(w, box, dmax, layers);
  for (int k = 0; k < layers; ++k) p.z_bottom_m.push_back(box.lo.z + dmax + k * p.layer_m);
  return p;
}

nlohmann::json to_json(const PorosityProfile& p) {
  return {{"margin_m", p.margin_m},
          {"layer_m", p.layer_m},
          {"z_bottom_m", p.z_bottom_m},
          {"porosity", p.porosity}};
}

double kinetic_energy_ratio(const World& w, const Vec3& at, double d50) {
  const ParticleStore& P = w.particles();
  double kinetic = 0, mass = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    kinetic += 0.5 * P.mass[i] * norm2(P.velocity[i]);
    mass += P.mass[i];
  }
  const double scale = mass * norm(w.body_field().acceleration(at, {})) * d50;
  return scale > 0 ? kinetic / scale : 0.0;
}

void build_foundation(World& world, const SlopeScenario& sc, const SlopeGeometry& geometry,
                      const std::string& cache_dir, double height_factor, FoundationResult& f,
                      const FoundationLog& log, int threads) {
  auto say = [&](std::string_view l) {
    if (log) log(l);
  };
  const double L = geometry.length(), B = geometry.breadth();
  world.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), sc.walls.chamber);
  world.add_wall(Wall::plane("back", {0, 0, 0}, {1, 0, 0}), sc.walls.chamber);
  world.add_wall(Wall::plane("side_y0", {0, 0, 0}, {0, 1, 0}), sc.walls.chamber);
  world.add_wall(Wall::plane("side_y1", {0, B, 0}, {0, -1, 0}), sc.walls.chamber);
  if (sc.walls.end_wall) world.add_wall(Wall::plane("end", {L, 0, 0}, {-1, 0, 0}), sc.walls.end);
  world.set_ball_ball_defaults(sc.soil());

  SpecimenSpec spec = sc.specimen;
  if (spec.region) spec.region->hi.z = spec.region->lo.z + height_factor * geometry.height();
  std::string cached;
  if (!cache_dir.empty() && spec.source == SpecimenSpec::Source::distribute &&
      spec.brick_file.empty()) {
    SpecimenSpec key = spec;
    key.region.reset(); // the brick does not depend on the region
    const std::uint64_t h = fnv1a(resolved_specimen_toml(key));
    cached = (fs::path(cache_dir) / fmt::format("brick_{:016x}.json", h)).string();
    if (fs::exists(cached)) {
      spec.brick_file = spec.brick_file_path = cached;
      f.brick_from_cache = true;
    }
  }
  if (!cached.empty() && !f.brick_from_cache) {
    // Make the brick and cache it; the foundation is then always built from
    // the cached file, so a first trial and a later one start alike.
    const std::vector<GradationBin> bins = resolve_gradation(spec);
    check_specimen_size(spec, bins);
    const Brick brick = make_brick(bins, spec.porosity, spec.brick_size_m, spec.density_kg_m3,
                                   spec.group, spec.seed, spec.relax, log, threads);
    make_directories(cache_dir);
    const std::string tmp = cached + fmt::format(".tmp{}", static_cast<long>(::getpid()));
    write_brick(brick, tmp);
    fs::rename(tmp, cached); // atomic: parallel trials may race to write it
    spec.brick_file = spec.brick_file_path = cached;
  }
  const BuiltSpecimen built = build_specimen(spec, world, log, threads);
  f.brick_file = cached;
  f.brick_particles = built.brick ? built.brick->size() : 0;
  f.particles = world.particles().size();
  f.box_top_m = geometry.height();
  f.porosity_before =
      1 - solid_volume_m3(world.particles()) / (L * B * height_factor * geometry.height());
  const long fit = calm_into_walls(world); // no body force yet
  say(fmt::format("fitted into the chamber walls in {} calm steps", fit));
}

void prepare_foundation(World& world, const SlopeScenario& sc, const SlopeGeometry& geometry,
                        FoundationResult& f, const FoundationLog& log) {
  auto say = [&](const std::string& l) {
    if (log) log(l);
  };
  const PreparationSpec& prep = sc.preparation;
  const double L = geometry.length(), B = geometry.breadth(), H = geometry.height();
  const ContactProperties soil = sc.soil();
  const ContactProperties packing = apply(prep.during_compaction, soil);
  f.prepared = true;
  f.generated_particles = world.particles().size();
  f.compaction_g_level = prep.compaction_g_level;
  // Uniform n g / s whatever the trial's field: the compaction stands for the
  // model's preparation in the laboratory, before it is spun; the radial field
  // acts from the trial on (which brings the foundation to rest in it before
  // the cut). So every field shares one foundation, and comparisons between
  // fields are not blurred by packing scatter (docs/results/centrifuge.md).
  world.set_body_field(BodyField::scaled_gravity(prep.compaction_g_level, geometry.scale()));
  const double d50 = median_diameter(world.particles());
  const Vec3 floor_centre{0.5 * L, 0.5 * B, 0.0};

  // A top plate (frictionless, servo-controlled) when a compaction stress is given.
  std::optional<std::size_t> plate;
  if (prep.compaction_stress_Pa > 0) {
    double top = 0;
    for (std::size_t i = 0; i < world.particles().size(); ++i)
      top = std::max(top, world.particles().position[i].z + world.particles().radius[i]);
    plate = world.add_wall(Wall::plane("compaction_plate", {0, 0, top}, {0, 0, -1}),
                           paper::ball_wall(0.0));
    WallServo servo;
    servo.active = true;
    servo.direction = {0, 0, -1};
    servo.target_force_N = prep.compaction_stress_Pa * L * B;
    servo.gain_factor = 0.5;
    servo.max_speed_m_per_s = 1.0; // the loose packing collapses by ~20 % of its height
    world.set_wall_servo(*plate, servo);
  }
  auto plate_stress = [&] {
    return plate ? world.walls()[*plate].force.z / (L * B) : 0.0; // balls push the plate up
  };

  // Cycles in chunks until done() or the step limit; returns the steps.
  const long chunk = std::max<long>(sc.trial.check_interval_steps, 100);
  auto t_last = std::chrono::steady_clock::now();
  auto cycle_until = [&](const char* phase, const std::function<bool()>& done) {
    long steps = 0;
    while (steps < prep.max_steps) {
      world.cycle(std::min(chunk, prep.max_steps - steps));
      steps += std::min(chunk, prep.max_steps - steps);
      const bool ok = done();
      if (std::chrono::steady_clock::now() - t_last > std::chrono::seconds(10)) {
        t_last = std::chrono::steady_clock::now();
        say(fmt::format("foundation preparation, {}: step {}, ratio {:.3g} (target {:.3g}), "
                        "kinetic {:.3g}{}",
                        phase, steps, world.mean_unbalanced_force_ratio(), prep.ratio,
                        kinetic_energy_ratio(world, floor_centre, d50),
                        plate ? fmt::format(", plate {:.3g} kPa", 1e-3 * plate_stress()) : ""));
      }
      if (ok) return std::pair{steps, true};
    }
    return std::pair{steps, false};
  };
  // Compacted: balanced forces (and the plate at its stress). At rest, after
  // the switch: also little motion.
  auto compacted_now = [&] {
    return world.mean_unbalanced_force_ratio() < prep.ratio &&
           (!plate || std::abs(plate_stress() - prep.compaction_stress_Pa) <
                          0.01 * prep.compaction_stress_Pa);
  };
  auto at_rest = [&] {
    return compacted_now() &&
           kinetic_energy_ratio(world, floor_centre, d50) < sc.trial.rest_kinetic_ratio;
  };
  say(fmt::format(
      "foundation preparation: {} particles compacted with {} under {:g} g{}",
      world.particles().size(), inline_patch(prep.during_compaction), prep.compaction_g_level,
      plate ? fmt::format(" and a top plate at {:g} kPa", 1e-3 * prep.compaction_stress_Pa)
            : std::string()));
  assign_ball_ball_contacts(world, packing);
  const auto [compaction, compacted] = cycle_until("compaction", compacted_now);
  f.compaction_steps = compaction;
  assign_ball_ball_contacts(world, soil);
  if (plate) {
    WallServo s = world.walls()[*plate].servo;
    s.error_integral_N_s = 0;
    world.set_wall_servo(*plate, s);
  }
  const auto [settle, settled] = cycle_until("settling with the soil", at_rest);
  f.settle_steps = settle;
  if (!compacted || !settled)
    say(fmt::format("warning: the foundation preparation reached its step limit "
                    "(preparation.max_steps = {}) before coming to rest ({})",
                    prep.max_steps, !compacted ? "compaction" : "settling"));
  if (plate) world.remove_wall("compaction_plate");

  // The prepared surface must stand at or above the design; trim the excess.
  const double smin = foundation_surface(world.particles(), L, d50).first;
  f.prepared_surface_min_m = smin;
  if (smin < H) {
    throw InputError("preparation.overfill", tomlread::num(sc.preparation.overfill),
                     fmt::format("too little soil: the prepared surface stands at {:.3f} mm at "
                                 "its lowest, below the design crest at {:.3f} mm; raise it to "
                                 "about {:.2f}",
                                 1e3 * smin, 1e3 * H, sc.preparation.overfill * H / smin + 0.05));
  }
  const ParticleStore& P = world.particles();
  f.trimmed = world.remove_particles([&](std::size_t i) { return P.position[i].z > H; });
  f.particles = world.particles().size();
  double dmax = 0;
  for (double r : world.particles().radius) dmax = std::max(dmax, 2 * r);
  f.layer_porosity = layer_porosities(world, Box{{0, 0, 0}, {L, B, H}}, dmax);
  f.coordination_number = world.measure().coordination_number;
  say(fmt::format("foundation prepared: {} + {} steps; surface {:.3f} mm at its lowest (design "
                  "{:.3f} mm); {} particles above the design removed, {} remain; porosity "
                  "bottom / middle / top {:.4f} / {:.4f} / {:.4f}; coordination {:.2f}",
                  f.compaction_steps, f.settle_steps, 1e3 * smin, 1e3 * H, f.trimmed, f.particles,
                  f.layer_porosity[0], f.layer_porosity[1], f.layer_porosity[2],
                  f.coordination_number));
}

std::string prepared_foundation_path(const SlopeScenario& sc, const std::string& cache_dir) {
  if (cache_dir.empty())
    throw InputError("--cache", "\"\"", "a folder for the prepared foundation");
  // The key: everything that changes the prepared foundation. The field is
  // not among them (prepared under uniform gravity, above); the recipe keeps
  // its line with the defaults so that earlier cache entries stay valid.
  const FieldSpec field{};
  SpecimenSpec spec = sc.specimen;
  spec.region.reset();
  const SlopeGeometry geometry(sc.slope);
  const std::string recipe = fmt::format(
      "centridem prepared foundation v1\n{}{}\nsoil = {}\nchamber = {}\nend = {}\nend_wall = {}\n"
      "box = {} {} {}\nfield = {} {} {} {} {}\nrest_kinetic_ratio = {}\ncheck = {}\n"
      "local_damping = {}\n",
      resolved_specimen_toml(spec), resolved_preparation_toml(sc.preparation),
      tomlread::contact_inline(sc.soil()), tomlread::contact_inline(sc.walls.chamber),
      tomlread::contact_inline(sc.walls.end), sc.walls.end_wall, tomlread::num(geometry.length()),
      tomlread::num(geometry.breadth()), tomlread::num(geometry.height()),
      field.kind == FieldKind::uniform ? "uniform" : "centrifuge",
      tomlread::num(field.base_radius_m), tomlread::num(field.reference_radius_m), field.axis,
      field.coriolis, tomlread::num(sc.trial.rest_kinetic_ratio), sc.trial.check_interval_steps,
      tomlread::num(sc.trial.local_damping));
  return (fs::path(cache_dir) / fmt::format("foundation_{:016x}.bin", fnv1a(recipe))).string();
}

PreparedFoundationFile ensure_prepared_foundation(const SlopeScenario& sc,
                                                  const std::string& cache_dir,
                                                  const FoundationLog& log, int threads) {
  const std::string path = prepared_foundation_path(sc, cache_dir);
  const SlopeGeometry geometry(sc.slope);
  if (auto cached = cached_foundation_result(sc, cache_dir)) return {path, *cached, false};
  WorldSettings ws;
  ws.local_damping = sc.trial.local_damping;
  ws.threads = threads;
  World world(ws);
  FoundationResult f;
  build_foundation(world, sc, geometry, cache_dir, sc.preparation.overfill, f, log, threads);
  prepare_foundation(world, sc, geometry, f, log);
  f.cache_file = path;
  make_directories(cache_dir);
  write_checkpoint(world, path, to_json(f).dump());
  // The report beside it (written last: its presence means the cache entry
  // is complete), readable without loading the World.
  replace_text_file(path + ".json", to_json(f).dump(2) + "\n");
  return {path, f, true};
}

std::optional<FoundationResult> cached_foundation_result(const SlopeScenario& sc,
                                                         const std::string& cache_dir) {
  const std::string path = prepared_foundation_path(sc, cache_dir);
  if (!fs::exists(path) || !fs::exists(path + ".json")) return std::nullopt;
  std::ifstream in(path + ".json");
  try {
    return foundation_from_json(json::parse(in));
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}.json: unreadable prepared-foundation report ({}); delete "
                                 "it and its .bin to prepare the foundation again",
                                 path, e.what()));
  }
}

} // namespace centridem
