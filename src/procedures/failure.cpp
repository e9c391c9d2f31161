#include "procedures/failure.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>

namespace centridem {

namespace {

double sphere_volume(double r) {
  return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

void require(bool ok, const std::string& key, double value, const std::string& allowed) {
  if (!ok || !std::isfinite(value)) throw InputError(key, fmt::format("{:g}", value), allowed);
}

// Union-find with path halving.
struct DisjointSets {
  std::vector<std::uint32_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Empties the sliding-mass fields of a report.
void clear_mass(FailureReport& r) {
  r.sliding_mass = false;
  r.particles = 0;
  r.volume_m3 = r.particle_share = r.volume_share = 0.0;
  r.mean_speed_m_s = r.mean_displacement_m = r.max_displacement_m = 0.0;
  r.benches_crossed.clear();
  r.source_benches.clear();
  r.particles_from_bench.clear();
  r.slip_surface.clear();
  r.front_x_m = r.runout_m = r.runout_model_m = 0.0;
}

} // namespace

void validate(const FailureCriteria& c, const std::string& where) {
  auto k = [&](const char* name) { return where + "." + name; };
  require(c.mass.displacement_threshold_d50 > 0, k("displacement_threshold_d50"),
          c.mass.displacement_threshold_d50, "must be > 0 (median diameters)");
  require(c.mass.displacement_threshold_m >= 0, k("displacement_threshold_m"),
          c.mass.displacement_threshold_m, "must be >= 0 [m] (0: use displacement_threshold_d50)");
  require(c.mass.link_distance_factor >= 1, k("link_distance_factor"), c.mass.link_distance_factor,
          "must be >= 1 (centre distance / (Ri + Rj); 1 = touching)");
  require(c.min_volume_fraction >= 0 && c.min_volume_fraction <= 1, k("min_volume_fraction"),
          c.min_volume_fraction, "must be in [0, 1]");
  if (c.min_particles < 1)
    throw InputError(k("min_particles"), "0", "must be >= 1 (particles in a sliding mass)");
  require(c.moving_speed_factor > 0, k("moving_speed_factor"), c.moving_speed_factor,
          "must be > 0 (x sqrt(g d50))");
  require(c.moving_speed_m_s >= 0, k("moving_speed_m_s"), c.moving_speed_m_s,
          "must be >= 0 [m/s] (0: use moving_speed_factor)");
  require(c.failure_displacement_d50 >= 0, k("failure_displacement_d50"),
          c.failure_displacement_d50, "must be >= 0 (median diameters; 0 = off)");
  require(c.consecutive_checks >= 1, k("consecutive_checks"), c.consecutive_checks, "must be >= 1");
  require(c.equilibrium_ratio > 0, k("equilibrium_ratio"), c.equilibrium_ratio, "must be > 0");
  require(c.growth_tolerance >= 0, k("growth_tolerance"), c.growth_tolerance, "must be >= 0");
  require(c.slip_surface_bin_d50 > 0, k("slip_surface_bin_d50"), c.slip_surface_bin_d50,
          "must be > 0 (median diameters)");
  require(c.start_share > 0 && c.start_share <= 1, k("start_share"), c.start_share,
          "must be in (0, 1]");
  require(c.bench_share >= 0 && c.bench_share <= 1, k("bench_share"), c.bench_share,
          "must be in [0, 1]");
}

double median_diameter(const ParticleStore& p) {
  const std::size_t n = p.size();
  if (n == 0) return 0.0;
  std::vector<double> r(p.radius.begin(), p.radius.end());
  std::sort(r.begin(), r.end());
  double total = 0.0;
  for (double x : r) total += x * x * x;
  double sum = 0.0;
  for (double x : r) {
    sum += x * x * x;
    if (sum >= 0.5 * total) return 2.0 * x;
  }
  return 2.0 * r.back();
}

SlidingMass find_sliding_mass(const World& world, const SlidingMassCriteria& c, double d50_m) {
  const ParticleStore& P = world.particles();
  SlidingMass out;
  out.threshold_m = c.displacement_threshold_m > 0 ? c.displacement_threshold_m
                                                   : c.displacement_threshold_d50 * d50_m;
  const double t2 = out.threshold_m * out.threshold_m;
  std::vector<std::uint32_t> cand;
  double r_max = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i)
    if (norm2(P.displacement[i]) > t2) {
      cand.push_back(static_cast<std::uint32_t>(i));
      r_max = std::max(r_max, P.radius[i]);
    }
  out.above_threshold = cand.size();
  if (cand.empty()) return out;

  // Cell grid over the candidates: a cell of f x 2 R_max holds every linked
  // pair within one cell step.
  const double f = c.link_distance_factor;
  const double cell = f * 2.0 * r_max;
  Vec3 lo = P.position[cand[0]];
  for (std::uint32_t i : cand)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], P.position[i][a]);
  auto cell_of = [&](const Vec3& x) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>((x.x - lo.x) / cell),
                                       static_cast<std::int64_t>((x.y - lo.y) / cell),
                                       static_cast<std::int64_t>((x.z - lo.z) / cell)};
  };
  constexpr std::int64_t span = 1 << 20; // cells per axis in the key
  auto key = [&](std::int64_t ix, std::int64_t iy, std::int64_t iz) {
    return (ix * span + iy) * span + iz;
  };
  std::vector<std::pair<std::int64_t, std::uint32_t>> cells; // (cell key, candidate slot)
  cells.reserve(cand.size());
  for (std::uint32_t k = 0; k < cand.size(); ++k) {
    const auto ci = cell_of(P.position[cand[k]]);
    cells.emplace_back(key(ci[0], ci[1], ci[2]), k);
  }
  std::sort(cells.begin(), cells.end());
  DisjointSets sets(cand.size());
  for (std::uint32_t k = 0; k < cand.size(); ++k) {
    const std::size_t i = cand[k];
    const auto ci = cell_of(P.position[i]);
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          if (ci[0] + dx < 0 || ci[1] + dy < 0 || ci[2] + dz < 0) continue;
          const std::int64_t kk = key(ci[0] + dx, ci[1] + dy, ci[2] + dz);
          auto it = std::lower_bound(cells.begin(), cells.end(),
                                     std::pair<std::int64_t, std::uint32_t>{kk, 0});
          for (; it != cells.end() && it->first == kk; ++it) {
            const std::uint32_t m = it->second;
            if (m <= k) continue;
            const std::size_t j = cand[m];
            const double reach = f * (P.radius[i] + P.radius[j]);
            if (norm2(P.position[j] - P.position[i]) <= reach * reach) sets.unite(k, m);
          }
        }
  }
  std::vector<double> volume(cand.size(), 0.0);
  for (std::uint32_t k = 0; k < cand.size(); ++k)
    volume[sets.find(k)] += sphere_volume(P.radius[cand[k]]);
  std::uint32_t best = 0;
  for (std::uint32_t k = 0; k < cand.size(); ++k) {
    if (sets.find(k) == k) ++out.groups;
    if (volume[k] > volume[best]) best = k;
  }
  out.volume_m3 = volume[best];
  for (std::uint32_t k = 0; k < cand.size(); ++k)
    if (sets.find(k) == best) out.indices.push_back(cand[k]);
  std::sort(out.indices.begin(), out.indices.end());
  return out;
}

