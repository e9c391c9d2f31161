#include "core/world.hpp"

#include "core/errors.hpp"
#include "physics/damping.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <numeric>
#include <omp.h>
#include <unordered_map>

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

namespace {
// Threads for a loop over n items: small loops run serially (a parallel
// region costs more than it saves there, and oversubscribed machines make
// waiting threads spin). Results do not depend on the thread count.
int thread_count(const WorldSettings& s, std::size_t n = SIZE_MAX) {
  if (n < 2000) return 1;
  return s.threads > 0 ? s.threads : omp_get_max_threads();
}
} // namespace

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

// --------------------------------------------------------- neighbour search --

double World::skin() const {
  if (settings_.neighbour_skin_m > 0) return settings_.neighbour_skin_m;
  if (p_.size() == 0) return 0.0;
  if (skin_cached_ > 0) return skin_cached_;
  return 0.5 * *std::min_element(p_.radius.begin(), p_.radius.end());
}

void World::ensure_built() {
  if (dirty_ || bb_.row_offset.size() != p_.size() + 1) rebuild_sorted();
}

void World::rebuild_sorted() {
  std::vector<std::uint32_t> all(p_.size());
  std::iota(all.begin(), all.end(), 0u);
  rebuild(std::move(all));
}

namespace {
struct PendingPair {
  std::uint32_t i, j;
  std::uint16_t properties;
  ContactState state;
};
struct PendingWall {
  std::uint32_t i;
  std::uint16_t wall;
  std::uint16_t properties;
  ContactState state;
};

struct CellGrid {
  Vec3 origin;
  std::array<double, 3> h{1, 1, 1};
  std::array<std::int64_t, 3> n{1, 1, 1};
  std::array<bool, 3> periodic{false, false, false};
  std::int64_t axis_cell(double v, int a) const {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>((v - origin[a]) / h[a]), 0, n[a] - 1);
  }
  std::int64_t cell_of(const Vec3& x) const {
    return (axis_cell(x.z, 2) * n[1] + axis_cell(x.y, 1)) * n[0] + axis_cell(x.x, 0);
  }
  std::size_t count() const { return static_cast<std::size_t>(n[0] * n[1] * n[2]); }
};

CellGrid make_grid(const std::vector<Vec3>& x, std::span<const std::uint32_t> which, double h,
                   const PeriodicBox& pb) {
  CellGrid g;
  g.periodic = pb.axis;
  if (which.empty()) return g;
  Vec3 lo = x[which[0]], hi = lo;
  for (std::uint32_t k : which) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], x[k][a]), hi[a] = std::max(hi[a], x[k][a]);
  }
  for (int a = 0; a < 3; ++a) {
    if (!pb.axis[a]) continue;
    const double L = pb.hi[a] - pb.lo[a];
    const auto cells = static_cast<std::int64_t>(L / h);
    if (cells < 3)
      throw InputError(fmt::format("periodic box length along {}", "xyz"[a]),
                       fmt::format("{:.4g} m", L),
                       fmt::format("must be at least 3 neighbour cells = {:.4g} m (3 x (largest "
                                   "diameter + skin + attraction range))",
                                   3 * h));
    lo[a] = pb.lo[a];
    g.n[a] = cells;
    g.h[a] = L / static_cast<double>(cells);
  }
  // Keep the grid at most ~4 cells per particle (sparse, spread-out models).
  const double max_cells = std::max<double>(64.0, 4.0 * static_cast<double>(which.size()));
  double hh = h;
  for (;;) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a) {
      if (pb.axis[a]) {
        total *= static_cast<double>(g.n[a]);
        continue;
      }
      g.h[a] = hh;
      g.n[a] = static_cast<std::int64_t>((hi[a] - lo[a]) / hh) + 1;
      total *= static_cast<double>(g.n[a]);
    }
    if (total <= max_cells || hh > 1e3 * h) break;
    hh *= 1.25;
  }
  g.origin = lo;
  return g;
}
} // namespace

