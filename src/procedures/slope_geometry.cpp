#include "procedures/slope_geometry.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <numbers>

namespace centridem {

namespace {

constexpr double deg = std::numbers::pi / 180.0;

// Horizontal run of a face of height h at angle a (degrees from horizontal);
// exactly 0 for a vertical face.
double face_run(double h, double angle_deg) {
  return angle_deg >= 90.0 ? 0.0 : h / std::tan(angle_deg * deg);
}

void require(bool ok, const std::string& key, double value, const std::string& allowed) {
  if (!ok || !std::isfinite(value)) throw InputError(key, fmt::format("{:g}", value), allowed);
}

// Tolerance for sums of lengths given in metres (round-off of decimal input).
double length_tolerance(double scale) {
  return 1e-9 * std::max(1.0, scale);
}

} // namespace

BenchedSlope BenchedSlope::paper_lower_first_bench() {
  BenchedSlope s;
  s.benches = {Bench{0.0375, 0.03, 70.0}, Bench{0.1125, std::nullopt, 70.0}};
  return s;
}

BenchedSlope BenchedSlope::paper_higher_first_bench() {
  BenchedSlope s;
  s.benches = {Bench{0.075, 0.03, 70.0}, Bench{0.075, std::nullopt, 70.0}};
  return s;
}

void validate(const BenchedSlope& s, const std::string& where) {
  auto k = [&](const std::string& name) { return where + "." + name; };
  // Below 1e-4 the DEM box of a metre-high model is under 0.1 mm and gravity n g / s beyond
  // 1e5 g per g-level: a typo, not a model.
  require(s.size_reduction_factor >= 1e-4 && s.size_reduction_factor <= 1,
          k("size_reduction_factor"), s.size_reduction_factor,
          "must be in [1e-4, 1] (DEM lengths = model lengths x s)");
  require(s.total_height_m > 0, k("total_height_m"), s.total_height_m, "must be > 0 [m]");
  require(s.foundation_height_m >= 0 && s.foundation_height_m < s.total_height_m,
          k("foundation_height_m"), s.foundation_height_m,
          fmt::format("must be in [0, total_height_m = {:g}) [m]", s.total_height_m));
  require(s.breadth_m > 0, k("breadth_m"), s.breadth_m, "must be > 0 [m]");
  require(s.crest_to_wall_m >= 0, k("crest_to_wall_m"), s.crest_to_wall_m, "must be >= 0 [m]");
  require(s.length_m > 0, k("length_m"), s.length_m, "must be > 0 [m]");
  if (s.benches.empty())
    throw InputError(k("benches"), "[]", "at least one bench {height_m, width_m, face_angle_deg}");
  const std::size_t n = s.benches.size();
  double heights = 0.0, x = s.crest_to_wall_m;
  for (std::size_t b = 0; b < n; ++b) {
    const Bench& bench = s.benches[b];
    const std::string key = fmt::format("{}.benches[{}]", where, b);
    require(bench.height_m > 0, key + ".height_m", bench.height_m, "must be > 0 [m]");
    require(bench.face_angle_deg > 0 && bench.face_angle_deg <= 90, key + ".face_angle_deg",
            bench.face_angle_deg, "must be in (0, 90] degrees from horizontal");
    if (b + 1 < n) {
      if (!bench.width_m)
        throw InputError(key + ".width_m", "(missing)",
                         "required for every bench below the top one (width of its top) [m]");
      require(*bench.width_m >= 0, key + ".width_m", *bench.width_m, "must be >= 0 [m]");
      x += *bench.width_m;
    } else if (bench.width_m) {
      require(std::abs(*bench.width_m - s.crest_to_wall_m) <= length_tolerance(s.crest_to_wall_m),
              key + ".width_m", *bench.width_m,
              fmt::format("the top bench's width is the crest plateau: leave it out or give "
                          "crest_to_wall_m = {:g} [m]",
                          s.crest_to_wall_m));
    }
    heights += bench.height_m;
    x += face_run(bench.height_m, bench.face_angle_deg);
  }
  const double slope_height = s.total_height_m - s.foundation_height_m;
  if (std::abs(heights - slope_height) > length_tolerance(slope_height))
    throw InputError(k("benches"), fmt::format("heights adding up to {:g} m", heights),
                     fmt::format("bench heights must add up to total_height_m - "
                                 "foundation_height_m = {:g} m",
                                 slope_height));
  if (x > s.length_m + length_tolerance(s.length_m))
    throw InputError(k("length_m"), fmt::format("{:g}", s.length_m),
                     fmt::format("the benches do not fit: the toe lies at x = {:.6g} m from the "
                                 "back wall (crest_to_wall_m + bench widths + face runs); "
                                 "length_m must be at least that",
                                 x));
}

std::string_view to_string(SlopeZone zone) {
  switch (zone) {
  case SlopeZone::crest:
    return "crest";
  case SlopeZone::upper_face:
    return "upper_face";
  case SlopeZone::bench_top:
    return "bench_top";
  case SlopeZone::lower_face:
    return "lower_face";
  case SlopeZone::toe:
    return "toe";
  }
  return "?";
}

std::string to_string(const ZoneId& z) {
  if (z.zone == SlopeZone::bench_top || z.zone == SlopeZone::lower_face)
    return fmt::format("{}_{}", to_string(z.zone), z.bench);
  return std::string(to_string(z.zone));
}

SlopeGeometry::SlopeGeometry(BenchedSlope slope) : slope_(std::move(slope)) {
  validate(slope_);
  const double s = slope_.size_reduction_factor;
  const int n = bench_count();
  length_ = slope_.length_m * s;
  breadth_ = slope_.breadth_m * s;
  height_ = slope_.total_height_m * s;
  toe_z_ = slope_.foundation_height_m * s;
  crest_x_ = slope_.crest_to_wall_m * s;
  face_foot_x_.assign(static_cast<std::size_t>(n), 0.0);

  // Walk the surface from the back wall down to the toe.
  double x = crest_x_, z = height_;
  outline_ = {{0.0, height_}, {x, z}};
  segments_.push_back({0.0, height_, x, z, {SlopeZone::crest, n}});
  for (int b = n; b >= 1; --b) {
    const Bench& bench = slope_.benches[static_cast<std::size_t>(b - 1)];
    const double h = bench.height_m * s;
    const double x1 = x + face_run(h, bench.face_angle_deg);
    const double z1 = z - h;
    segments_.push_back(
        {x, z, x1, z1, {b == n ? SlopeZone::upper_face : SlopeZone::lower_face, b}});
    outline_.push_back({x1, z1});
    face_foot_x_[static_cast<std::size_t>(b - 1)] = x1;
    x = x1, z = z1;
    if (b > 1) { // the top of the bench below
      const double w = *slope_.benches[static_cast<std::size_t>(b - 2)].width_m * s;
      segments_.push_back({x, z, x + w, z, {SlopeZone::bench_top, b - 1}});
      x += w;
      outline_.push_back({x, z});
    }
  }
  toe_x_ = x;
  z = toe_z_; // exact (the walk subtracts bench heights)
  outline_.back().z = z;
  segments_.back().z1 = z;
  if (length_ > toe_x_) {
    segments_.push_back({toe_x_, z, length_, z, {SlopeZone::toe, 0}});
    outline_.push_back({length_, z});
  }
}

double SlopeGeometry::z_surface(double x) const {
  x = std::clamp(x, 0.0, length_);
  for (const OutlineSegment& g : segments_) {
    if (x < g.x0 || x > g.x1) continue;
    if (g.x1 <= g.x0) return std::max(g.z0, g.z1); // vertical face
    const double t = (x - g.x0) / (g.x1 - g.x0);
    return g.z0 + t * (g.z1 - g.z0);
  }
  return toe_z_; // x = length with the toe at the end of the model
}

bool SlopeGeometry::is_soil(const Vec3& p) const {
  return p.x >= 0 && p.x <= length_ && p.y >= 0 && p.y <= breadth_ && p.z >= 0 &&
         p.z <= z_surface(p.x);
}

bool SlopeGeometry::excavated(const Vec3& p) const {
  return p.z > z_surface(p.x);
}

std::function<bool(std::size_t)> SlopeGeometry::excavation_predicate(const World& world) const {
  const ParticleStore& P = world.particles();
  return [this, &P](std::size_t i) { return excavated(P.position[i]); };
}

std::size_t SlopeGeometry::excavate(World& world) const {
  return world.remove_particles(excavation_predicate(world));
}

std::vector<SectionPoint> SlopeGeometry::outline() const {
  return outline_;
}

ZoneId SlopeGeometry::classify(double x, double z) const {
  double best = INFINITY;
  ZoneId zone;
  for (const OutlineSegment& g : segments_) {
    const double dx = g.x1 - g.x0, dz = g.z1 - g.z0;
    const double len2 = dx * dx + dz * dz;
    const double t =
        len2 > 0 ? std::clamp(((x - g.x0) * dx + (z - g.z0) * dz) / len2, 0.0, 1.0) : 0.0;
    const double ex = x - (g.x0 + t * dx), ez = z - (g.z0 + t * dz);
    const double d2 = ex * ex + ez * ez;
    if (d2 < best) best = d2, zone = g.zone;
  }
  return zone;
}

int SlopeGeometry::bench_at(double x) const {
  for (int b = bench_count(); b >= 1; --b) // from the back wall outwards
    if (x <= face_foot_x_[static_cast<std::size_t>(b - 1)]) return b;
  return 0;
}

std::pair<double, double> SlopeGeometry::bench_column(int bench) const {
  const int n = bench_count();
  if (bench < 0 || bench > n)
    throw InputError("bench", std::to_string(bench), fmt::format("must be in [0, {}]", n));
  if (bench == 0) return {toe_x_, length_};
  const double end = face_foot_x_[static_cast<std::size_t>(bench - 1)];
  const double begin = bench == n ? 0.0 : face_foot_x_[static_cast<std::size_t>(bench)];
  return {begin, end};
}

double SlopeGeometry::soil_area_model_m2() const {
  // Trapezoids under the outline (DEM), scaled back to model by 1/s^2.
  double area = 0.0;
  for (const OutlineSegment& g : segments_) area += 0.5 * (g.z0 + g.z1) * (g.x1 - g.x0);
  const double s = scale();
  return area / (s * s);
}

nlohmann::json to_json(const SlopeGeometry& g) {
  using nlohmann::json;
  const BenchedSlope& in = g.input();
  json benches = json::array();
  for (const Bench& b : in.benches) {
    json j = {{"height_m", b.height_m}, {"face_angle_deg", b.face_angle_deg}};
    j["width_m"] = b.width_m ? *b.width_m : in.crest_to_wall_m;
    benches.push_back(j);
  }
  json outline = json::array();
  for (const SectionPoint& p : g.outline()) outline.push_back({p.x, p.z});
  json zones = json::array();
  for (const OutlineSegment& s : g.segments())
    zones.push_back({{"zone", to_string(s.zone)},
                     {"bench", s.zone.bench},
                     {"from", {s.x0, s.z0}},
                     {"to", {s.x1, s.z1}}});
  json columns = json::array();
  for (int b = 0; b <= g.bench_count(); ++b) {
    const auto [x0, x1] = g.bench_column(b);
    columns.push_back({{"bench", b}, {"x_begin_m", x0}, {"x_end_m", x1}});
  }
  return {{"model_scale",
           {{"total_height_m", in.total_height_m},
            {"foundation_height_m", in.foundation_height_m},
            {"benches", benches},
            {"breadth_m", in.breadth_m},
            {"crest_to_wall_m", in.crest_to_wall_m},
            {"length_m", in.length_m},
            {"size_reduction_factor", in.size_reduction_factor}}},
          {"dem",
           {{"length_m", g.length()},
            {"breadth_m", g.breadth()},
            {"height_m", g.height()},
            {"toe_height_m", g.toe_height()},
            {"crest_x_m", g.crest_x()},
            {"toe_x_m", g.toe_x()}}},
          {"outline_xz_m", outline},
          {"zones", zones},
          {"bench_columns", columns},
          {"excavated_area_fraction", g.excavated_fraction()}};
}

} // namespace centridem
