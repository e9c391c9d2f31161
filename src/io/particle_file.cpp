#include "io/particle_file.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <fmt/os.h>
#include <fstream>
#include <numeric>
#include <unordered_map>

namespace centridem {

std::vector<ParticleRecord> read_particle_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("particle file", "\"" + path + "\"", "cannot be opened for reading");
  std::vector<ParticleRecord> out;
  std::string line;
  long lineno = 0;
  const char* names[4] = {"x", "y", "z", "r"};
  while (std::getline(in, line)) {
    ++lineno;
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    double v[4];
    int k = 0;
    const char* p = line.data();
    const char* end = p + line.size();
    while (p < end) {
      while (p < end && (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r')) ++p;
      if (p >= end) break;
      double value = 0;
      auto [next, ec] = std::from_chars(p, end, value);
      if (ec != std::errc() || !std::isfinite(value)) {
        const char* stop = p;
        while (stop < end && *stop != ' ' && *stop != '\t' && *stop != ',') ++stop;
        throw InputError(fmt::format("{}:{} column {}", path, lineno, k + 1),
                         "\"" + std::string(p, stop) + "\"",
                         "expected a finite number (columns: x y z r, in metres)");
      }
      if (k < 4) v[k] = value;
      ++k;
      p = next;
    }
    if (k == 0) continue;
    if (k < 4)
      throw InputError(fmt::format("{}:{}", path, lineno), fmt::format("{} columns", k),
                       fmt::format("expected 4 columns x y z r (missing {})", names[k]));
    if (!(v[3] > 0))
      throw InputError(fmt::format("{}:{} column 4 (r)", path, lineno), fmt::format("{:g}", v[3]),
                       "radius must be > 0 [m]");
    out.push_back({{v[0], v[1], v[2]}, v[3], lineno});
  }
  if (out.empty()) throw InputError("particle file", "\"" + path + "\"", "holds no particles");
  return out;
}

void check_particle_overlaps(const std::vector<ParticleRecord>& records, const std::string& path,
                             double max_overlap_fraction) {
  if (records.size() < 2) return;
  double r_max = 0;
  for (const ParticleRecord& q : records) r_max = std::max(r_max, q.radius);
  // Cells of 2 r_max: two particles that touch are in the same or adjacent cells.
  const double cell = 2 * r_max;
  auto key = [](long i, long j, long k) {
    return (static_cast<std::uint64_t>(i & 0x1FFFFF) << 42) |
           (static_cast<std::uint64_t>(j & 0x1FFFFF) << 21) |
           static_cast<std::uint64_t>(k & 0x1FFFFF);
  };
  auto index = [&](double x) { return static_cast<long>(std::floor(x / cell)); };
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> grid;
  grid.reserve(records.size());
  for (std::size_t n = 0; n < records.size(); ++n) {
    const ParticleRecord& a = records[n];
    const long ci = index(a.position.x), cj = index(a.position.y), ck = index(a.position.z);
    for (long di = -1; di <= 1; ++di)
      for (long dj = -1; dj <= 1; ++dj)
        for (long dk = -1; dk <= 1; ++dk) {
          const auto it = grid.find(key(ci + di, cj + dj, ck + dk));
          if (it == grid.end()) continue;
          for (std::size_t m : it->second) {
            const ParticleRecord& b = records[m];
            const double overlap = a.radius + b.radius - norm(a.position - b.position);
            const double r_min = std::min(a.radius, b.radius);
            if (overlap > max_overlap_fraction * r_min)
              throw InputError(
                  fmt::format("{}:{} and line {}", path, b.line, a.line),
                  fmt::format("two particles {} apart (radii {:g} and {:g} m)",
                              overlap >= a.radius + b.radius
                                  ? std::string("0 m")
                                  : fmt::format("{:g} m", norm(a.position - b.position)),
                              b.radius, a.radius),
                  fmt::format("they overlap by {:.3g} of the smaller radius, more than the "
                              "run's overlap guard allows ({:g}, simulation.max_overlap_fraction)"
                              "; a line given twice, a packing to relax first, or radii "
                              "written in mm (everything is SI: m)",
                              overlap / r_min, max_overlap_fraction));
          }
        }
    grid[key(ci, cj, ck)].push_back(n);
  }
}

void write_particle_file(const World& world, const std::string& path) {
  const auto& p = world.particles();
  std::vector<std::size_t> order(p.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return p.id[a] < p.id[b]; });
  auto out = fmt::output_file(path);
  out.print("# x y z r vx vy vz (SI: m, m/s), one particle per line, in id order\n");
  for (std::size_t i : order) {
    const Vec3& x = p.position[i];
    const Vec3& v = p.velocity[i];
    out.print("{:.9e} {:.9e} {:.9e} {:.9e} {:.6e} {:.6e} {:.6e}\n", x.x, x.y, x.z, p.radius[i], v.x,
              v.y, v.z);
  }
}

} // namespace centridem