std::string_view to_string(SlopeState s) {
  switch (s) {
  case SlopeState::undecided:
    return "undecided";
  case SlopeState::stable:
    return "stable";
  case SlopeState::failed:
    return "failed";
  }
  return "?";
}

FailureMonitor::FailureMonitor(SlopeGeometry geometry, FailureCriteria criteria)
    : geometry_(std::move(geometry)), criteria_(criteria) {
  validate(criteria_);
}

SlopeState FailureMonitor::update(const World& world, double time_s) {
  const ParticleStore& P = world.particles();
  FailureReport& r = report_;
  const int check = r.checks++;
  if (check == 0) {
    r.slope_particles = P.size();
    r.slope_volume_m3 = 0.0;
    double g = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i) {
      r.slope_volume_m3 += sphere_volume(P.radius[i]);
      g += norm(world.body_field().acceleration(P.position[i], Vec3{}));
    }
    r.gravity_m_s2 = P.size() > 0 ? g / static_cast<double>(P.size()) : 0.0;
    r.d50_m = median_diameter(P);
    r.moving_speed_m_s = criteria_.moving_speed_m_s > 0
                             ? criteria_.moving_speed_m_s
                             : criteria_.moving_speed_factor * std::sqrt(r.gravity_m_s2 * r.d50_m);
  }
  r.time_s = time_s;
  const double toe_z = geometry_.toe_height();
  r.unbalanced_force_ratio =
      world.mean_unbalanced_force_ratio([&](std::size_t i) { return P.position[i].z > toe_z; });
  r.model_unbalanced_force_ratio = world.mean_unbalanced_force_ratio();

  const SlidingMass mass = find_sliding_mass(world, criteria_.mass, r.d50_m);
  r.displacement_threshold_m = mass.threshold_m;
  r.above_threshold = mass.above_threshold;
  r.largest_group_particles = mass.size();
  const double t2 = mass.threshold_m * mass.threshold_m;
  for (std::size_t i = 0; i < P.size(); ++i)
    if (norm2(P.displacement[i]) > t2) first_check_above_.try_emplace(P.id[i], check);

  double speed = 0.0, moved = 0.0;
  for (std::size_t i : mass.indices) {
    speed += norm(P.velocity[i]);
    moved += norm(P.displacement[i]);
  }
  if (!mass.indices.empty()) {
    speed /= static_cast<double>(mass.size());
    moved /= static_cast<double>(mass.size());
  }

  const bool significant = mass.size() > 0 && mass.size() >= criteria_.min_particles &&
                           mass.volume_m3 >= criteria_.min_volume_fraction * r.slope_volume_m3;
  const bool moving = significant && speed > r.moving_speed_m_s &&
                      moved >= criteria_.failure_displacement_d50 * r.d50_m;
  const bool at_rest = r.unbalanced_force_ratio < criteria_.equilibrium_ratio;
  const bool growing =
      static_cast<double>(mass.size()) >
      static_cast<double>(previous_group_) * (1.0 + criteria_.growth_tolerance) + 1.0;
  previous_group_ = mass.size();
  history_.push_back({time_s, mass.above_threshold, mass.size(), speed, r.unbalanced_force_ratio,
                      significant, moving});

  const int need = criteria_.consecutive_checks;
  if (moving) {
    if (moving_streak_ == 0) { // a candidate onset: where is this mass now?
      streak_start_time_ = time_s;
      streak_start_zone_ = start_zone(world, mass);
    }
    ++moving_streak_;
  } else {
    moving_streak_ = 0;
  }
  stable_streak_ = (at_rest && !moving && !growing) ? stable_streak_ + 1 : 0;
  settled_streak_ = at_rest ? settled_streak_ + 1 : 0;
  r.settled = settled_streak_ >= need;

  if (r.state != SlopeState::failed && moving_streak_ >= need) {
    r.state = SlopeState::failed;
    r.onset_time_s = streak_start_time_;
    r.start_zone = streak_start_zone_;
  } else if (r.state != SlopeState::failed) {
    r.state = stable_streak_ >= need ? SlopeState::stable : SlopeState::undecided;
  }

  if (significant)
    describe_mass(world, mass, speed);
  else if (r.state != SlopeState::failed)
    clear_mass(r); // no sliding mass to speak of (a failed report keeps its last one)
  return r.state;
}

