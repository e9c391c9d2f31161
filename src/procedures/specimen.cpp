#include "procedures/specimen.hpp"

#include "base/errors.hpp"
#include "io/output.hpp"
#include "io/particle_file.hpp"
#include "io/vtk.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/os.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <sstream>
#include <unordered_map>

namespace centridem {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void say(const SpecimenLog& log, const std::string& s) {
  if (log) log(s);
}

double smallest_diameter(const std::vector<GradationBin>& bins) {
  double d = std::numeric_limits<double>::infinity();
  for (const GradationBin& b : bins)
    if (b.volume_fraction > 0) d = std::min(d, b.d_min_m);
  return d;
}

double largest_diameter(const std::vector<GradationBin>& bins) {
  double d = 0;
  for (const GradationBin& b : bins)
    if (b.volume_fraction > 0) d = std::max(d, b.d_max_m);
  return d;
}

// Largest overlap / smaller radius below which a relaxing assembly counts as
// stress free (too loose to jam): its contacts carry no force worth balancing.
constexpr double kStressFreeOverlap = 1e-6;

void zero_motion(World& w) {
  ParticleStore& p = w.particles_mut();
  std::fill(p.velocity.begin(), p.velocity.end(), Vec3{});
  std::fill(p.spin.begin(), p.spin.end(), Vec3{});
}

} // namespace

// --------------------------------------------------------------- distribute --

std::size_t distribute(World& world, const std::vector<GradationBin>& bins, double porosity,
                       const Box& cell, double density_kg_m3, std::int32_t group,
                       SpecimenRandom& random) {
  if (!(porosity > 0 && porosity < 1))
    throw InputError("specimen.porosity", fmt::format("{:g}", porosity), "must be in (0, 1)");
  const double solid = (1.0 - porosity) * cell.volume();
  std::vector<double> radii = draw_radii(bins, solid, random);
  // Random order (Fisher-Yates), so that ids do not follow size.
  for (std::size_t i = radii.size(); i > 1; --i) std::swap(radii[i - 1], radii[random.bits() % i]);
  const Vec3 L = cell.hi - cell.lo;
  for (double r : radii) {
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = cell.lo[a] + random.uniform() * L[a];
    world.add_particle(x, r, density_kg_m3, group);
  }
  return radii.size();
}

// -------------------------------------------------------------------- relax --

RelaxResult relax_packing(World& w, const RelaxSpec& r, const SpecimenLog& log) {
  RelaxResult out;
  ContactProperties packing;
  packing.model = ContactModel::linear;
  packing.effective_modulus_Pa = r.effective_modulus_Pa;
  packing.stiffness_ratio = r.stiffness_ratio;
  packing.friction = 0.0;
  w.set_ball_ball_defaults(packing);
  w.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                              [&](ContactProperties& p) { p = packing; });
  w.set_local_damping(r.local_damping);
  const long chunk = r.calm_interval > 0 ? r.calm_interval : 100;
  Measurements m;
  long next_log = 1000;
  while (out.packing_steps < r.max_steps) {
    const long c = std::min(chunk, r.max_steps - out.packing_steps);
    w.cycle(c);
    out.packing_steps += c;
    if (r.calm_interval > 0) zero_motion(w); // PFC `calm`
    m = w.measure();
    if (out.packing_steps >= next_log) {
      say(log, fmt::format("  relax: step {}, mean unbalanced-force ratio {:.3g}, max overlap "
                           "{:.3g} R, {} contacts",
                           out.packing_steps, m.mean_unbalanced_force_ratio, m.max_overlap_ratio,
                           m.ball_ball_contacts));
      next_log += 1000;
    }
    // Relaxed: in equilibrium with small overlaps, or (an assembly too loose
    // to carry stress) overlaps that have all but vanished.
    if ((m.mean_unbalanced_force_ratio <= r.ratio && m.max_overlap_ratio <= r.max_overlap_ratio) ||
        m.max_overlap_ratio <= kStressFreeOverlap) {
      out.converged = true;
      break;
    }
  }
  if (r.contact) {
    w.set_ball_ball_defaults(*r.contact);
    w.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                                [&](ContactProperties& p) { p = *r.contact; });
    zero_motion(w);
    out.contact_steps = w.cycle_until_equilibrium(r.contact_ratio, r.contact_max_steps);
    m = w.measure();
    out.converged = out.converged && m.mean_unbalanced_force_ratio <= r.contact_ratio;
  }
  zero_motion(w);
  out.ratio = m.mean_unbalanced_force_ratio;
  out.max_overlap_ratio = m.max_overlap_ratio;
  out.coordination_number = m.coordination_number;
  out.contacts = m.ball_ball_contacts;
  return out;
}

// -------------------------------------------------------------------- brick --