void World::rebuild(std::vector<std::uint32_t> candidates) {
  const std::size_t old_n = p_.size();
  const std::size_t n = candidates.size();
  // Radii of the kept particles only (remove_particles passes the kept ones):
  // the skin and the cell size must not depend on particles being removed.
  double rmin = std::numeric_limits<double>::infinity(), rmax = 0.0;
  for (std::uint32_t k : candidates) {
    rmin = std::min(rmin, p_.radius[k]);
    rmax = std::max(rmax, p_.radius[k]);
  }
  skin_cached_ = n ? 0.5 * rmin : 0.0;
  const double cut = skin() + cutoff_extra_;
  // Wrap periodic positions into the box (only here, so that image codes stay
  // valid between rebuilds).
  if (periodic_.any()) {
    for (std::uint32_t k : candidates) {
      Vec3& xk = p_.position[k];
      for (int a = 0; a < 3; ++a) {
        if (!periodic_.axis[a]) continue;
        const double L = periodic_.hi[a] - periodic_.lo[a];
        xk[a] -= L * std::floor((xk[a] - periodic_.lo[a]) / L);
        if (xk[a] >= periodic_.hi[a]) xk[a] = periodic_.lo[a]; // round-off at hi
      }
    }
  }
  const CellGrid grid = make_grid(p_.position, candidates, 2.0 * rmax + cut, periodic_);

  // Order the kept particles by cell (counting sort, stable: deterministic).
  const std::size_t ncells = grid.count();
  std::vector<std::uint32_t> cell_start(ncells + 1, 0);
  std::vector<std::uint32_t> cell_of_candidate(n);
  for (std::size_t k = 0; k < n; ++k) {
    cell_of_candidate[k] = static_cast<std::uint32_t>(grid.cell_of(p_.position[candidates[k]]));
    ++cell_start[cell_of_candidate[k] + 1];
  }
  std::partial_sum(cell_start.begin(), cell_start.end(), cell_start.begin());
  std::vector<std::uint32_t> new_to_old(n);
  {
    std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t k = 0; k < n; ++k) new_to_old[fill[cell_of_candidate[k]]++] = candidates[k];
  }
  std::vector<std::uint32_t> old_to_new(old_n, UINT32_MAX);
  for (std::size_t k = 0; k < n; ++k) old_to_new[new_to_old[k]] = static_cast<std::uint32_t>(k);

  // Carry the history of active contacts over to the new numbering.
  std::vector<PendingPair> pending;
  const std::size_t old_rows = bb_.row_offset.size() - 1;
  for (std::size_t i = 0; i < old_rows; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      std::uint32_t a = old_to_new[i], b = old_to_new[bb_.other[e]];
      if (a == UINT32_MAX || b == UINT32_MAX) continue; // an end was removed
      ContactState s = bb_.state[e];
      if (a > b) { // ends swap: the history on the new end 2 is the opposite
        std::swap(a, b);
        s.shear_force = -s.shear_force;
        s.rolling_moment = -s.rolling_moment;
      }
      pending.push_back({a, b, bb_.properties[e], s});
    }
  }
  std::vector<PendingWall> pending_wall;
  for (std::size_t i = 0; i + 1 < bw_.row_offset.size(); ++i) {
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact || old_to_new[i] == UINT32_MAX) continue;
      pending_wall.push_back({old_to_new[i], bw_.wall[e], bw_.properties[e], bw_.state[e]});
    }
  }
  if (!restored_.empty()) {
    std::unordered_map<std::int64_t, std::uint32_t> index_of_id;
    index_of_id.reserve(n);
    for (std::size_t k = 0; k < n; ++k)
      index_of_id[p_.id[new_to_old[k]]] = static_cast<std::uint32_t>(k);
    for (const ContactRecord& rec : restored_) {
      const auto a = index_of_id.find(rec.id1);
      if (a == index_of_id.end()) continue;
      const std::uint16_t pr = register_properties(rec.properties);
      if (rec.wall >= 0) {
        if (static_cast<std::size_t>(rec.wall) < walls_.size())
          pending_wall.push_back({a->second, static_cast<std::uint16_t>(rec.wall), pr, rec.state});
        continue;
      }
      const auto b = index_of_id.find(rec.id2);
      if (b == index_of_id.end()) continue;
      std::uint32_t i = a->second, j = b->second;
      ContactState st = rec.state;
      if (i > j) {
        std::swap(i, j);
        st.shear_force = -st.shear_force;
        st.rolling_moment = -st.rolling_moment;
      }
      pending.push_back({i, j, pr, st});
    }
    restored_.clear();
  }
  std::sort(pending.begin(), pending.end(), [](const PendingPair& a, const PendingPair& b) {
    return a.i != b.i ? a.i < b.i : a.j < b.j;
  });
  std::sort(pending_wall.begin(), pending_wall.end(),
            [](const PendingWall& a, const PendingWall& b) {
              return a.i != b.i ? a.i < b.i : a.wall < b.wall;
            });

  p_.apply_order(new_to_old);

  // Cells of the sorted particles: particle k lies in cell c iff
  // cell_start[c] <= k < cell_start[c+1]. Scanning neighbour cells in
  // increasing index gives each row's j in increasing order.
  const auto& x = p_.position;
  const auto& r = p_.radius;
  const int nthreads = thread_count(settings_, n);
  // visit(j, image code) for each j > i within reach; with periodic axes a
  // neighbour cell past the box wraps around and j is taken at its image.
  auto for_each_candidate = [&](std::size_t i, auto&& visit) {
    std::array<std::int64_t, 3> c{grid.axis_cell(x[i].x, 0), grid.axis_cell(x[i].y, 1),
                                  grid.axis_cell(x[i].z, 2)};
    std::array<std::int64_t, 3> cc{};
    std::array<int, 3> sh{};
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int dd[3] = {dx, dy, dz};
          bool skip = false;
          for (int a = 0; a < 3; ++a) {
            cc[a] = c[a] + dd[a];
            sh[a] = 0;
            if (cc[a] < 0 || cc[a] >= grid.n[a]) {
              if (!grid.periodic[a]) {
                skip = true;
                break;
              }
              sh[a] = cc[a] < 0 ? -1 : 1;
              cc[a] -= sh[a] * grid.n[a];
            }
          }
          if (skip) continue;
          const std::uint8_t code =
              static_cast<std::uint8_t>((sh[0] + 1) + 3 * (sh[1] + 1) + 9 * (sh[2] + 1));
          const Vec3 shift = image_shift_[code];
          const std::size_t cell =
              static_cast<std::size_t>((cc[2] * grid.n[1] + cc[1]) * grid.n[0] + cc[0]);
          for (std::uint32_t j =
                   std::max<std::uint32_t>(cell_start[cell], static_cast<std::uint32_t>(i + 1));
               j < cell_start[cell + 1]; ++j) {
            const double reach = r[i] + r[j] + cut;
            if (norm2(x[j] + shift - x[i]) < reach * reach) visit(j, code);
          }
        }
      }
    }
  };
  auto near_wall = [&](std::size_t i, const Wall& w) {
    return wall_proximity(w, x[i]).distance < r[i] + cut;
  };

  std::vector<std::uint32_t> count(n + 1, 0), wall_count(n + 1, 0);
