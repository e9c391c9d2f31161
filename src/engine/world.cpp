// The World as the owner: settings, particles, walls, contact defaults, periodic
// boundaries, contact records, and the cycle that runs the engine's parts in order
// (docs/ARCHITECTURE.md "One step"). The parts live in their own files:
// neighbour_search.cpp, contact_pass.cpp, integration.cpp, timestep.cpp,
// measurements.cpp.
#include "engine/world.hpp"

#include "base/errors.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <fmt/format.h>

namespace centridem {

void validate(const WorldSettings& s) {
  auto bad = [](const char* key, double v, const char* allowed) {
    throw InputError(key, fmt::format("{:g}", v), allowed);
  };
  if (!(s.local_damping >= 0 && s.local_damping < 1))
    bad("simulation.local_damping", s.local_damping, "must be in [0, 1)");
  if (!(s.timestep_s >= 0) || !std::isfinite(s.timestep_s))
    bad("simulation.timestep_s", s.timestep_s, "must be > 0, or 0 / \"auto\" for automatic");
  if (!(s.timestep_safety_factor > 0 && s.timestep_safety_factor <= 1))
    bad("simulation.timestep_safety_factor", s.timestep_safety_factor, "must be in (0, 1]");
  if (!(s.timestep_growth_limit >= 0 && s.timestep_growth_limit <= 1))
    bad("simulation.timestep_growth_limit", s.timestep_growth_limit, "must be in [0, 1]");
  if (s.timestep_update_interval < 1)
    bad("simulation.timestep_update_interval", s.timestep_update_interval, "must be >= 1");
  if (!(s.neighbour_skin_m >= 0) || !std::isfinite(s.neighbour_skin_m))
    bad("simulation.neighbour_skin_m", s.neighbour_skin_m, "must be >= 0 (0 = automatic)");
  if (!(s.max_overlap_fraction > 0))
    bad("simulation.max_overlap_fraction", s.max_overlap_fraction,
        "must be > 0 (values above 1 tolerate deep overlaps, e.g. while relaxing a distributed "
        "specimen)");
  if (s.threads < 0) bad("simulation.threads", s.threads, "must be >= 0 (0 = all cores)");
}

World::World(WorldSettings settings) : settings_(settings) {
  validate(settings_);
  // Property set 0: a frictionless linear default until the user sets one.
  ContactProperties p;
  p.effective_modulus_Pa = 1e8;
  props_.push_back(p);
  bb_.row_offset.assign(1, 0);
  bb_.incoming_offset.assign(1, 0);
  bw_.row_offset.assign(1, 0);
}
void World::set_local_damping(double alpha) {
  WorldSettings s = settings_;
  s.local_damping = alpha;
  validate(s);
  settings_ = s;
}

void World::set_max_overlap_fraction(double fraction) {
  WorldSettings s = settings_;
  s.max_overlap_fraction = fraction;
  validate(s);
  settings_ = s;
}

void World::set_fixed_timestep(double dt_s) {
  WorldSettings s = settings_;
  s.timestep_s = dt_s;
  validate(s);
  settings_ = s;
  dt_ = dt_s;
}

// ---------------------------------------------------------------- particles --

std::size_t World::add_particle(const Vec3& x, double radius_m, double density_kg_m3,
                                std::int32_t group, std::optional<std::int64_t> id) {
  if (!(radius_m > 0) || !std::isfinite(radius_m))
    throw InputError("particle radius", fmt::format("{:g}", radius_m), "must be > 0 [m]");
  if (!(density_kg_m3 > 0) || !std::isfinite(density_kg_m3))
    throw InputError("particle density", fmt::format("{:g}", density_kg_m3),
                     "must be > 0 [kg/m^3]");
  if (!is_finite(x))
    throw InputError("particle position", fmt::format("[{}, {}, {}]", x.x, x.y, x.z),
                     "must be finite [m]");
  const std::int64_t pid = id ? *id : next_id_;
  next_id_ = std::max(next_id_, pid + 1);
  dirty_ = true;
  return p_.add(pid, x, radius_m, density_kg_m3, group);
}

std::size_t World::remove_particles(const std::function<bool(std::size_t)>& remove) {
  std::vector<std::uint32_t> keep;
  keep.reserve(p_.size());
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (!remove(i)) keep.push_back(static_cast<std::uint32_t>(i));
  const std::size_t removed = p_.size() - keep.size();
  if (removed > 0) rebuild(std::move(keep));
  return removed;
}

std::optional<std::size_t> World::index_of(std::int64_t id) const {
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (p_.id[i] == id) return i;
  return std::nullopt;
}

void World::reset_displacements() {
  std::fill(p_.displacement.begin(), p_.displacement.end(), Vec3{});
}

// -------------------------------------------------------------------- walls --

std::size_t World::add_wall(Wall wall, const ContactProperties& defaults) {
  for (const Wall& w : walls_)
    if (w.name == wall.name)
      throw InputError("walls.name", "\"" + wall.name + "\"", "wall names must be unique");
  if (walls_.size() >= 0xFFFF) throw InputError("walls", "too many", "at most 65535 walls");
  wall.properties = register_properties(defaults);
  walls_.push_back(std::move(wall));
  wall_motion_since_build_.push_back({});
  wall_point_at_build_.push_back(walls_.back().point);
  dirty_ = true;
  return walls_.size() - 1;
}

std::size_t World::wall_index(const std::string& name) const {
  for (std::size_t k = 0; k < walls_.size(); ++k)
    if (walls_[k].name == name) return k;
  std::string known;
  for (const Wall& w : walls_) known += (known.empty() ? "" : ", ") + ("\"" + w.name + "\"");
  throw InputError("wall", "\"" + name + "\"",
                   "no such wall; known walls: " + (known.empty() ? "none" : known));
}

void World::remove_wall(const std::string& name) {
  const std::size_t k = wall_index(name);
  // Drop that wall's contacts and renumber the walls after it.
  std::vector<std::uint32_t> offset(p_.size() + 1, 0);
  BallWallContacts out;
  out.row_offset.assign(bw_.row_offset.size(), 0);
  for (std::size_t i = 0; i + 1 < bw_.row_offset.size(); ++i) {
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.wall[e] == k) continue;
      out.ball.push_back(bw_.ball[e]);
      out.wall.push_back(
          static_cast<std::uint16_t>(bw_.wall[e] > k ? bw_.wall[e] - 1 : bw_.wall[e]));
      out.properties.push_back(bw_.properties[e]);
      out.state.push_back(bw_.state[e]);
      out.force_on_wall.push_back(bw_.force_on_wall[e]);
    }
    out.row_offset[i + 1] = static_cast<std::uint32_t>(out.wall.size());
  }
  bw_ = std::move(out);
  walls_.erase(walls_.begin() + static_cast<std::ptrdiff_t>(k));
  wall_motion_since_build_.erase(wall_motion_since_build_.begin() + static_cast<std::ptrdiff_t>(k));
  wall_point_at_build_.erase(wall_point_at_build_.begin() + static_cast<std::ptrdiff_t>(k));
}