bool Brick::operator==(const Brick& o) const {
  if (!(size_m == o.size_m && density_kg_m3 == o.density_kg_m3 && group == o.group &&
        position == o.position && radius == o.radius && contacts.size() == o.contacts.size()))
    return false;
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactRecord &a = contacts[k], &b = o.contacts[k];
    if (!(a.id1 == b.id1 && a.id2 == b.id2 && a.wall == b.wall && a.image == b.image &&
          a.properties == b.properties && a.state.shear_force == b.state.shear_force &&
          a.state.rolling_moment == b.state.rolling_moment))
      return false;
  }
  return true;
}

double minimum_brick_side(const std::vector<GradationBin>& bins) {
  return 3.0 * (largest_diameter(bins) + 0.25 * smallest_diameter(bins));
}

WorldSettings brick_world_settings(const std::vector<GradationBin>& bins, const RelaxSpec& relax,
                                   int threads) {
  WorldSettings s;
  s.local_damping = relax.local_damping;
  s.threads = threads;
  // Skin fixed at half the smallest possible radius, so the minimum cell
  // side does not depend on the radii drawn.
  s.neighbour_skin_m = 0.25 * smallest_diameter(bins);
  // Random placement can put a small particle right inside a large one:
  // overlap up to (R + r)/r of the smaller radius.
  const double rmin = 0.5 * smallest_diameter(bins), rmax = 0.5 * largest_diameter(bins);
  s.max_overlap_fraction = std::max(3.0, 2.0 * (rmax + rmin) / rmin + 1.0);
  return s;
}

Brick make_brick(const std::vector<GradationBin>& bins, double porosity, const Vec3& size_m,
                 double density_kg_m3, std::int32_t group, std::uint64_t seed,
                 const RelaxSpec& relax, const SpecimenLog& log, int threads) {
  if (bins.empty()) throw InputError("specimen.gradation", "(none)", "a gradation is required");
  double range = 0;
  if (relax.contact && relax.contact->attraction_force_N > 0)
    range = relax.contact->attraction_range_m;
  const double min_side = minimum_brick_side(bins) + 3.0 * range;
  for (int a = 0; a < 3; ++a)
    if (!(size_m[a] >= min_side))
      throw InputError("specimen.brick.size_m",
                       fmt::format("[{:g}, {:g}, {:g}]", size_m.x, size_m.y, size_m.z),
                       fmt::format("every side must be at least {:.4g} m = 3 x (largest diameter "
                                   "{:.4g} m + neighbour skin {:.4g} m{}) so that the periodic "
                                   "cell holds 3 neighbour cells; the {} side is {:.4g} m",
                                   min_side, largest_diameter(bins), 0.25 * smallest_diameter(bins),
                                   range > 0 ? " + attraction range" : "", "xyz"[a], size_m[a]));
  World w(brick_world_settings(bins, relax, threads));
  PeriodicBox pb;
  pb.axis = {true, true, true};
  pb.lo = {0, 0, 0};
  pb.hi = size_m;
  w.set_periodic(pb);
  SpecimenRandom random(seed);
  const std::size_t n = distribute(w, bins, porosity, {pb.lo, pb.hi}, density_kg_m3, group, random);
  say(log, fmt::format("brick: {} particles distributed in {:.4g} x {:.4g} x {:.4g} mm (porosity "
                       "{} ignoring overlaps, seed {}); relaxing",
                       n, size_m.x * 1e3, size_m.y * 1e3, size_m.z * 1e3, porosity, seed));
  const RelaxResult rr = relax_packing(w, relax, log);
  say(log,
      fmt::format("brick: relaxed in {} + {} steps: mean unbalanced-force ratio {:.3g}, max "
                  "overlap {:.3g} of the smaller radius, {} contacts{}",
                  rr.packing_steps, rr.contact_steps, rr.ratio, rr.max_overlap_ratio, rr.contacts,
                  rr.converged ? "" : " (step limit reached before the targets)"));
  Brick b = capture_brick(w);
  b.density_kg_m3 = density_kg_m3;
  b.group = group;
  b.seed = seed;
  b.target_porosity = porosity;
  b.relax = rr;
  return b;
}

