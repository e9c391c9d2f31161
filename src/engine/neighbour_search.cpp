// Neighbour search: the cell grid, the half neighbour lists (ball-ball and
// ball-wall) with their incoming index, the re-sort of the particles into cell
// order, and the carry-over of contact history across rebuilds; also the
// build state that lets a checkpoint resume without a fresh rebuild.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include "base/errors.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fmt/format.h>
#include <numeric>
#include <span>
#include <unordered_map>

namespace centridem {

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

// Sizes a list for a rebuild, keeping its storage where that is large enough
// and at most a quarter larger. Growing, it takes the size and 1/16 more,
// not the doubling `resize` would give (which, kept from rebuild to rebuild,
// had the lists at 1.6 times their entries after a few rebuilds: 1,117
// bytes per particle on the bench packing instead of 709). The contents are
// not kept: every element is written by the rebuild.
template <class V> void size_list(V& v, std::size_t size) {
  if (size > v.capacity() || v.capacity() > size + size / 4 + 64) {
    V fresh;
    fresh.reserve(size + size / 16);
    v.swap(fresh);
  }
  v.resize(size);
}

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
  // The pending pairs in (i, j) order: counted into rows by i, then each row
  // (a handful of pairs) sorted by j. Each pair appears once, so this is the
  // order a sort of the whole list gives, at a fraction of its cost.
  std::vector<std::uint32_t> pend_start(n + 1, 0);
  for (const PendingPair& q : pending) ++pend_start[q.i + 1];
  std::partial_sum(pend_start.begin(), pend_start.end(), pend_start.begin());
  {
    std::vector<PendingPair> by_row(pending.size());
    std::vector<std::uint32_t> fill(pend_start.begin(), pend_start.end() - 1);
    for (const PendingPair& q : pending) by_row[fill[q.i]++] = q;
    pending = std::move(by_row);
    for (std::size_t i = 0; i < n; ++i)
      std::sort(pending.begin() + pend_start[i], pending.begin() + pend_start[i + 1],
                [](const PendingPair& a, const PendingPair& b) { return a.j < b.j; });
  }
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
  // The sorted positions and radii as structure of arrays, padded to whole
  // batches, so that the distance test below runs kLanes candidates at once.
  using Lanes = ContactLanes; // physics/lanes.hpp: the widest batch of doubles
  constexpr std::size_t kLanes = Lanes::size;
  std::vector<double> sx(n + kLanes, 0.0), sy(n + kLanes, 0.0), sz(n + kLanes, 0.0),
      sr(n + kLanes, 0.0);
  for (std::size_t k = 0; k < n; ++k) sx[k] = x[k].x, sy[k] = x[k].y, sz[k] = x[k].z, sr[k] = r[k];
  // visit(j, image code) for each j > i within reach, in increasing j; with
  // periodic axes a neighbour cell past the box wraps around and j is taken at
  // its image. The test is the scalar norm2(x[j] + shift - x[i]) < (r[i] + r[j]
  // + cut)^2, lane by lane with the same operations in the same order.
  auto for_each_candidate = [&](std::size_t i, auto&& visit) {
    const Lanes xi(x[i].x), yi(x[i].y), zi(x[i].z), ri(r[i]), cut_lanes(cut);
    std::array<std::int64_t, 3> c{grid.axis_cell(x[i].x, 0), grid.axis_cell(x[i].y, 1),
                                  grid.axis_cell(x[i].z, 2)};
    std::array<std::int64_t, 3> cc{};
    std::array<int, 3> sh{};
    // The candidates among sorted particles first .. hi - 1, taken at the
    // image `code`. Cells in a row along x hold consecutive particles, so the
    // three cells dx = -1, 0, 1 of a (dy, dz) row are one range: fewer, fuller
    // batches than cell by cell (the rebuild's scan 27 % faster on the flowing
    // column), and the same j in the same order.
    auto scan = [&](std::uint32_t first, std::uint32_t hi, std::uint8_t code) {
      const Vec3 shift = image_shift_[code];
      const Lanes shx(shift.x), shy(shift.y), shz(shift.z);
      for (std::uint32_t j0 = std::max<std::uint32_t>(first, static_cast<std::uint32_t>(i + 1));
           j0 < hi; j0 += kLanes) {
        const Lanes ddx = (Lanes::load_unaligned(&sx[j0]) + shx) - xi;
        const Lanes ddy = (Lanes::load_unaligned(&sy[j0]) + shy) - yi;
        const Lanes ddz = (Lanes::load_unaligned(&sz[j0]) + shz) - zi;
        const Lanes reach = (ri + Lanes::load_unaligned(&sr[j0])) + cut_lanes;
        std::uint64_t near = lane_bits(ddx * ddx + ddy * ddy + ddz * ddz < reach * reach);
        if (hi - j0 < kLanes) near &= (std::uint64_t{1} << (hi - j0)) - 1; // past the range
        for (; near != 0; near &= near - 1)
          visit(j0 + static_cast<std::uint32_t>(std::countr_zero(near)), code);
      }
    };
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        const int dd[3] = {0, dy, dz};
        bool skip = false;
        for (int a = 1; a < 3; ++a) {
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
        const std::int64_t row = (cc[2] * grid.n[1] + cc[1]) * grid.n[0];
        const int code_yz = 3 * (sh[1] + 1) + 9 * (sh[2] + 1);
        const bool wraps_x = grid.periodic[0] && (c[0] == 0 || c[0] == grid.n[0] - 1);
        if (!wraps_x) { // the three cells along x as one range
          const std::int64_t lo = std::max<std::int64_t>(c[0] - 1, 0);
          const std::int64_t hi = std::min<std::int64_t>(c[0] + 1, grid.n[0] - 1);
          scan(cell_start[static_cast<std::size_t>(row + lo)],
               cell_start[static_cast<std::size_t>(row + hi + 1)],
               static_cast<std::uint8_t>(1 + code_yz));
          continue;
        }
        // A periodic x wraps at this cell: cell by cell, in dx order (the
        // carry-over searches such rows, whose j do not increase).
        for (int dx = -1; dx <= 1; ++dx) {
          std::int64_t cx = c[0] + dx;
          int shx = 0;
          if (cx < 0 || cx >= grid.n[0]) {
            shx = cx < 0 ? -1 : 1;
            cx -= shx * grid.n[0];
          }
          const std::size_t cell = static_cast<std::size_t>(row + cx);
          scan(cell_start[cell], cell_start[cell + 1],
               static_cast<std::uint8_t>(shx + 1 + code_yz));
        }
      }
    }
  };
  auto near_wall = [&](std::size_t i, const Wall& w) {
    return wall_proximity(w, x[i]).distance < r[i] + cut;
  };

  // One sweep over the cells: the neighbours found for each block of rows are
  // kept, in row order, and copied into the lists once their sizes are known.
  struct Found {
    std::uint32_t j;
    std::uint8_t code;
  };
  constexpr std::size_t kBlock = 512; // rows
  std::vector<std::vector<Found>> found((n + kBlock - 1) / kBlock);
  std::vector<std::uint32_t> count(n + 1, 0), wall_count(n + 1, 0);