void FailureMonitor::describe_mass(const World& world, const SlidingMass& mass, double mean_speed) {
  const ParticleStore& P = world.particles();
  FailureReport& r = report_;
  const SlopeGeometry& g = geometry_;
  const int n = g.bench_count();
  r.sliding_mass = true;
  r.particles = mass.size();
  r.volume_m3 = mass.volume_m3;
  r.particle_share = r.slope_particles > 0
                         ? static_cast<double>(mass.size()) / static_cast<double>(r.slope_particles)
                         : 0.0;
  r.volume_share = r.slope_volume_m3 > 0 ? mass.volume_m3 / r.slope_volume_m3 : 0.0;
  r.mean_speed_m_s = mean_speed;

  const double bin = criteria_.slip_surface_bin_d50 * r.d50_m;
  std::map<std::int64_t, double> lowest; // x bin -> lowest original centre z
  r.particles_from_bench.assign(static_cast<std::size_t>(n + 1), 0);
  double x_lo = INFINITY, x_hi = -INFINITY, sum_d = 0.0, max_d = 0.0;
  r.front_x_m = -INFINITY;
  for (std::size_t i : mass.indices) {
    const Vec3 x = P.position[i];
    const Vec3 x0 = x - P.displacement[i];
    const double d = norm(P.displacement[i]);
    sum_d += d, max_d = std::max(max_d, d);
    x_lo = std::min({x_lo, x.x, x0.x});
    x_hi = std::max({x_hi, x.x, x0.x});
    r.front_x_m = std::max(r.front_x_m, x.x);
    ++r.particles_from_bench[static_cast<std::size_t>(g.bench_at(x0.x))];
    const auto b = static_cast<std::int64_t>(std::floor(x0.x / bin));
    auto [it, fresh] = lowest.try_emplace(b, x0.z);
    if (!fresh) it->second = std::min(it->second, x0.z);
  }
  r.mean_displacement_m = sum_d / static_cast<double>(mass.size());
  r.max_displacement_m = max_d;
  r.slip_surface.clear();
  for (const auto& [b, z] : lowest)
    r.slip_surface.push_back({(static_cast<double>(b) + 0.5) * bin, z});
  r.benches_crossed.clear();
  for (int b = 1; b <= n; ++b) {
    const auto [c0, c1] = g.bench_column(b);
    if (x_hi >= c0 && x_lo <= c1) r.benches_crossed.push_back(b);
  }
  r.source_benches.clear();
  for (int b = 0; b <= n; ++b)
    if (r.particles_from_bench[static_cast<std::size_t>(b)] > 0 &&
        static_cast<double>(r.particles_from_bench[static_cast<std::size_t>(b)]) >=
            criteria_.bench_share * static_cast<double>(mass.size()))
      r.source_benches.push_back(b);
  r.runout_m = std::max(0.0, r.front_x_m - g.toe_x());
  r.runout_model_m = r.runout_m / g.scale();
}