Brick capture_brick(World& w) {
  const PeriodicBox& pb = w.periodic();
  if (!(pb.axis[0] && pb.axis[1] && pb.axis[2]))
    throw InputError("brick", "a world that is not periodic along x, y and z",
                     "a brick is captured from a periodic cell");
  zero_motion(w);
  w.request_rebuild();
  w.cycle(0); // rebuild now: positions wrapped into the cell, images current
  const ParticleStore& p = w.particles();
  std::vector<std::size_t> order(p.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return p.id[a] < p.id[b]; });
  std::unordered_map<std::int64_t, std::int64_t> local; // world id -> brick id
  Brick b;
  b.size_m = pb.length();
  b.density_kg_m3 =
      p.size() ? p.mass[0] / (4.0 / 3.0 * std::numbers::pi * std::pow(p.radius[0], 3)) : 0;
  b.group = p.size() ? p.group[0] : 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    local[p.id[i]] = static_cast<std::int64_t>(k + 1);
    b.position.push_back(p.position[i] - pb.lo);
    b.radius.push_back(p.radius[i]);
  }
  for (ContactRecord rec : w.contact_records()) {
    if (rec.wall >= 0) continue;
    rec.id1 = local.at(rec.id1);
    rec.id2 = local.at(rec.id2);
    b.contacts.push_back(rec);
  }
  std::sort(b.contacts.begin(), b.contacts.end(),
            [](const ContactRecord& a, const ContactRecord& c) {
              return a.id1 != c.id1 ? a.id1 < c.id1 : a.id2 < c.id2;
            });
  return b;
}

// ---------------------------------------------------------------- brick file --

namespace {

json vec_json(const Vec3& v) {
  return json::array({v.x, v.y, v.z});
}

json properties_json(const ContactProperties& c) {
  return {{"model", std::string(to_string(c.model))},
          {"stiffness_method",
           c.stiffness_method == StiffnessMethod::deformability ? "deformability" : "direct"},
          {"effective_modulus_Pa", c.effective_modulus_Pa},
          {"stiffness_ratio", c.stiffness_ratio},
          {"normal_stiffness_N_per_m", c.normal_stiffness_N_per_m},
          {"shear_stiffness_N_per_m", c.shear_stiffness_N_per_m},
          {"friction", c.friction},
          {"rolling_friction", c.rolling_friction},
          {"attraction_force_N", c.attraction_force_N},
          {"attraction_range_m", c.attraction_range_m},
          {"dashpot_normal_ratio", c.dashpot_normal_ratio},
          {"dashpot_shear_ratio", c.dashpot_shear_ratio},
          {"dashpot_mode", c.dashpot_mode},
          {"limits_use_net_force", c.limits_use_net_force}};
}

ContactProperties properties_from_json(const json& j, const std::string& where) {
  ContactProperties c;
  c.model = contact_model_from_string(j.at("model").get<std::string>(), where + ".model");
  const std::string m = j.at("stiffness_method").get<std::string>();
  if (m != "deformability" && m != "direct")
    throw InputError(where + ".stiffness_method", "\"" + m + "\"",
                     "expected \"deformability\" or \"direct\"");
  c.stiffness_method = m == "direct" ? StiffnessMethod::direct : StiffnessMethod::deformability;
  c.effective_modulus_Pa = j.at("effective_modulus_Pa").get<double>();
  c.stiffness_ratio = j.at("stiffness_ratio").get<double>();
  c.normal_stiffness_N_per_m = j.at("normal_stiffness_N_per_m").get<double>();
  c.shear_stiffness_N_per_m = j.at("shear_stiffness_N_per_m").get<double>();
  c.friction = j.at("friction").get<double>();
  c.rolling_friction = j.at("rolling_friction").get<double>();
  c.attraction_force_N = j.at("attraction_force_N").get<double>();
  c.attraction_range_m = j.at("attraction_range_m").get<double>();
  c.dashpot_normal_ratio = j.at("dashpot_normal_ratio").get<double>();
  c.dashpot_shear_ratio = j.at("dashpot_shear_ratio").get<double>();
  c.dashpot_mode = j.at("dashpot_mode").get<int>();
  c.limits_use_net_force = j.at("limits_use_net_force").get<bool>();
  validate(c, where);
  return c;
}

json relax_json(const RelaxResult& r) {
  return {{"packing_steps", r.packing_steps},
          {"contact_steps", r.contact_steps},
          {"converged", r.converged},
          {"mean_unbalanced_force_ratio", r.ratio},
          {"max_overlap_ratio", r.max_overlap_ratio},
          {"coordination_number", r.coordination_number},
          {"contacts", r.contacts}};
}

Vec3 vec_from(const json& j) {
  if (!j.is_array() || j.size() != 3) throw std::runtime_error("expected [x, y, z]");
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

} // namespace

void write_brick(const Brick& b, const std::string& path) {
  json j;
  j["format"] = "centridem-brick";
  j["version"] = 1;
  j["comment"] = "A relaxed periodic cell [0, size_m) and its contacts (docs/specimens.md). "
                 "particles: [x, y, z, r] in metres, particle k has id k+1. contacts: [id1, "
                 "id2, image_x, image_y, image_z, property_set, shear_force_x, _y, _z (N, on "
                 "end 2), rolling_moment_x, _y, _z (N m, on end 2)]; image = periodic image of "
                 "end 2 relative to end 1.";
  j["size_m"] = vec_json(b.size_m);
  j["density_kg_m3"] = b.density_kg_m3;
  j["group"] = b.group;
  j["seed"] = b.seed;
  j["target_porosity"] = b.target_porosity;
  j["relax"] = relax_json(b.relax);
  json parts = json::array();
  for (std::size_t k = 0; k < b.size(); ++k)
    parts.push_back({b.position[k].x, b.position[k].y, b.position[k].z, b.radius[k]});
  j["particles"] = std::move(parts);
  std::vector<ContactProperties> sets;
  json contacts = json::array();
  for (const ContactRecord& c : b.contacts) {
    std::size_t s = 0;
    while (s < sets.size() && !(sets[s] == c.properties)) ++s;
    if (s == sets.size()) sets.push_back(c.properties);
    const ContactState& st = c.state;
    contacts.push_back({c.id1, c.id2, c.image[0], c.image[1], c.image[2], s, st.shear_force.x,
                        st.shear_force.y, st.shear_force.z, st.rolling_moment.x,
                        st.rolling_moment.y, st.rolling_moment.z});
  }
  json js = json::array();
  for (const ContactProperties& c : sets) js.push_back(properties_json(c));
  j["property_sets"] = std::move(js);
  j["contacts"] = std::move(contacts);
  const fs::path tmp = fs::path(path).string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError("brick file", "\"" + path + "\"", "cannot be opened for writing");
    out << j.dump() << '\n';
    if (!out) throw InputError("brick file", "\"" + path + "\"", "write failed");
  }
  fs::rename(tmp, path);
}