void World::set_wall_servo(std::size_t wall, const WallServo& servo) {
  WallServo s = servo;
  const std::string key = "walls." + walls_.at(wall).name + ".servo";
  if (s.active) {
    const double len = norm(s.direction);
    if (!(len > 0) || !std::isfinite(len))
      throw InputError(key + ".direction",
                       fmt::format("[{}, {}, {}]", s.direction.x, s.direction.y, s.direction.z),
                       "must be a non-zero vector");
    s.direction = s.direction / len;
    if (!(s.gain_factor > 0 && s.gain_factor <= 1))
      throw InputError(key + ".gain_factor", fmt::format("{:g}", s.gain_factor),
                       "must be in (0, 1]");
    if (!(s.max_speed_m_per_s > 0) || !std::isfinite(s.max_speed_m_per_s))
      throw InputError(key + ".max_speed_m_per_s", fmt::format("{:g}", s.max_speed_m_per_s),
                       "must be > 0 [m/s]");
    if (!(s.integral_time_s >= 0) || !std::isfinite(s.integral_time_s))
      throw InputError(key + ".integral_time_s", fmt::format("{:g}", s.integral_time_s),
                       "must be >= 0 [s] (0: proportional only)");
    if (!std::isfinite(s.target_force_N))
      throw InputError(key + ".target_force_N", fmt::format("{:g}", s.target_force_N),
                       "must be finite [N]");
  }
  walls_[wall].servo = s;
}

void World::move_wall(std::size_t wall, const Vec3& displacement) {
  walls_[wall].point += displacement;
  wall_motion_since_build_[wall] += displacement;
  const double skin_half = 0.5 * skin();
  if (norm(wall_motion_since_build_[wall]) > skin_half) dirty_ = true;
}