ZoneId FailureMonitor::start_zone(const World& world, const SlidingMass& mass) const {
  const ParticleStore& P = world.particles();
  // Members ordered by the check at which they first exceeded the threshold.
  std::vector<std::pair<int, std::size_t>> order;
  order.reserve(mass.size());
  for (std::size_t i : mass.indices) {
    const auto it = first_check_above_.find(P.id[i]);
    order.emplace_back(it == first_check_above_.end() ? report_.checks : it->second, i);
  }
  std::sort(order.begin(), order.end());
  std::size_t take =
      std::max<std::size_t>(std::min<std::size_t>(10, order.size()),
                            static_cast<std::size_t>(std::ceil(criteria_.start_share *
                                                               static_cast<double>(order.size()))));
  take = std::min(take, order.size());
  while (take < order.size() && order[take].first == order[take - 1].first) ++take; // ties
  std::map<std::pair<int, int>, std::size_t> votes; // (zone, bench) -> count
  for (std::size_t k = 0; k < take; ++k) {
    const std::size_t i = order[k].second;
    const Vec3 x0 = P.position[i] - P.displacement[i];
    const ZoneId z = geometry_.classify(x0.x, x0.z);
    ++votes[{static_cast<int>(z.zone), z.bench}];
  }
  std::pair<int, int> best{static_cast<int>(SlopeZone::toe), 0};
  std::size_t most = 0;
  for (const auto& [z, count] : votes)
    if (count > most) most = count, best = z;
  return {static_cast<SlopeZone>(best.first), best.second};
}