#pragma omp parallel for schedule(static, 512) num_threads(nthreads)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t c = 0;
    for_each_candidate(i, [&](std::uint32_t, std::uint8_t) { ++c; });
    count[i + 1] = c;
    std::uint32_t cw = 0;
    for (const Wall& w : walls_) cw += near_wall(i, w) ? 1u : 0u;
    wall_count[i + 1] = cw;
  }
  std::partial_sum(count.begin(), count.end(), count.begin());
  std::partial_sum(wall_count.begin(), wall_count.end(), wall_count.begin());

  BallBallContacts bb;
  bb.row_offset = std::move(count);
  const std::size_t entries = bb.row_offset[n];
  bb.other.resize(entries);
  bb.properties.assign(entries, kNoContact);
  const bool periodic = periodic_.any();
  if (periodic) bb.image.resize(entries);
  bb.state.assign(entries, ContactState{});
  bb.force_on_2.resize(entries);
  bb.moment_on_2.resize(entries);
  BallWallContacts bw;
  bw.row_offset = std::move(wall_count);
  const std::size_t wall_entries = bw.row_offset[n];
  bw.wall.resize(wall_entries);
  bw.ball.resize(wall_entries);
  bw.properties.assign(wall_entries, kNoContact);
  bw.state.assign(wall_entries, ContactState{});
  bw.force_on_wall.resize(wall_entries);

  // Row starts into the pending lists.
  std::vector<std::uint32_t> pend_start(n + 1, 0), pend_wall_start(n + 1, 0);
  for (const PendingPair& q : pending) ++pend_start[q.i + 1];
  for (const PendingWall& q : pending_wall) ++pend_wall_start[q.i + 1];
  std::partial_sum(pend_start.begin(), pend_start.end(), pend_start.begin());
  std::partial_sum(pend_wall_start.begin(), pend_wall_start.end(), pend_wall_start.begin());

#pragma omp parallel for schedule(static, 512) num_threads(nthreads)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t e = bb.row_offset[i];
    std::uint32_t q = pend_start[i];
    for_each_candidate(i, [&](std::uint32_t j, std::uint8_t code) {
      bb.other[e] = j;
      if (periodic) bb.image[e] = code;
      if (periodic) { // wrapped cells break the increasing-j order: search the row
        const auto first = pending.begin() + pend_start[i],
                   last = pending.begin() + pend_start[i + 1];
        const auto it = std::lower_bound(
            first, last, j, [](const PendingPair& pp, std::uint32_t jj) { return pp.j < jj; });
        if (it != last && it->j == j) {
          bb.properties[e] = it->properties;
          bb.state[e] = it->state;
        }
      } else {
        while (q < pend_start[i + 1] && pending[q].j < j) ++q; // separated beyond the list
        if (q < pend_start[i + 1] && pending[q].j == j) {
          bb.properties[e] = pending[q].properties;
          bb.state[e] = pending[q].state;
        }
      }
      ++e;
    });
    std::uint32_t ew = bw.row_offset[i];
    std::uint32_t qw = pend_wall_start[i];
    for (std::size_t k = 0; k < walls_.size(); ++k) {
      if (!near_wall(i, walls_[k])) continue;
      bw.wall[ew] = static_cast<std::uint16_t>(k);
      bw.ball[ew] = static_cast<std::uint32_t>(i);
      while (qw < pend_wall_start[i + 1] && pending_wall[qw].wall < k) ++qw;
      if (qw < pend_wall_start[i + 1] && pending_wall[qw].wall == k) {
        bw.properties[ew] = pending_wall[qw].properties;
        bw.state[ew] = pending_wall[qw].state;
      }
      ++ew;
    }
  }

  // Transpose (deterministic: incoming entries in increasing entry order).
  bb.incoming_offset.assign(n + 1, 0);
  for (std::size_t e = 0; e < entries; ++e) ++bb.incoming_offset[bb.other[e] + 1];
  std::partial_sum(bb.incoming_offset.begin(), bb.incoming_offset.end(),
                   bb.incoming_offset.begin());
  bb.incoming.resize(entries);
  {
    std::vector<std::uint32_t> fill(bb.incoming_offset.begin(), bb.incoming_offset.end() - 1);
    for (std::size_t e = 0; e < entries; ++e)
      bb.incoming[fill[bb.other[e]]++] = static_cast<std::uint32_t>(e);
  }

  bb_ = std::move(bb);
  bw_ = std::move(bw);
  position_at_build_ = p_.position;
  std::fill(wall_motion_since_build_.begin(), wall_motion_since_build_.end(), Vec3{});
  for (std::size_t k = 0; k < walls_.size(); ++k) wall_point_at_build_[k] = walls_[k].point;
  dirty_ = false;
  ++rebuilds_;
}

World::BuildState World::build_state() const {
  const bool pending = dirty_ || bb_.row_offset.size() != p_.size() + 1;
  if (pending) return {true, {}, {}, {}, cutoff_extra_};
  return {false, position_at_build_, wall_point_at_build_, wall_motion_since_build_, cutoff_extra_};
}