// ---------------------------------------------------------- contact defaults --

std::uint16_t World::register_properties(const ContactProperties& p) {
  validate(p, "contact properties");
  for (std::size_t k = 0; k < props_.size(); ++k)
    if (props_[k] == p) return static_cast<std::uint16_t>(k);
  if (props_.size() >= kNoContact)
    throw InputError("contact properties", "too many distinct sets", "at most 65534");
  props_.push_back(p);
  if (p.attraction_force_N > 0 && p.attraction_range_m > cutoff_extra_) {
    cutoff_extra_ = p.attraction_range_m;
    dirty_ = true; // the neighbour cutoff grew
  }
  return static_cast<std::uint16_t>(props_.size() - 1);
}

void World::set_ball_ball_defaults(const ContactProperties& p) {
  validate(p, "contact.ball_ball");
  ball_ball_default_ = register_properties(p);
  band_props_.clear();
}

void World::set_ball_ball_defaults_by_height(const HeightGradedDefaults& g) {
  if (g.per_band.empty()) {
    band_props_.clear();
    return;
  }
  if (!(g.band_height_m > 0) || !std::isfinite(g.band_height_m) || !std::isfinite(g.z0_m))
    throw InputError("band_height_m", fmt::format("{:g}", g.band_height_m),
                     "the bands of the graded defaults need a finite height > 0 [m]");
  std::vector<std::uint16_t> bands;
  bands.reserve(g.per_band.size());
  for (const ContactProperties& p : g.per_band) {
    validate(p, "contact.ball_ball (graded by height)");
    bands.push_back(register_properties(p));
  }
  band_z0_ = g.z0_m;
  band_height_ = g.band_height_m;
  band_props_ = std::move(bands);
}

World::HeightGradedDefaults World::ball_ball_defaults_by_height() const {
  HeightGradedDefaults g;
  if (band_props_.empty()) return g;
  g.z0_m = band_z0_;
  g.band_height_m = band_height_;
  for (std::uint16_t k : band_props_) g.per_band.push_back(props_[k]);
  return g;
}

void World::set_wall_defaults(std::size_t wall, const ContactProperties& p) {
  validate(p, "walls." + walls_.at(wall).name + ".contact");
  walls_[wall].properties = register_properties(p);
}

std::size_t
World::modify_ball_ball_contacts(const std::function<bool(std::size_t, std::size_t)>& select,
                                 const std::function<void(ContactProperties&)>& change) {
  ensure_built();
  std::vector<std::int32_t> remap(props_.size(), -1);
  std::size_t changed = 0;
  const std::size_t n = bb_.row_offset.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      const std::uint16_t pr = bb_.properties[e];
      if (pr == kNoContact || !select(i, bb_.other[e])) continue;
      if (remap[pr] < 0) {
        ContactProperties c = props_[pr];
        change(c);
        remap[pr] = register_properties(c);
        if (remap.size() < props_.size()) remap.resize(props_.size(), -1);
      }
      bb_.properties[e] = static_cast<std::uint16_t>(remap[pr]);
      ++changed;
    }
  }
  return changed;
}