nlohmann::json to_json(const FailureReport& r) {
  using nlohmann::json;
  json slip = json::array();
  for (const SectionPoint& p : r.slip_surface) slip.push_back({p.x, p.z});
  json j = {{"state", to_string(r.state)},
            {"settled", r.settled},
            {"checks", r.checks},
            {"time_s", r.time_s},
            {"unbalanced_force_ratio", r.unbalanced_force_ratio},
            {"model_unbalanced_force_ratio", r.model_unbalanced_force_ratio},
            {"d50_m", r.d50_m},
            {"gravity_m_s2", r.gravity_m_s2},
            {"displacement_threshold_m", r.displacement_threshold_m},
            {"moving_speed_m_s", r.moving_speed_m_s},
            {"slope_particles", r.slope_particles},
            {"slope_volume_m3", r.slope_volume_m3},
            {"onset_time_s", r.onset_time_s ? json(*r.onset_time_s) : json(nullptr)},
            {"start_zone", r.start_zone ? json(to_string(*r.start_zone)) : json(nullptr)},
            {"sliding_mass", r.sliding_mass},
            {"particles", r.particles},
            {"volume_m3", r.volume_m3},
            {"particle_share", r.particle_share},
            {"volume_share", r.volume_share},
            {"mean_speed_m_s", r.mean_speed_m_s},
            {"mean_displacement_m", r.mean_displacement_m},
            {"max_displacement_m", r.max_displacement_m},
            {"benches_crossed", r.benches_crossed},
            {"source_benches", r.source_benches},
            {"particles_from_bench", r.particles_from_bench},
            {"slip_surface_xz_m", slip},
            {"front_x_m", r.sliding_mass ? json(r.front_x_m) : json(nullptr)},
            {"runout_m", r.runout_m},
            {"runout_model_m", r.runout_model_m},
            {"largest_group_particles", r.largest_group_particles},
            {"above_threshold", r.above_threshold}};
  return j;
}

// ------------------------------------------------------------ checkpoints --

namespace {
nlohmann::json zone_json(const std::optional<ZoneId>& z) {
  if (!z) return nullptr;
  return {static_cast<int>(z->zone), z->bench};
}
std::optional<ZoneId> zone_from(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  return ZoneId{static_cast<SlopeZone>(j.at(0).get<int>()), j.at(1).get<int>()};
}
std::optional<double> opt_from(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  return j.get<double>();
}
} // namespace

nlohmann::json FailureMonitor::save() const {
  using nlohmann::json;
  const FailureReport& r = report_;
  json slip = json::array();
  for (const SectionPoint& p : r.slip_surface) slip.push_back({p.x, p.z});
  json report = {{"state", static_cast<int>(r.state)},
                 {"settled", r.settled},
                 {"checks", r.checks},
                 {"time_s", r.time_s},
                 {"ratio", r.unbalanced_force_ratio},
                 {"model_ratio", r.model_unbalanced_force_ratio},
                 {"d50_m", r.d50_m},
                 {"gravity_m_s2", r.gravity_m_s2},
                 {"threshold_m", r.displacement_threshold_m},
                 {"moving_speed_m_s", r.moving_speed_m_s},
                 {"slope_particles", r.slope_particles},
                 {"slope_volume_m3", r.slope_volume_m3},
                 {"onset_time_s", r.onset_time_s ? json(*r.onset_time_s) : json(nullptr)},
                 {"start_zone", zone_json(r.start_zone)},
                 {"sliding_mass", r.sliding_mass},
                 {"particles", r.particles},
                 {"volume_m3", r.volume_m3},
                 {"particle_share", r.particle_share},
                 {"volume_share", r.volume_share},
                 {"mean_speed_m_s", r.mean_speed_m_s},
                 {"mean_displacement_m", r.mean_displacement_m},
                 {"max_displacement_m", r.max_displacement_m},
                 {"benches_crossed", r.benches_crossed},
                 {"source_benches", r.source_benches},
                 {"particles_from_bench", r.particles_from_bench},
                 {"slip", slip},
                 {"front_x_m", r.front_x_m},
                 {"runout_m", r.runout_m},
                 {"runout_model_m", r.runout_model_m},
                 {"largest_group", r.largest_group_particles},
                 {"above_threshold", r.above_threshold}};
  json history = json::array();
  for (const FailureCheck& c : history_)
    history.push_back({c.time_s, c.above_threshold, c.mass_particles, c.mass_mean_speed_m_s,
                       c.unbalanced_force_ratio, c.significant, c.moving});
  json first = json::array();
  for (const auto& [id, check] : first_check_above_) first.push_back({id, check});
  return {{"report", report},
          {"history", history},
          {"first_check_above", first},
          {"moving_streak", moving_streak_},
          {"stable_streak", stable_streak_},
          {"settled_streak", settled_streak_},
          {"streak_start_time_s", streak_start_time_ ? json(*streak_start_time_) : json(nullptr)},
          {"streak_start_zone", zone_json(streak_start_zone_)},
          {"previous_group", previous_group_}};
}