void World::restore_build_state(const BuildState& s) {
  // The cutoff grows with every property set ever registered; the resumed
  // World may not have seen them all.
  cutoff_extra_ = std::max(cutoff_extra_, s.cutoff_extra_m);
  if (s.pending) {
    dirty_ = true;
    return;
  }
  if (s.positions.size() != p_.size() || s.wall_points.size() != walls_.size() ||
      s.wall_motion.size() != walls_.size())
    throw InputError(
        "neighbour-list state",
        fmt::format("{} particles, {} walls", s.positions.size(), s.wall_points.size()),
        fmt::format("must match the World's {} particles and {} walls", p_.size(), walls_.size()));
  // Rebuild at the positions of the last rebuild. The particles are already
  // in the order that rebuild sorted them into (the stable sort by cell
  // leaves them in place), so only the lists are made.
  std::vector<Vec3> now = std::move(p_.position);
  const std::vector<std::int64_t> ids = p_.id;
  std::vector<Vec3> walls_now;
  for (std::size_t k = 0; k < walls_.size(); ++k) {
    walls_now.push_back(walls_[k].point);
    walls_[k].point = s.wall_points[k];
  }
  p_.position = s.positions;
  rebuild_sorted();
  if (p_.id != ids) {
    // Not expected (the sort leaves sorted particles in place); should it
    // happen, the run goes on correctly, in the new order (not bit for bit).
    std::unordered_map<std::int64_t, std::size_t> was;
    for (std::size_t k = 0; k < ids.size(); ++k) was[ids[k]] = k;
    std::vector<Vec3> reordered(now.size());
    for (std::size_t k = 0; k < p_.size(); ++k) reordered[k] = now[was.at(p_.id[k])];
    now = std::move(reordered);
  }
  p_.position = std::move(now);
  for (std::size_t k = 0; k < walls_.size(); ++k) walls_[k].point = walls_now[k];
  wall_motion_since_build_ = s.wall_motion;
  --rebuilds_; // not a rebuild of the run
}

// ------------------------------------------------------------------- cycle --

void World::compute_contacts() {
  if (periodic_.any())
    compute_contacts_impl<true>();
  else
    compute_contacts_impl<false>();
}

template <bool Periodic> void World::compute_contacts_impl() {
  const std::size_t n = p_.size();
  const double dt = dt_;
  auto& P = p_;
  const auto& x = p_.position;
  const auto& v = p_.velocity;
  const auto& w = p_.spin;
  const auto& r = p_.radius;
  const auto& m = p_.mass;
  const ContactProperties* props = props_.data();
  const std::uint16_t bb_default = ball_ball_default_;
  const ContactProperties& bb_def = props_[bb_default];
  const double bb_default_range = bb_def.attraction_force_N > 0 ? bb_def.attraction_range_m : 0.0;
  const double max_overlap = settings_.max_overlap_fraction;
  std::uint32_t unstable = UINT32_MAX;

  // Each row i is handled by one thread: it computes the contacts (i, j > i)
  // and its ball-wall contacts, sums its own side in registers and leaves the
  // force and moment on j in the entry; integrate() gathers those in a fixed
  // order. No two threads write the same memory, and sums do not depend on
  // the thread count. Each thread takes one contiguous block of rows: the
  // particles are in cell order, so most neighbours j of a row i lie in the
  // same block and their cache lines stay with one core (chunks of 256 rows
  // dealt in turn gave 1.6x from 1 to 2 threads; contiguous blocks 1.9x).
#pragma omp parallel for schedule(static) num_threads(thread_count(settings_, n))                  \
    reduction(min                                                                                  \
              : unstable)
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 fi = P.mass[i] * field_.acceleration(x[i], v[i]) + P.applied_force[i];
    Vec3 mi = P.applied_moment[i];
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      const std::uint32_t j = bb_.other[e];
      Vec3 d = x[j] - x[i];
      if constexpr (Periodic) d += image_shift_[bb_.image[e]];
      const double dist2 = norm2(d);
      std::uint16_t pr = bb_.properties[e];
      if (pr == kNoContact) {
        const double reach = r[i] + r[j] + bb_default_range;
        if (dist2 >= reach * reach) continue; // not touching: nothing to do
        pr = bb_default;                      // contact is born: copy the defaults
        bb_.state[e] = ContactState{};
      }
      const double dist = std::sqrt(dist2);
      const double overlap = r[i] + r[j] - dist;
      const ContactProperties& cp = props[pr];
      if (!contact_active(cp, overlap) || dist == 0.0) { // contact ends
        bb_.properties[e] = kNoContact;
        bb_.state[e] = ContactState{};
        bb_.force_on_2[e] = {};
        bb_.moment_on_2[e] = {};
        continue;
      }
      bb_.properties[e] = pr;
      const Vec3 nrm = d * (1.0 / dist);
      // Lever arms from the centres to the contact point: a1 n and -a2 n [m].
      // With them, the relative velocity at the contact point
      // (v_j + w_j x (-a2 n)) - (v_i + w_i x a1 n) is (v_j - v_i) - (a1 w_i + a2 w_j) x n,
      // and the moments of a force F about the centres are a1 (n x F) on i and
      // -a2 (n x F) on j: one cross product each instead of two.
      const double a1 = r[i] - 0.5 * overlap, a2 = r[j] - 0.5 * overlap;
      const ContactGeometry g{nrm,
                              overlap,
                              (v[j] - v[i]) - cross(a1 * w[i] + a2 * w[j], nrm),
                              w[j] - w[i],
                              std::min(r[i], r[j]),
                              r[i] + r[j],
                              r[i] * r[j] / (r[i] + r[j]),
                              has_dashpot(cp) ? m[i] * m[j] / (m[i] + m[j]) : 0.0};
      const ContactResult res = contact_law(cp, g, bb_.state[e], dt);
      const Vec3 nxf = cross(nrm, res.force);
      bb_.force_on_2[e] = res.force;
      bb_.moment_on_2[e] = res.moment - a2 * nxf;
      fi -= res.force;
      mi -= a1 * nxf + res.moment;
      if (overlap > max_overlap * std::min(r[i], r[j])) unstable = std::min(unstable, e);
    }
    // Ball-wall contacts of ball i (end 1 = ball, end 2 = wall).
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      const Wall& wl = walls_[bw_.wall[e]];
      const WallProximity prox = wall_proximity(wl, x[i]);
      const double overlap = r[i] - prox.distance;
      std::uint16_t pr = bw_.properties[e];
      if (pr == kNoContact) {
        if (!contact_active(props[wl.properties], overlap)) continue;
        pr = wl.properties;
        bw_.state[e] = ContactState{};
      }
      const ContactProperties& cp = props[pr];
      if (!contact_active(cp, overlap)) {
        bw_.properties[e] = kNoContact;
        bw_.state[e] = ContactState{};
        bw_.force_on_wall[e] = {};
        continue;
      }
      bw_.properties[e] = pr;
      const Vec3 nrm = ball_to_wall_normal(wl, prox);
      const double a = r[i] - 0.5 * overlap; // lever arm a n to the contact point [m]
      const ContactGeometry g{
          nrm, overlap, wl.velocity - v[i] + a * cross(nrm, w[i]), -w[i], r[i], r[i], r[i], m[i]};
      const ContactResult res = contact_law(cp, g, bw_.state[e], dt);
      bw_.force_on_wall[e] = res.force;
      fi -= res.force;
      mi -= a * cross(nrm, res.force) + res.moment;
      if (overlap > max_overlap * r[i])
        unstable = std::min(unstable, UINT32_MAX - 1 - static_cast<std::uint32_t>(i));
    }
    P.force[i] = fi;
    P.moment[i] = mi;
  }
  unstable_entry_ = unstable;
}