#pragma omp parallel for schedule(static, kBlock) num_threads(nthreads)
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<Found>& mine = found[i / kBlock];
    const std::size_t before = mine.size();
    for_each_candidate(i, [&](std::uint32_t j, std::uint8_t code) { mine.push_back({j, code}); });
    count[i + 1] = static_cast<std::uint32_t>(mine.size() - before);
    std::uint32_t cw = 0;
    for (const Wall& w : walls_) cw += near_wall(i, w) ? 1u : 0u;
    wall_count[i + 1] = cw;
  }
  std::partial_sum(count.begin(), count.end(), count.begin());
  std::partial_sum(wall_count.begin(), wall_count.end(), wall_count.begin());

  // The new lists reuse the old lists' storage (their history is in the
  // pending lists now), and every element is written once, by the fill below.
  BallBallContacts bb = std::move(bb_);
  bb.row_offset = std::move(count);
  const std::size_t entries = bb.row_offset[n];
  const bool periodic = periodic_.any();
  size_list(bb.other, entries);
  size_list(bb.properties, entries);
  size_list(bb.image, periodic ? entries : 0);
  size_list(bb.state, entries);
  size_list(bb.force_on_2, entries);
  size_list(bb.moment_on_2, entries);
  BallWallContacts bw = std::move(bw_);
  bw.row_offset = std::move(wall_count);
  const std::size_t wall_entries = bw.row_offset[n];
  size_list(bw.wall, wall_entries);
  size_list(bw.ball, wall_entries);
  size_list(bw.properties, wall_entries);
  size_list(bw.state, wall_entries);
  size_list(bw.force_on_wall, wall_entries);

  // Row starts into the pending wall list.
  std::vector<std::uint32_t> pend_wall_start(n + 1, 0);
  for (const PendingWall& q : pending_wall) ++pend_wall_start[q.i + 1];
  std::partial_sum(pend_wall_start.begin(), pend_wall_start.end(), pend_wall_start.begin());