void World::cycle(long steps) {
  ensure_built();
  // Any bit set counts, -0.0 included, so that skipping them adds the same
  // zeros the arrays hold, bit for bit.
  const auto set = [](const Vec3& a) {
    return std::bit_cast<std::uint64_t>(a.x) | std::bit_cast<std::uint64_t>(a.y) |
           std::bit_cast<std::uint64_t>(a.z);
  };
  move_bound_m_ = kUnknownMove; // positions may have been changed between calls
  applied_loads_ = std::any_of(p_.applied_force.begin(), p_.applied_force.end(), set) ||
                   std::any_of(p_.applied_moment.begin(), p_.applied_moment.end(), set);
  if (settings_.timestep_s > 0) {
    const double crit = critical_timestep();
    if (settings_.timestep_s > crit)
      throw InputError(
          "simulation.timestep_s", fmt::format("{:.4g}", settings_.timestep_s),
          fmt::format(
              "above the critical timestep {:.4g} s estimated from the particles' masses "
              "and contact stiffnesses; use at most {:.4g} s (safety factor {}) or \"auto\"",
              crit, settings_.timestep_safety_factor * crit, settings_.timestep_safety_factor));
  }
  // The automatic timestep is estimated on a fixed step interval and after
  // rebuilds only, so a run does not depend on how it is split into calls.
  using SteadyClock = std::chrono::steady_clock;
  auto seconds = [](SteadyClock::time_point a, SteadyClock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
  };
  for (long s = 0; s < steps; ++s) {
    const auto t0 = SteadyClock::now();
    const bool rebuilt = dirty_;
    ensure_built();
    update_timestep(rebuilt);
    const auto t1 = SteadyClock::now();
    keep_contact_forces_ = s + 1 == steps;
    compute_contacts();
    const auto t2 = SteadyClock::now();
    phase_seconds_.neighbour_search += seconds(t0, t1);
    phase_seconds_.contact_pass += seconds(t1, t2);
    if (unstable_entry_ != UINT32_MAX) {
      std::string who;
      if (unstable_entry_ >= UINT32_MAX / 2) {
        const std::size_t i = UINT32_MAX - 1 - unstable_entry_;
        who = fmt::format("ball id {} (radius {:.4g} m) and a wall", p_.id[i], p_.radius[i]);
      } else {
        const std::size_t i = first_end(unstable_entry_);
        const std::size_t j = bb_.other[unstable_entry_];
        who = fmt::format("balls id {} and id {} (radii {:.4g} m, {:.4g} m)", p_.id[i], p_.id[j],
                          p_.radius[i], p_.radius[j]);
      }
      throw InstabilityError(fmt::format(
          "unstable at step {} (t = {:.6g} s): {} overlap by more than {} of the smaller radius. "
          "Likely cause: timestep {:.3g} s too large for the stiffness (critical estimate {:.3g} "
          "s), "
          "stiffness too low for the load (raise E* or kn), or particles created overlapping.",
          step_, time_, who, settings_.max_overlap_fraction, dt_, critical_timestep()));
    }
    integrate();
    phase_seconds_.integration += seconds(t2, SteadyClock::now());
    time_ += dt_;
    ++step_;
  }
}

long World::cycle_until_equilibrium(double ratio, long max_steps, int check_interval) {
  long done = 0;
  while (done < max_steps) {
    const long chunk = std::min<long>(check_interval, max_steps - done);
    cycle(chunk);
    done += chunk;
    if (mean_unbalanced_force_ratio() < ratio) break;
  }
  return done;
}
// ------------------------------------------------------- periodic, records --

void World::set_periodic(const PeriodicBox& box) {
  for (int a = 0; a < 3; ++a)
    if (box.axis[a] && !(box.hi[a] > box.lo[a]))
      throw InputError(fmt::format("periodic.{}", "xyz"[a]),
                       fmt::format("[{:g}, {:g}]", box.lo[a], box.hi[a]), "hi must exceed lo [m]");
  periodic_ = box;
  const Vec3 L = box.length();
  for (int sz = -1; sz <= 1; ++sz)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sx = -1; sx <= 1; ++sx)
        image_shift_[static_cast<std::size_t>((sx + 1) + 3 * (sy + 1) + 9 * (sz + 1))] = {
            box.axis[0] ? sx * L.x : 0.0, box.axis[1] ? sy * L.y : 0.0,
            box.axis[2] ? sz * L.z : 0.0};
  dirty_ = true;
}

std::vector<ContactRecord> World::contact_records() const {
  std::vector<ContactRecord> out;
  const std::size_t n = p_.size();
  if (bb_.row_offset.size() != n + 1) return out;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      ContactRecord rec;
      rec.id1 = p_.id[i];
      rec.id2 = p_.id[bb_.other[e]];
      if (!bb_.image.empty()) {
        const int c = bb_.image[e];
        rec.image = {static_cast<std::int8_t>(c % 3 - 1), static_cast<std::int8_t>((c / 3) % 3 - 1),
                     static_cast<std::int8_t>(c / 9 - 1)};
      }
      rec.properties = props_[bb_.properties[e]];
      rec.state = bb_.state[e];
      out.push_back(rec);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      ContactRecord rec;
      rec.id1 = p_.id[i];
      rec.wall = bw_.wall[e];
      rec.properties = props_[bw_.properties[e]];
      rec.state = bw_.state[e];
      out.push_back(rec);
    }
  }
  return out;
}

void World::restore_contacts(const std::vector<ContactRecord>& records) {
  // Register the property sets now, so the neighbour cutoff covers their
  // attraction range before the rebuild that matches the records.
  for (const ContactRecord& rec : records) register_properties(rec.properties);
  restored_.insert(restored_.end(), records.begin(), records.end());
  dirty_ = true;
}

} // namespace centridem