void World::integrate() {
  const std::size_t n = p_.size();
  const double dt = dt_;
  const double alpha = settings_.local_damping;
  auto& P = p_;
  double max_move2 = 0.0;
  std::uint32_t bad = UINT32_MAX;

  int team = 1;
#pragma omp parallel num_threads(thread_count(settings_, n))
  {
#pragma omp single nowait
    team = omp_get_num_threads();
#pragma omp for schedule(static) reduction(max : max_move2) reduction(min : bad)
    for (std::size_t i = 0; i < n; ++i) {
      // Own side was summed by compute_contacts; add the forces from the
      // contacts in which i is the second end (zero for non-touching entries).
      Vec3 f = P.force[i];
      Vec3 mo = P.moment[i];
      for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
        const std::uint32_t e = bb_.incoming[k];
        f += bb_.force_on_2[e];
        mo += bb_.moment_on_2[e];
      }
      P.force[i] = f;
      P.moment[i] = mo;
      // Central differences (PFC): v(t+dt/2) = v(t-dt/2) + (F + Fd)/m dt.
      if (!(P.flags[i] & fix_translation))
        P.velocity[i] += (f + local_damping_force(f, P.velocity[i], alpha)) * (dt / P.mass[i]);
      if (!(P.flags[i] & fix_rotation))
        P.spin[i] += (mo + local_damping_force(mo, P.spin[i], alpha)) * (dt / P.inertia[i]);
      const Vec3 dx = P.velocity[i] * dt;
      P.position[i] += dx;
      P.displacement[i] += dx;
      if (!is_finite(P.position[i]) || !is_finite(P.spin[i]))
        bad = std::min(bad, static_cast<std::uint32_t>(i));
      max_move2 = std::max(max_move2, norm2(P.position[i] - position_at_build_[i]));
    }
  }
  threads_used_ = team;

  if (bad != UINT32_MAX)
    throw InstabilityError(fmt::format(
        "unstable at step {}: particle id {} has a non-finite position or spin (NaN/inf). Likely "
        "cause: timestep too large for the contact stiffness (critical estimate {:.3g} s, "
        "timestep {:.3g} s), or an input that produced an infinite force.",
        step_, P.id[bad], critical_timestep(), dt_));

  // Walls: prescribed motion, and the force the balls exert on them.
  double max_wall_move = 0.0;
  for (std::size_t k = 0; k < walls_.size(); ++k) {
    walls_[k].point += walls_[k].velocity * dt;
    wall_motion_since_build_[k] += walls_[k].velocity * dt;
    walls_[k].force = {};
    walls_[k].contact_count = 0;
    max_wall_move = std::max(max_wall_move, norm(wall_motion_since_build_[k]));
  }
  bool any_servo = false;
  for (Wall& wl : walls_) {
    wl.normal_stiffness_N_per_m = 0.0;
    any_servo = any_servo || wl.servo.active;
  }
  for (std::size_t e = 0; e < bw_.entries(); ++e) {
    if (bw_.properties[e] == kNoContact) continue;
    Wall& wl = walls_[bw_.wall[e]];
    wl.force += bw_.force_on_wall[e];
    ++wl.contact_count;
    if (wl.servo.active) {
      const double R = p_.radius[bw_.ball[e]];
      const ContactGeometry g{{}, 0.0, {}, {}, R, R, R, 0.0};
      wl.normal_stiffness_N_per_m += contact_stiffness(props_[bw_.properties[e]], g).kn;
    }
  }
  if (any_servo) {
    for (Wall& wl : walls_) {
      if (!wl.servo.active) continue;
      WallServo& sv = wl.servo;
      const double measured = -dot(wl.force, sv.direction); // balls push against `direction`
      const double error = sv.target_force_N - measured;
      const double demand = sv.integral_time_s > 0
                                ? error + sv.error_integral_N_s / sv.integral_time_s
                                : error; // [N]
      const double free_speed = wl.normal_stiffness_N_per_m > 0
                                    ? sv.gain_factor * demand / (wl.normal_stiffness_N_per_m * dt)
                                    : (demand > 0 ? sv.max_speed_m_per_s : -sv.max_speed_m_per_s);
      const double speed = std::clamp(free_speed, -sv.max_speed_m_per_s, sv.max_speed_m_per_s);
      if (sv.integral_time_s > 0 && (speed == free_speed || error * free_speed < 0))
        sv.error_integral_N_s += error * dt;
      wl.velocity =
          wl.velocity - dot(wl.velocity, sv.direction) * sv.direction + speed * sv.direction;
    }
  }

  const double max_move = std::sqrt(max_move2);
  const double s = skin();
  if (2.0 * max_move > s || max_move + max_wall_move > s) dirty_ = true;
}