void FailureMonitor::restore(const nlohmann::json& j) {
  const nlohmann::json& q = j.at("report");
  FailureReport r;
  r.state = static_cast<SlopeState>(q.at("state").get<int>());
  r.settled = q.at("settled");
  r.checks = q.at("checks");
  r.time_s = q.at("time_s");
  r.unbalanced_force_ratio = q.at("ratio");
  r.model_unbalanced_force_ratio = q.value("model_ratio", 0.0);
  r.d50_m = q.at("d50_m");
  r.gravity_m_s2 = q.at("gravity_m_s2");
  r.displacement_threshold_m = q.at("threshold_m");
  r.moving_speed_m_s = q.at("moving_speed_m_s");
  r.slope_particles = q.at("slope_particles");
  r.slope_volume_m3 = q.at("slope_volume_m3");
  r.onset_time_s = opt_from(q.at("onset_time_s"));
  r.start_zone = zone_from(q.at("start_zone"));
  r.sliding_mass = q.at("sliding_mass");
  r.particles = q.at("particles");
  r.volume_m3 = q.at("volume_m3");
  r.particle_share = q.at("particle_share");
  r.volume_share = q.at("volume_share");
  r.mean_speed_m_s = q.at("mean_speed_m_s");
  r.mean_displacement_m = q.at("mean_displacement_m");
  r.max_displacement_m = q.at("max_displacement_m");
  r.benches_crossed = q.at("benches_crossed").get<std::vector<int>>();
  r.source_benches = q.at("source_benches").get<std::vector<int>>();
  r.particles_from_bench = q.at("particles_from_bench").get<std::vector<std::size_t>>();
  for (const auto& p : q.at("slip")) r.slip_surface.push_back({p.at(0), p.at(1)});
  r.front_x_m = q.at("front_x_m");
  r.runout_m = q.at("runout_m");
  r.runout_model_m = q.at("runout_model_m");
  r.largest_group_particles = q.at("largest_group");
  r.above_threshold = q.at("above_threshold");
  report_ = std::move(r);
  history_.clear();
  for (const auto& c : j.at("history"))
    history_.push_back({c.at(0), c.at(1), c.at(2), c.at(3), c.at(4), c.at(5), c.at(6)});
  first_check_above_.clear();
  for (const auto& e : j.at("first_check_above"))
    first_check_above_.emplace(e.at(0).get<std::int64_t>(), e.at(1).get<int>());
  moving_streak_ = j.at("moving_streak");
  stable_streak_ = j.at("stable_streak");
  settled_streak_ = j.at("settled_streak");
  streak_start_time_ = opt_from(j.at("streak_start_time_s"));
  streak_start_zone_ = zone_from(j.at("streak_start_zone"));
  previous_group_ = j.at("previous_group");
}

} // namespace centridem