Brick read_brick(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("brick file", "\"" + path + "\"", "cannot be opened for reading");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError("brick file", "\"" + path + "\"", std::string("not valid JSON: ") + e.what());
  }
  Brick b;
  std::string stage = "header";
  try {
    if (j.value("format", std::string()) != "centridem-brick")
      throw InputError("brick file", "\"" + path + "\"",
                       "not a brick file (format must be \"centridem-brick\")");
    if (j.at("version").get<int>() != 1)
      throw InputError("brick file", "\"" + path + "\"",
                       fmt::format("version {} is not supported (this build reads version 1)",
                                   j.at("version").get<int>()));
    b.size_m = vec_from(j.at("size_m"));
    for (int a = 0; a < 3; ++a)
      if (!(b.size_m[a] > 0)) throw std::runtime_error("size_m must be > 0");
    b.density_kg_m3 = j.at("density_kg_m3").get<double>();
    b.group = j.at("group").get<std::int32_t>();
    b.seed = j.value("seed", std::uint64_t{0});
    b.target_porosity = j.value("target_porosity", 0.0);
    if (j.contains("relax")) {
      const json& r = j["relax"];
      b.relax.packing_steps = r.value("packing_steps", 0L);
      b.relax.contact_steps = r.value("contact_steps", 0L);
      b.relax.converged = r.value("converged", false);
      b.relax.ratio = r.value("mean_unbalanced_force_ratio", 0.0);
      b.relax.max_overlap_ratio = r.value("max_overlap_ratio", 0.0);
      b.relax.coordination_number = r.value("coordination_number", 0.0);
      b.relax.contacts = r.value("contacts", std::size_t{0});
    }
    stage = "particles";
    for (const json& p : j.at("particles")) {
      if (!p.is_array() || p.size() != 4) throw std::runtime_error("a particle is [x, y, z, r]");
      const Vec3 x{p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
      const double r = p[3].get<double>();
      if (!(r > 0) || !is_finite(x)) throw std::runtime_error("bad radius or position");
      b.position.push_back(x);
      b.radius.push_back(r);
    }
    stage = "property_sets";
    std::vector<ContactProperties> sets;
    for (const json& s : j.at("property_sets"))
      sets.push_back(
          properties_from_json(s, fmt::format("{}: property_sets[{}]", path, sets.size())));
    stage = "contacts";
    const auto n = static_cast<std::int64_t>(b.size());
    for (const json& c : j.at("contacts")) {
      if (!c.is_array() || c.size() != 12) throw std::runtime_error("a contact has 12 values");
      ContactRecord rec;
      rec.id1 = c[0].get<std::int64_t>();
      rec.id2 = c[1].get<std::int64_t>();
      if (rec.id1 < 1 || rec.id1 > n || rec.id2 < 1 || rec.id2 > n || rec.id1 == rec.id2)
        throw std::runtime_error(
            fmt::format("contact ids {} {} not in 1..{}", rec.id1, rec.id2, n));
      for (int a = 0; a < 3; ++a) {
        const int s = c[static_cast<std::size_t>(2 + a)].get<int>();
        if (s < -1 || s > 1) throw std::runtime_error("image codes are -1, 0 or 1");
        rec.image[static_cast<std::size_t>(a)] = static_cast<std::int8_t>(s);
      }
      const auto set = c[5].get<std::size_t>();
      if (set >= sets.size()) throw std::runtime_error("property set index out of range");
      rec.properties = sets[set];
      rec.state.shear_force = {c[6].get<double>(), c[7].get<double>(), c[8].get<double>()};
      rec.state.rolling_moment = {c[9].get<double>(), c[10].get<double>(), c[11].get<double>()};
      b.contacts.push_back(rec);
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError("brick file", "\"" + path + "\"",
                     fmt::format("bad or missing {}: {}", stage, e.what()));
  }
  if (b.radius.empty()) throw InputError("brick file", "\"" + path + "\"", "holds no particles");
  return b;
}

// ----------------------------------------------------------------- assembly --

std::array<int, 3> copies_to_fill(const Vec3& cell, const Box& region) {
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) {
    const double want = (region.hi[a] - region.lo[a]) / cell[a];
    n[static_cast<std::size_t>(a)] = std::max(1, static_cast<int>(std::ceil(want - 1e-9)));
  }
  return n;
}