double World::critical_timestep() {
  ensure_built();
  const std::size_t n = p_.size();
  if (n == 0) return std::numeric_limits<double>::infinity();
  const auto& r = p_.radius;
  const auto& m = p_.mass;
  const auto& I = p_.inertia;
  const ContactProperties& def = props_[ball_ball_default_];
  // Per contact, an upper bound of its contribution to the squared highest
  // frequency seen by one particle (column sum of the Gershgorin bound of
  // M^-1 K): normal kn (1/m1 + 1/m2); tangential ks (1/m1 + R1^2/I1 + 1/m2 +
  // R2^2/I2) plus rolling kr (1/I1 + 1/I2). Central differences are stable
  // for dt < 2/omega_max. Walls have infinite mass and inertia.
  auto omega2 = [](const ContactStiffness& k, double m1, double I1, double R1, double m2inv,
                   double I2inv, double R2) {
    const double ln = k.kn * (1.0 / m1 + m2inv);
    const double lt =
        k.ks * (1.0 / m1 + R1 * R1 / I1 + m2inv + R2 * R2 * I2inv) + k.kr * (1.0 / I1 + I2inv);
    return std::max(ln, lt);
  };
  double max_omega2 = 0.0;
#pragma omp parallel for schedule(static, 512) num_threads(thread_count(settings_, n))             \
    reduction(max                                                                                  \
              : max_omega2)
  for (std::size_t i = 0; i < n; ++i) {
    double w2 = 0.0;
    bool any = false;
    auto pair = [&](std::size_t j, std::uint16_t pr, std::uint32_t e) {
      const double ov = r[i] + r[j] - norm(i < j ? pair_vector(e, i, j) : pair_vector(e, j, i));
      const ContactGeometry g{
          {}, ov, {}, {}, std::min(r[i], r[j]), r[i] + r[j], r[i] * r[j] / (r[i] + r[j]), 0.0};
      w2 +=
          omega2(contact_stiffness(props_[pr], g), m[i], I[i], r[i], 1.0 / m[j], 1.0 / I[j], r[j]);
      any = true;
    };
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e)
      if (bb_.properties[e] != kNoContact) pair(bb_.other[e], bb_.properties[e], e);
    for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
      const std::uint32_t e = bb_.incoming[k];
      if (bb_.properties[e] == kNoContact) continue;
      // find the first end of entry e: the row that holds it
      pair(first_end(e), bb_.properties[e], e);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const ContactGeometry g{{}, 0.0, {}, {}, r[i], r[i], r[i], 0.0};
      w2 +=
          omega2(contact_stiffness(props_[bw_.properties[e]], g), m[i], I[i], r[i], 0.0, 0.0, 0.0);
      any = true;
    }
    if (!any) { // a free particle: as if touching one identical particle, or
                // the stiffest wall, whichever is stiffer (it may land on either)
      const ContactGeometry g{{}, 0.0, {}, {}, r[i], 2 * r[i], 0.5 * r[i], 0.0};
      w2 = omega2(contact_stiffness(def, g), m[i], I[i], r[i], 1.0 / m[i], 1.0 / I[i], r[i]);
      const ContactGeometry gw{{}, 0.0, {}, {}, r[i], r[i], r[i], 0.0};
      for (const Wall& wl : walls_)
        w2 = std::max(w2, omega2(contact_stiffness(props_[wl.properties], gw), m[i], I[i], r[i],
                                 0.0, 0.0, 0.0));
    }
    max_omega2 = std::max(max_omega2, w2);
  }
  // Viscous dashpots lower the stability limit of central differences from
  // 2/omega to (2/omega)(sqrt(1 + beta^2) - beta) (e.g. Belytschko & Hughes,
  // "Computational Methods for Transient Analysis", 1983, ch. 2), with beta
  // the largest dashpot ratio of the property sets in use.
  double beta = 0.0;
  auto consider = [&](std::uint16_t k) {
    beta = std::max({beta, props_[k].dashpot_normal_ratio, props_[k].dashpot_shear_ratio});
  };
  consider(ball_ball_default_);
  for (const Wall& wl : walls_) consider(wl.properties);
  for (std::uint16_t k : bb_.properties)
    if (k != kNoContact) consider(k);
  for (std::uint16_t k : bw_.properties)
    if (k != kNoContact) consider(k);
  const double damping_factor = std::sqrt(1.0 + beta * beta) - beta;
  return max_omega2 > 0 ? damping_factor * 2.0 / std::sqrt(max_omega2)
                        : std::numeric_limits<double>::infinity();
}