#pragma omp parallel for schedule(static, kBlock) num_threads(nthreads)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t e = bb.row_offset[i];
    std::uint32_t q = pend_start[i];
    const std::size_t block = i / kBlock;
    const Found* f = found[block].data() + (e - bb.row_offset[block * kBlock]);
    for (const Found* row_end = f + (bb.row_offset[i + 1] - e); f != row_end; ++f) {
      const std::uint32_t j = f->j;
      const std::uint8_t code = f->code;
      bb.other[e] = j;
      if (periodic) bb.image[e] = code;
      const PendingPair* carried = nullptr;
      if (periodic) { // wrapped cells break the increasing-j order: search the row
        const auto first = pending.begin() + pend_start[i],
                   last = pending.begin() + pend_start[i + 1];
        const auto it = std::lower_bound(
            first, last, j, [](const PendingPair& pp, std::uint32_t jj) { return pp.j < jj; });
        if (it != last && it->j == j) carried = &*it;
      } else {
        while (q < pend_start[i + 1] && pending[q].j < j) ++q; // separated beyond the list
        if (q < pend_start[i + 1] && pending[q].j == j) carried = &pending[q];
      }
      bb.properties[e] = carried ? carried->properties : kNoContact;
      bb.state[e] = carried ? carried->state : ContactState{};
      bb.force_on_2[e] = {}; // all +0: every index is some entry's
      bb.moment_on_2[e] = {};
      ++e;
    }
    std::uint32_t ew = bw.row_offset[i];
    std::uint32_t qw = pend_wall_start[i];
    for (std::size_t k = 0; k < walls_.size(); ++k) {
      if (!near_wall(i, walls_[k])) continue;
      bw.wall[ew] = static_cast<std::uint16_t>(k);
      bw.ball[ew] = static_cast<std::uint32_t>(i);
      while (qw < pend_wall_start[i + 1] && pending_wall[qw].wall < k) ++qw;
      const bool carried = qw < pend_wall_start[i + 1] && pending_wall[qw].wall == k;
      bw.properties[ew] = carried ? pending_wall[qw].properties : kNoContact;
      bw.state[ew] = carried ? pending_wall[qw].state : ContactState{};
      bw.force_on_wall[ew] = {};
      ++ew;
    }
  }

  // Transpose (deterministic: incoming entries in increasing entry order).
  bb.incoming_offset.assign(n + 1, 0);
  for (std::size_t e = 0; e < entries; ++e) ++bb.incoming_offset[bb.other[e] + 1];
  std::partial_sum(bb.incoming_offset.begin(), bb.incoming_offset.end(),
                   bb.incoming_offset.begin());
  size_list(bb.incoming, entries);
  size_list(bb.slot_row, entries);
  {
    std::vector<std::uint32_t> fill(bb.incoming_offset.begin(), bb.incoming_offset.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      for (std::uint32_t e = bb.row_offset[i]; e < bb.row_offset[i + 1]; ++e) {
        const std::uint32_t k = fill[bb.other[e]]++;
        bb.incoming[k] = e;
        bb.slot_row[k] = static_cast<std::uint32_t>(i);
      }
  }
  bb.record_waits.assign(n, 0); // the records are all +0 again

  bb_ = std::move(bb);
  bw_ = std::move(bw);
  position_at_build_ = p_.position;
  move_bound_m_ = 0.0;
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

std::size_t World::first_end(std::uint32_t e) const {
  const auto it = std::upper_bound(bb_.row_offset.begin(), bb_.row_offset.end(), e);
  return static_cast<std::size_t>(it - bb_.row_offset.begin() - 1);
}

} // namespace centridem