AssemblyResult assemble_bricks(const Brick& brick, World& world, const AssemblyOptions& o) {
  AssemblyResult res;
  res.copies = o.copies;
  const auto nx = o.copies[0], ny = o.copies[1], nz = o.copies[2];
  if (nx < 1 || ny < 1 || nz < 1)
    throw InputError("brick copies", fmt::format("{} x {} x {}", nx, ny, nz), "must be >= 1");
  const std::size_t N = brick.size();
  const Vec3 L = brick.size_m;
  if (o.periodic[0] || o.periodic[1] || o.periodic[2]) {
    PeriodicBox pb;
    pb.axis = o.periodic;
    pb.lo = o.origin;
    pb.hi = o.origin + Vec3{nx * L.x, ny * L.y, nz * L.z};
    world.set_periodic(pb);
  }
  const std::int64_t base = world.clock().next_id;
  const std::size_t ncopies = static_cast<std::size_t>(nx) * ny * nz;
  std::vector<std::uint8_t> kept(ncopies * N, 0);
  auto copy_index = [&](int a, int b, int c) {
    return static_cast<std::size_t>(a + nx * (b + ny * c));
  };
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < ny; ++b)
      for (int a = 0; a < nx; ++a) {
        const std::size_t ci = copy_index(a, b, c);
        const Vec3 shift = o.origin + Vec3{a * L.x, b * L.y, c * L.z};
        for (std::size_t k = 0; k < N; ++k) {
          const Vec3 x = brick.position[k] + shift;
          if (o.keep) {
            bool inside = true;
            for (int ax = 0; ax < 3; ++ax) // periodic axes are filled exactly: no cut there
              if (!o.periodic[static_cast<std::size_t>(ax)] &&
                  (x[ax] < o.keep->lo[ax] || x[ax] > o.keep->hi[ax]))
                inside = false;
            if (!inside) continue;
          }
          world.add_particle(x, brick.radius[k], brick.density_kg_m3, brick.group,
                             base + static_cast<std::int64_t>(ci * N + k));
          kept[ci * N + k] = 1;
          ++res.particles;
        }
      }
  std::vector<ContactRecord> records;
  records.reserve(brick.contacts.size() * ncopies);
  const std::array<int, 3> n = o.copies;
  for (const ContactRecord& bc : brick.contacts) {
    if (bc.wall >= 0) continue;
    const auto k1 = static_cast<std::size_t>(bc.id1 - 1), k2 = static_cast<std::size_t>(bc.id2 - 1);
    for (int c = 0; c < nz; ++c)
      for (int b = 0; b < ny; ++b)
        for (int a = 0; a < nx; ++a) {
          const std::array<int, 3> from{a, b, c};
          std::array<int, 3> to{};
          ContactRecord rec = bc;
          bool exists = true;
          for (std::size_t ax = 0; ax < 3; ++ax) {
            int t = from[ax] + bc.image[ax];
            int img = 0;
            if (t < 0 || t >= n[ax]) {
              if (!o.periodic[ax]) {
                exists = false;
                break;
              }
              img = t < 0 ? -1 : 1;
              t -= img * n[ax];
            }
            to[ax] = t;
            rec.image[ax] = static_cast<std::int8_t>(img);
          }
          if (!exists) continue;
          const std::size_t c1 = copy_index(a, b, c), c2 = copy_index(to[0], to[1], to[2]);
          if (!kept[c1 * N + k1] || !kept[c2 * N + k2]) continue;
          rec.id1 = base + static_cast<std::int64_t>(c1 * N + k1);
          rec.id2 = base + static_cast<std::int64_t>(c2 * N + k2);
          records.push_back(rec);
        }
  }
  res.contacts = records.size();
  world.restore_contacts(records);
  return res;
}