void World::update_timestep(bool force_estimate) {
  if (settings_.timestep_s > 0) {
    dt_ = settings_.timestep_s;
    // Contacts may stiffen during a run (new contacts, a denser packing):
    // check the fixed timestep whenever the automatic one would be estimated.
    if (force_estimate || step_ % settings_.timestep_update_interval == 0) {
      const double crit = critical_timestep();
      if (dt_ > crit)
        throw InstabilityError(fmt::format(
            "fixed timestep {:.4g} s is above the critical timestep {:.4g} s estimated at step "
            "{} (t = {:.6g} s) from the current contacts: they stiffened during the run (more "
            "contacts per particle, or stiffer ones). Likely cause: simulation.timestep_s "
            "chosen for a looser state; use at most {:.4g} s (safety factor {}) or \"auto\"",
            dt_, crit, step_, time_, settings_.timestep_safety_factor * crit,
            settings_.timestep_safety_factor));
    }
    return;
  }
  if (force_estimate || dt_target_ <= 0 || step_ % settings_.timestep_update_interval == 0) {
    const double crit = critical_timestep();
    dt_target_ = std::isfinite(crit) ? settings_.timestep_safety_factor * crit : 1e-6;
  }
  dt_ = dt_ > 0 ? std::min(dt_target_, dt_ * (1.0 + settings_.timestep_growth_limit)) : dt_target_;
}

void World::cycle(long steps) {
  ensure_built();
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
  for (long s = 0; s < steps; ++s) {
    const bool rebuilt = dirty_;
    ensure_built();
    update_timestep(rebuilt);
    compute_contacts();
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

std::size_t World::first_end(std::uint32_t e) const {
  const auto it = std::upper_bound(bb_.row_offset.begin(), bb_.row_offset.end(), e);
  return static_cast<std::size_t>(it - bb_.row_offset.begin() - 1);
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

// ------------------------------------------------------------ measurements --

// The magnitudes of every force applied to particle i: body, applied,
// contacts (PFC `mech.ratio.avg`'s denominator) [N].
double World::applied_force_magnitude(std::size_t i) const {
  double a = norm(p_.mass[i] * field_.acceleration(p_.position[i], p_.velocity[i])) +
             norm(p_.applied_force[i]);
  for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e)
    if (bb_.properties[e] != kNoContact) a += norm(bb_.force_on_2[e]);
  for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k)
    if (bb_.properties[bb_.incoming[k]] != kNoContact) a += norm(bb_.force_on_2[bb_.incoming[k]]);
  for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e)
    if (bw_.properties[e] != kNoContact) a += norm(bw_.force_on_wall[e]);
  return a;
}

double World::unbalanced_force_ratio_over(const std::function<bool(std::size_t)>* include) const {
  const std::size_t n = p_.size();
  if (n == 0 || bb_.row_offset.size() != n + 1) return 0.0;
  // PFC `mech.ratio.avg`: average unbalanced force magnitude over the average
  // magnitude of the forces applied to the balls (body, applied, contacts).
  // Blocks of kBlock particles in parallel, their sums added in block order:
  // the rounding does not depend on how the blocks were shared out.
  constexpr std::size_t kBlock = 512;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> unbalanced(blocks), applied(blocks); // once per check, not per step
#pragma omp parallel for schedule(static) num_threads(thread_count(settings_, n))
  for (std::size_t b = 0; b < blocks; ++b) {
    double u = 0.0, a = 0.0;
    for (std::size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      if ((p_.flags[i] & fix_translation) || (include && !(*include)(i))) continue;
      u += norm(p_.force[i]);
      a += applied_force_magnitude(i);
    }
    unbalanced[b] = u;
    applied[b] = a;
  }
  double u = 0.0, a = 0.0;
  for (std::size_t b = 0; b < blocks; ++b) {
    u += unbalanced[b];
    a += applied[b];
  }
  return a > 0 ? u / a : 0.0;
}

double World::mean_unbalanced_force_ratio() const {
  return unbalanced_force_ratio_over(nullptr);
}

double World::mean_unbalanced_force_ratio(const std::function<bool(std::size_t)>& include) const {
  return unbalanced_force_ratio_over(&include);
}

Measurements World::measure() const {
  Measurements out;
  out.step = step_;
  out.time_s = time_;
  out.timestep_s = dt_;
  out.particles = p_.size();
  const std::size_t n = p_.size();
  if (bb_.row_offset.size() != n + 1) return out;
  double max_ratio = 0.0;
  std::size_t nbb = 0, nbw = 0;
  double ke = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      ++nbb;
      const std::uint32_t j = bb_.other[e];
      const double ov = p_.radius[i] + p_.radius[j] - norm(pair_vector(e, i, j));
      max_ratio = std::max(max_ratio, ov / std::min(p_.radius[i], p_.radius[j]));
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      ++nbw;
      const double ov = p_.radius[i] - wall_proximity(walls_[bw_.wall[e]], p_.position[i]).distance;
      max_ratio = std::max(max_ratio, ov / p_.radius[i]);
    }
    ke += 0.5 * p_.mass[i] * norm2(p_.velocity[i]) + 0.5 * p_.inertia[i] * norm2(p_.spin[i]);
  }
  out.ball_ball_contacts = nbb;
  out.ball_wall_contacts = nbw;
  out.coordination_number =
      n ? (2.0 * static_cast<double>(nbb) + static_cast<double>(nbw)) / static_cast<double>(n)
        : 0.0;
  out.mean_unbalanced_force_ratio = mean_unbalanced_force_ratio();
  out.kinetic_energy_J = ke;
  out.max_overlap_ratio = max_ratio;
  return out;
}

Energy World::energy() const {
  Energy en;
  const std::size_t n = p_.size();
  for (std::size_t i = 0; i < n; ++i) {
    en.kinetic_J += 0.5 * p_.mass[i] * norm2(p_.velocity[i]);
    en.rotational_J += 0.5 * p_.inertia[i] * norm2(p_.spin[i]);
  }
  if (bb_.row_offset.size() != n + 1) return en;
  auto strain = [&](const ContactProperties& cp, const ContactGeometry& g, const ContactState& s) {
    const ContactStiffness k = contact_stiffness(cp, g);
    const double ov = std::max(g.overlap_m, 0.0);
    en.strain_normal_J += 0.5 * k.kn * ov * ov;
    if (k.ks > 0) en.strain_shear_J += norm2(s.shear_force) / (2.0 * k.ks);
    if (k.kr > 0) en.strain_rolling_J += norm2(s.rolling_moment) / (2.0 * k.kr);
    en.attraction_J += attraction_potential(cp, g.overlap_m);
  };
  const auto& r = p_.radius;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const double ov = r[i] + r[j] - norm(pair_vector(e, i, j));
      strain(props_[bb_.properties[e]],
             {{}, ov, {}, {}, std::min(r[i], r[j]), r[i] + r[j], r[i] * r[j] / (r[i] + r[j]), 0.0},
             bb_.state[e]);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const double ov = r[i] - wall_proximity(walls_[bw_.wall[e]], p_.position[i]).distance;
      strain(props_[bw_.properties[e]], {{}, ov, {}, {}, r[i], r[i], r[i], 0.0}, bw_.state[e]);
    }
  }
  return en;
}

RegionMeasurement World::measure_region(const Box& box) const {
  RegionMeasurement out;
  const std::size_t n = p_.size();
  const double volume = box.volume();
  if (!(volume > 0)) throw InputError("region", "empty box", "hi must exceed lo on every axis");
  double solid = 0.0;
  std::array<double, 9> s{};
  auto add = [&](const Vec3& arm, const Vec3& f) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s[3 * a + b] += arm[a] * f[b];
  };
  const bool built = bb_.row_offset.size() == n + 1;
  const auto& x = p_.position;
  const auto& r = p_.radius;
  for (std::size_t i = 0; i < n; ++i) {
    if (!box.contains(x[i])) continue;
    ++out.particles;
    solid += 4.0 / 3.0 * std::numbers::pi * r[i] * r[i] * r[i];
    if (!built) continue;
    // Love-Weber: sigma = (1/V) sum_p sum_c (x_c - x_p) (x) F_c.
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const Vec3 d = pair_vector(e, i, j);
      const double dist = norm(d);
      const double ov = r[i] + r[j] - dist;
      add(d * ((r[i] - 0.5 * ov) / dist), -bb_.force_on_2[e]);
    }
    for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
      const std::uint32_t e = bb_.incoming[k];
      if (bb_.properties[e] == kNoContact) continue;
      const std::size_t a = first_end(e);
      const Vec3 d = -pair_vector(e, a, i);
      const double dist = norm(d);
      const double ov = r[i] + r[a] - dist;
      add(d * ((r[i] - 0.5 * ov) / dist), bb_.force_on_2[e]);
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const Wall& wl = walls_[bw_.wall[e]];
      const WallProximity prox = wall_proximity(wl, x[i]);
      const double ov = r[i] - prox.distance;
      add(ball_to_wall_normal(wl, prox) * (r[i] - 0.5 * ov), -bw_.force_on_wall[e]);
    }
  }
  for (double& v : s) v /= volume;
  out.stress_Pa = s;
  out.porosity = 1.0 - solid / volume;
  out.mean_pressure_Pa = -(s[0] + s[4] + s[8]) / 3.0;
  return out;
}

std::vector<ContactView> World::ball_ball_contacts() const {
  std::vector<ContactView> out;
  const std::size_t n = p_.size();
  if (bb_.row_offset.size() != n + 1) return out;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      if (bb_.properties[e] == kNoContact) continue;
      const std::uint32_t j = bb_.other[e];
      const Vec3 d = pair_vector(e, i, j);
      const double dist = norm(d);
      const double ov = p_.radius[i] + p_.radius[j] - dist;
      const Vec3 nrm = d / dist;
      out.push_back({static_cast<std::uint32_t>(i), j,
                     p_.position[i] + nrm * (p_.radius[i] - 0.5 * ov), nrm, bb_.force_on_2[e], ov,
                     bb_.properties[e]});
    }
  }
  return out;
}

std::size_t World::bytes_per_particle() const {
  const std::size_t n = p_.size();
  if (n == 0) return 0;
  auto cap = [](const auto& v) {
    return v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type);
  };
  std::size_t bytes = 0;
  for (const auto* v :
       {&p_.position, &p_.velocity, &p_.spin, &p_.force, &p_.moment, &p_.applied_force,
        &p_.applied_moment, &p_.displacement, &position_at_build_})
    bytes += cap(*v);
  bytes +=
      cap(p_.radius) + cap(p_.mass) + cap(p_.inertia) + cap(p_.id) + cap(p_.group) + cap(p_.flags);
  bytes += cap(bb_.row_offset) + cap(bb_.other) + cap(bb_.properties) + cap(bb_.state) +
           cap(bb_.force_on_2) + cap(bb_.moment_on_2) + cap(bb_.incoming_offset) +
           cap(bb_.incoming);
  bytes += cap(bw_.row_offset) + cap(bw_.wall) + cap(bw_.properties) + cap(bw_.state) +
           cap(bw_.force_on_wall);
  return bytes / n;
}

} // namespace centridem