// ------------------------------------------------------------------- report --

SpecimenReport specimen_report(const World& w, const Box& region,
                               const std::vector<GradationBin>& bins, double target_porosity) {
  SpecimenReport r;
  r.region = region;
  const RegionMeasurement m = w.measure_region(region);
  r.particles = m.particles;
  r.porosity = m.porosity;
  r.number_density_per_m3 = static_cast<double>(m.particles) / region.volume();
  const ParticleStore& p = w.particles();
  std::vector<double> radii;
  radii.reserve(p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    if (region.contains(p.position[i])) radii.push_back(p.radius[i]);
  r.d50_m = mass_median_diameter(radii);
  r.target_porosity = target_porosity;
  if (!bins.empty()) {
    r.target_d50_m = target_d50(bins);
    if (target_porosity > 0)
      r.expected_particles =
          (1 - target_porosity) * region.volume() * particles_per_solid_volume(bins);
    const std::vector<double> f = volume_fractions(radii, bins);
    for (std::size_t k = 0; k < bins.size(); ++k) r.bins.push_back({bins[k], f[k], 0});
    r.outside_bins_fraction = f.back();
    for (double rad : radii) {
      const double d = 2 * rad;
      for (BinReport& b : r.bins)
        if (d >= b.target.d_min_m * (1 - 1e-12) && d <= b.target.d_max_m * (1 + 1e-12)) {
          ++b.particles;
          break;
        }
    }
  }
  return r;
}

json to_json(const SpecimenReport& r) {
  json j;
  j["source"] = r.source;
  j["particles"] = r.particles;
  j["porosity"] = r.porosity;
  j["number_density_per_m3"] = r.number_density_per_m3;
  j["d50_m"] = r.d50_m;
  j["region"] = {{"lo_m", vec_json(r.region.lo)},
                 {"hi_m", vec_json(r.region.hi)},
                 {"volume_m3", r.region.volume()}};
  json target = json::object();
  if (r.target_porosity > 0) target["porosity"] = r.target_porosity;
  if (r.target_d50_m > 0) target["d50_m"] = r.target_d50_m;
  if (r.expected_particles > 0) target["particles_expected"] = r.expected_particles;
  j["target"] = target;
  json bins = json::array();
  for (const BinReport& b : r.bins)
    bins.push_back({{"d_min_m", b.target.d_min_m},
                    {"d_max_m", b.target.d_max_m},
                    {"target_volume_fraction", b.target.volume_fraction},
                    {"generated_volume_fraction", b.generated_volume_fraction},
                    {"particles", b.particles}});
  j["bins"] = bins;
  if (!r.bins.empty()) j["outside_bins_volume_fraction"] = r.outside_bins_fraction;
  j["contacts"] = r.contacts;
  if (r.has_brick)
    j["brick"] = {{"size_m", vec_json(r.brick_size_m)},
                  {"particles", r.brick_particles},
                  {"contacts", r.brick_contacts},
                  {"copies", r.copies},
                  {"seed", r.seed},
                  {"relax", relax_json(r.relax)},
                  {"seconds", r.brick_seconds}};
  return j;
}

std::string format_report(const SpecimenReport& r) {
  std::string o;
  const Vec3 s = r.region.hi - r.region.lo;
  o += fmt::format("specimen ({}): {} particles in a {:.4g} x {:.4g} x {:.4g} mm region", r.source,
                   r.particles, s.x * 1e3, s.y * 1e3, s.z * 1e3);
  if (r.expected_particles > 0) o += fmt::format(" (expected {:.0f})", r.expected_particles);
  o += "\n";
  o += fmt::format("  porosity ignoring overlaps: {:.4f}", r.porosity);
  if (r.target_porosity > 0) o += fmt::format(" (target {:.4f})", r.target_porosity);
  o += fmt::format("\n  number density: {:.4g} per m^3 ({:.2f} per mm^3)\n",
                   r.number_density_per_m3, r.number_density_per_m3 * 1e-9);
  o += fmt::format("  d50 (mass median): {:.4f} mm", r.d50_m * 1e3);
  if (r.target_d50_m > 0) o += fmt::format(" (target {:.4f} mm)", r.target_d50_m * 1e3);
  o += "\n";
  for (const BinReport& b : r.bins)
    o += fmt::format(
        "  {:.4g}-{:.4g} mm: {:6.2f} % of the volume (target {:6.2f} %), {} particles\n",
        b.target.d_min_m * 1e3, b.target.d_max_m * 1e3, 100 * b.generated_volume_fraction,
        100 * b.target.volume_fraction, b.particles);
  if (r.outside_bins_fraction > 0)
    o +=
        fmt::format("  outside every bin: {:.2f} % of the volume\n", 100 * r.outside_bins_fraction);
  if (r.has_brick)
    o += fmt::format("  brick: {:.4g} x {:.4g} x {:.4g} mm, {} particles, {} contacts, seed {}; "
                     "copies {} x {} x {}; relaxed in {} + {} steps (ratio {:.3g}, max overlap "
                     "{:.3g} R){}; {:.1f} s\n",
                     r.brick_size_m.x * 1e3, r.brick_size_m.y * 1e3, r.brick_size_m.z * 1e3,
                     r.brick_particles, r.brick_contacts, r.seed, r.copies[0], r.copies[1],
                     r.copies[2], r.relax.packing_steps, r.relax.contact_steps, r.relax.ratio,
                     r.relax.max_overlap_ratio, r.relax.converged ? "" : ", NOT converged",
                     r.brick_seconds);
  return o;
}

// -------------------------------------------------------------------- build --

double estimated_specimen_particles(const SpecimenSpec& spec,
                                    const std::vector<GradationBin>& bins) {
  if (spec.source == SpecimenSpec::Source::file || !spec.region || bins.empty()) return 0;
  const Vec3 e = spec.region->hi - spec.region->lo;
  return (1 - spec.porosity) * e.x * e.y * e.z * particles_per_solid_volume(bins);
}

void check_specimen_size(const SpecimenSpec& spec, const std::vector<GradationBin>& bins) {
  // 645 bytes per particle: what the engine holds per particle on the benchmark packing
  // (docs/results/bench.md), contacts and neighbour lists included.
  constexpr double kBytesPerParticle = 645;
  if (spec.source != SpecimenSpec::Source::file && spec.brick_file.empty() && !bins.empty()) {
    const Vec3 b = spec.brick_size_m;
    const double nb = (1 - spec.porosity) * b.x * b.y * b.z * particles_per_solid_volume(bins);
    if (!(nb <= spec.max_particles))
      throw InputError(
          "specimen.brick.size_m", fmt::format("[{:g}, {:g}, {:g}] m", b.x, b.y, b.z),
          fmt::format("the brick would hold about {:.3g} particles (about {:.3g} GB), more than "
                      "specimen.max_particles = {:g}. Lengths are in metres: a size written in "
                      "mm asks for 1e9 times too many",
                      nb, nb * kBytesPerParticle / 1e9, spec.max_particles));
  }
  const double n = estimated_specimen_particles(spec, bins);
  if (!(n <= spec.max_particles)) {
    const Vec3 e = spec.region->hi - spec.region->lo;
    throw InputError(
        "specimen.region", fmt::format("{:g} x {:g} x {:g} m", e.x, e.y, e.z),
        fmt::format("would hold about {:.3g} particles (about {:.3g} GB), more than "
                    "specimen.max_particles = {:g}. Lengths are in metres: a region written in "
                    "mm asks for 1e9 times too many. For a model that big, raise the limit "
                    "(--set specimen.max_particles=N)",
                    n, n * kBytesPerParticle / 1e9, spec.max_particles));
  }
}

BuiltSpecimen build_specimen(const SpecimenSpec& spec, World& world, const SpecimenLog& log,
                             int threads) {
  BuiltSpecimen out;
  const std::vector<GradationBin> bins = resolve_gradation(spec); // checks first
  check_specimen_size(spec, bins);
  if (spec.source == SpecimenSpec::Source::file) {
    std::vector<ParticleRecord> recs;
    try {
      recs = read_particle_file(spec.file_path);
    } catch (const InputError& e) {
      throw InputError(std::string("specimen.file: ") + e.what());
    }
    Box region;
    if (spec.region) {
      region = *spec.region;
    } else {
      region = {recs[0].position, recs[0].position};
      for (const ParticleRecord& q : recs)
        for (int a = 0; a < 3; ++a) {
          region.lo[a] = std::min(region.lo[a], q.position[a] - q.radius);
          region.hi[a] = std::max(region.hi[a], q.position[a] + q.radius);
        }
    }
    for (const ParticleRecord& q : recs)
      if (!spec.region || region.contains(q.position))
        world.add_particle(q.position, q.radius, spec.density_kg_m3, spec.group);
    out.report = specimen_report(world, region, bins, spec.porosity);
    out.report.source = "particle file";
    return out;
  }

  const Box region = *spec.region;
  const auto t0 = std::chrono::steady_clock::now();
  Brick brick;
  if (!spec.brick_file.empty()) {
    brick = read_brick(spec.brick_file_path);
    say(log, fmt::format("brick: {} particles and {} contacts read from {}", brick.size(),
                         brick.contacts.size(), spec.brick_file_path));
  } else {
    if (bins.empty())
      throw InputError("specimen.gradation", "(missing)", "a gradation is required");
    brick = make_brick(bins, spec.porosity, spec.brick_size_m, spec.density_kg_m3, spec.group,
                       spec.seed, spec.relax, log, threads);
  }
  brick.density_kg_m3 = spec.density_kg_m3;
  brick.group = spec.group;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::array<int, 3> copies = copies_to_fill(brick.size_m, region);
  for (int a = 0; a < 3; ++a) {
    if (!spec.periodic[static_cast<std::size_t>(a)]) continue;
    const double span = region.hi[a] - region.lo[a];
    const double filled = copies[static_cast<std::size_t>(a)] * brick.size_m[a];
    if (std::abs(filled - span) > 1e-9 * span)
      throw InputError(fmt::format("specimen.periodic[{}]", a), "true",
                       fmt::format("a periodic axis needs a whole number of bricks: the region "
                                   "is {:.6g} m along {}, the brick {:.6g} m ({:.6g} bricks)",
                                   span, "xyz"[a], brick.size_m[a], span / brick.size_m[a]));
  }
  AssemblyOptions ao;
  ao.origin = region.lo;
  ao.copies = copies;
  ao.periodic = spec.periodic;
  ao.keep = region;
  const AssemblyResult ar = assemble_bricks(brick, world, ao);
  say(log, fmt::format("assembled {} x {} x {} bricks: {} particles, {} contacts", copies[0],
                       copies[1], copies[2], ar.particles, ar.contacts));
  out.report = specimen_report(world, region, bins,
                               spec.porosity > 0 ? spec.porosity : brick.target_porosity);
  out.report.source = spec.brick_file.empty() ? "distribute" : "brick file";
  out.report.contacts = ar.contacts;
  out.report.has_brick = true;
  out.report.brick_size_m = brick.size_m;
  out.report.brick_particles = brick.size();
  out.report.brick_contacts = brick.contacts.size();
  out.report.copies = copies;
  out.report.seed = brick.seed;
  out.report.relax = brick.relax;
  out.report.brick_seconds = seconds;
  out.brick = std::move(brick);
  return out;
}

void write_specimen_outputs(const World& world, const BuiltSpecimen& built,
                            const SpecimenSpec& spec, const std::string& dir) {
  make_directories(dir);
  const fs::path d(dir);
  write_particles_vtu(world, (d / "specimen.vtu").string());
  plot_grain_size_curves(world.particles().radius, spec, (d / "gsd.png").string());
  {
    const ParticleStore& p = world.particles();
    std::vector<std::size_t> order(p.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return p.id[a] < p.id[b]; });
    auto f = fmt::output_file((d / "specimen.xyzr").string());
    f.print("# x y z r (SI: m), one particle per line, in id order; centridem generate\n");
    for (std::size_t i : order)
      f.print("{} {} {} {}\n", p.position[i].x, p.position[i].y, p.position[i].z, p.radius[i]);
  }
  {
    std::ofstream f(d / "specimen.json");
    f << to_json(built.report).dump(2) << '\n';
    if (!f)
      throw InputError("output file", "\"" + (d / "specimen.json").string() + "\"", "write failed");
  }
  {
    std::ofstream f(d / "specimen.toml");
    f << "# The resolved specimen (every default explicit); centridem generate\n"
      << resolved_specimen_toml(spec);
  }
  if (built.brick) write_brick(*built.brick, (d / "brick.json").string());
}

void assign_ball_ball_contacts(World& w, const ContactProperties& c) {
  w.set_ball_ball_defaults(c);
  w.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                              [&](ContactProperties& p) { p = c; });
}

double solid_volume_m3(const ParticleStore& P) {
  double v = 0;
  for (double r : P.radius) v += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  return v;
}

long calm_into_walls(World& w) {
  const double guard = w.settings().max_overlap_fraction;
  w.set_max_overlap_fraction(std::max(guard, 3.0));
  long steps = 0;
  // At least one chunk: the walls' contacts exist only after a cycle.
  for (long k = 0; k == 0 || (k < 2000 && w.measure().max_overlap_ratio > 0.05); ++k) {
    w.cycle(10);
    auto& P = w.particles_mut();
    std::fill(P.velocity.begin(), P.velocity.end(), Vec3{});
    std::fill(P.spin.begin(), P.spin.end(), Vec3{});
    steps += 10;
  }
  w.set_max_overlap_fraction(guard);
  return steps;
}

} // namespace centridem
