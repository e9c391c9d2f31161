// Bishop's simplified method on circular slip surfaces (see the header for the
// references). Notation of Duncan, Wright & Brandon (2014) ch. 6: slice i has
// width b, weight W, base inclination alpha, base length l. Moment equilibrium
// about the centre with vertical equilibrium of each slice (interslice shear
// neglected) gives
//
//   FS = sum[(c l cos(alpha) + W tan(phi)) / m_alpha] / sum[W x_W / R],
//   m_alpha = cos(alpha) + sin(alpha) tan(phi) / FS,
//
// the textbook FS = sum[(c b + W tan(phi)) / m_alpha] / sum[W sin(alpha)] with
// two thin-slice approximations made exact: l cos(alpha) for b (l is the
// slice's base arc, b / cos(alpha) its chord), and the lever arm x_W of the
// slice's weight about the centre (its centroid, integrated exactly) for
// R sin(alpha). For phi = 0 FS is then the exact moment balance of the
// circle, c R L_arc / sum(W x_W), whatever the number of slices.
//
// alpha is positive where the base descends in the direction of motion (the
// upslope part of the slip). The direction is that of the net moment of the
// weight about the centre, so a slope facing -x needs no special case.
//
// m_alpha guard: small or negative m_alpha (steep bases at the toe end with
// friction, near-vertical bases at the crest end) make Bishop's method
// unreliable (Whitman & Bailey 1967, J. Soil Mech. Found. Div. ASCE 93(SM4);
// DWB 2014 ch. 6). Usual practice is to flag such surfaces; here a circle
// with m_alpha < 0.2 in any slice, at the converged FS, is rejected as
// inadmissible (nullopt), not clipped.
#include "procedures/limit_equilibrium.hpp"

#include "base/errors.hpp"
#include "physics/body_field.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

namespace centridem {
namespace {

constexpr double kMinMAlpha = 0.2;
constexpr double kGravity = standard_gravity_m_s2; // the g of the g-levels, as the DEM's

std::string str(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

void require(bool ok, double value, const std::string& key, const std::string& allowed) {
  if (!ok || !std::isfinite(value)) throw InputError(key, str(value), allowed);
}

void validate(const LeCircle& c) {
  require(true, c.xc_m, "circle.xc_m", "a finite number [m]");
  require(true, c.zc_m, "circle.zc_m", "a finite number [m]");
  require(c.radius_m > 0, c.radius_m, "circle.radius_m", "> 0 [m]");
}

// One evaluated circle.
struct Slip {
  double fs, x_entry, x_exit, depth;
};

double sq(double v) {
  return v * v;
}

// Area and first moment about x = xc of the soil between the surface and the
// circle's lower arc over [xa, xb]: exact for a piecewise linear surface.
std::pair<double, double> strip(const LeSection& sec, const LeCircle& c, double xa, double xb) {
  const auto& p = sec.surface;
  double area = 0, moment = 0;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    const auto [sx0, sz0] = p[i];
    const auto [sx1, sz1] = p[i + 1];
    const double lo = std::max(xa, sx0), hi = std::min(xb, sx1);
    if (!(hi > lo)) continue;
    const auto z = [&](double x) { return sz0 + (sz1 - sz0) * (x - sx0) / (sx1 - sx0); };
    const double za = z(lo), zb = z(hi), mid = 0.5 * (lo + hi);
    area += 0.5 * (za + zb) * (hi - lo);
    moment += (hi - lo) / 6 * // Simpson, exact for the quadratic integrand
              ((lo - c.xc_m) * za + 4 * (mid - c.xc_m) * 0.5 * (za + zb) + (hi - c.xc_m) * zb);
  }
  const double R = c.radius_m, ua = xa - c.xc_m, ub = xb - c.xc_m; // minus the arc zc - S(u)
  const auto S = [R](double u) { return std::sqrt(std::max(0.0, R * R - u * u)); };
  const auto F = [&](double u) { // integral of S
    return 0.5 * (u * S(u) + R * R * std::asin(std::clamp(u / R, -1.0, 1.0)));
  };
  area -= c.zc_m * (ub - ua) - (F(ub) - F(ua));
  moment -= 0.5 * c.zc_m * (ub * ub - ua * ua) + (std::pow(S(ub), 3) - std::pow(S(ua), 3)) / 3;
  return {std::max(area, 0.0), moment};
}

// Bishop's FS of a validated circle, or nullopt (see the header).
std::optional<Slip> evaluate(const LeSection& sec, const LeSoil& soil, const LeCircle& c,
                             int slices) {
  const auto& p = sec.surface;
  const double R = c.radius_m;
  const auto inside = [&](std::pair<double, double> q) {
    return sq(q.first - c.xc_m) + sq(q.second - c.zc_m) < R * R;
  };
  // Where the surface enters and leaves the circle, in order along it. Both
  // ends of the surface must lie outside the circle.
  if (inside(p.front()) || inside(p.back())) return std::nullopt;
  std::vector<std::pair<double, double>> xs;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    const bool in0 = inside(p[i]), in1 = inside(p[i + 1]);
    if (in0 && in1) continue; // the disc is convex
    const double dx = p[i + 1].first - p[i].first, dz = p[i + 1].second - p[i].second;
    const double fx = p[i].first - c.xc_m, fz = p[i].second - c.zc_m;
    const double a = dx * dx + dz * dz, b = 2 * (fx * dx + fz * dz), cc = fx * fx + fz * fz - R * R;
    const double disc = b * b - 4 * a * cc;
    if (a == 0 || disc <= 0) continue; // tangent: no crossing
    const double t1 = (-b - std::sqrt(disc)) / (2 * a), t2 = (-b + std::sqrt(disc)) / (2 * a);
    const auto add = [&](double t) { xs.emplace_back(p[i].first + t * dx, p[i].second + t * dz); };
    if (in1) add(std::clamp(t1, 0.0, 1.0)); // enters
    if (in0) add(std::clamp(t2, 0.0, 1.0)); // leaves
    if (!in0 && !in1 && t1 > 0 && t2 < 1) add(t1), add(t2);
  }
  // Between an entry and the next exit the soil above the lower arc is a body
  // that can slide on its own. A circle that leaves the surface and cuts it
  // again (e.g. a toe circle of a steep cut, whose continuation passes under
  // the toe) holds several; the heaviest is analysed. Its ends must lie on the
  // lower half of the circle.
  double x0 = 0, x1 = 0, z_ends = 0, heaviest = 0;
  for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
    const auto [xa, za] = xs[k];
    const auto [xb, zb] = xs[k + 1];
    if (za > c.zc_m || zb > c.zc_m || !(xb - xa > 1e-9 * R)) continue;
    const double area = strip(sec, c, xa, xb).first;
    if (area > heaviest) heaviest = area, x0 = xa, x1 = xb, z_ends = std::min(za, zb);
  }
  if (heaviest == 0) return std::nullopt;
  const double z_low = (c.xc_m > x0 && c.xc_m < x1) ? c.zc_m - R : z_ends;
  if (z_low < sec.floor_z_m - 1e-9 * R) return std::nullopt;

  // Slices of equal width.
  const double b = (x1 - x0) / slices;
  const auto theta = [R](double u) { return std::asin(std::clamp(u / R, -1.0, 1.0)); };
  struct Slice {
    double area, moment, l, theta_m;
  };
  std::vector<Slice> sl(slices);
  double moment_sum = 0, depth = 0;
  for (int k = 0; k < slices; ++k) {
    const double xa = x0 + k * b, xb = k + 1 == slices ? x1 : x0 + (k + 1) * b;
    const auto [area, moment] = strip(sec, c, xa, xb);
    const double ua = xa - c.xc_m, ub = xb - c.xc_m;
    sl[k] = {area, moment, R * (theta(ub) - theta(ua)), 0.5 * (theta(ua) + theta(ub))};
    moment_sum += moment;
    depth = std::max(depth, area / (xb - xa));
  }
  // Motion towards +x (s = 1, counter-clockwise) when the weight lies on the
  // -x side of the centre on balance.
  if (moment_sum == 0) return std::nullopt;
  const double s = moment_sum < 0 ? 1.0 : -1.0;
  const double g = soil.unit_weight_N_m3, c_ = soil.cohesion_Pa;
  const double tan_phi = std::tan(soil.friction_angle_deg * std::numbers::pi / 180);
  double drive = 0, fs = 0; // sum W x_W / R; start from the ordinary method
  for (const auto& e : sl) drive += -s * g * e.moment / R;
  for (const auto& e : sl) fs += c_ * e.l + g * e.area * std::cos(e.theta_m) * tan_phi;
  fs /= drive;
  if (!(fs >= 0)) return std::nullopt;
  for (int it = 0; it < 200; ++it) {
    double resist = 0, m_min = std::numeric_limits<double>::infinity();
    for (const auto& e : sl) {
      const double cos_a = std::cos(e.theta_m), sin_a = -s * std::sin(e.theta_m);
      const double m = cos_a + (tan_phi > 0 ? sin_a * tan_phi / fs : 0.0);
      m_min = std::min(m_min, m);
      if (m <= 0) return std::nullopt;
      resist += (c_ * e.l * cos_a + g * e.area * tan_phi) / m;
    }
    const double next = resist / drive;
    if (std::abs(next - fs) <= 1e-10 * next) {
      // m_min is that of fs, within 1e-10 of next
      if (m_min < kMinMAlpha) return std::nullopt;
      return Slip{next, x0, x1, depth};
    }
    fs = next;
  }
  return std::nullopt; // no convergence
}

} // namespace

void validate(const LeSection& sec) {
  const auto& p = sec.surface;
  require(p.size() >= 2, static_cast<double>(p.size()), "section.surface",
          "at least 2 (x, z) points");
  require(true, sec.floor_z_m, "section.floor_z_m", "a finite number [m]");
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::string k = "section.surface[" + std::to_string(i) + "]";
    require(i == 0 || p[i].first >= p[i - 1].first, p[i].first, k + ".x",
            "finite, >= the previous point's x (points ordered along the surface)");
    require(p[i].second >= sec.floor_z_m, p[i].second, k + ".z", "finite, >= section.floor_z_m");
  }
  require(p.back().first > p.front().first, p.back().first - p.front().first, "section.surface",
          "points spanning a positive x range");
}

void validate(const LeSoil& soil) {
  require(soil.cohesion_Pa >= 0, soil.cohesion_Pa, "soil.cohesion_Pa", ">= 0 [Pa]");
  require(soil.friction_angle_deg >= 0 && soil.friction_angle_deg < 90, soil.friction_angle_deg,
          "soil.friction_angle_deg", "0 <= phi < 90 [deg]");
  require(soil.unit_weight_N_m3 > 0, soil.unit_weight_N_m3, "soil.unit_weight_N_m3", "> 0 [N/m^3]");
}

std::optional<double> bishop_factor_of_safety(const LeSection& section, const LeSoil& soil,
                                              const LeCircle& circle, int slices) {
  validate(section);
  validate(soil);
  validate(circle);
  require(slices >= 1, slices, "slices", ">= 1");
  const auto slip = evaluate(section, soil, circle, slices);
  return slip ? std::optional<double>(slip->fs) : std::nullopt;
}

LeSearchResult critical_circle(const LeSection& sec, const LeSoil& soil, const LeSearchOptions& o) {
  validate(sec);
  validate(soil);
  const std::initializer_list<std::pair<int, const char*>> counts{
      {o.centres_x, "options.centres_x"},
      {o.centres_z, "options.centres_z"},
      {o.radii, "options.radii"},
      {o.slices, "options.slices"}};
  for (const auto& [v, k] : counts) require(v >= 1, v, k, ">= 1");
  require(o.refine_starts >= 0, o.refine_starts, "options.refine_starts", ">= 0");
  require(o.centre_height_factor >= 0, o.centre_height_factor, "options.centre_height_factor",
          ">= 0");
  require(true, o.min_depth_m, "options.min_depth_m", "a finite number [m]");

  const auto& p = sec.surface;
  const double x_min = p.front().first, x_max = p.back().first;
  double z_lo = p[0].second, z_hi = p[0].second;
  for (const auto& q : p) z_lo = std::min(z_lo, q.second), z_hi = std::max(z_hi, q.second);
  const double height = z_hi > z_lo ? z_hi - z_lo : 0.1 * (x_max - x_min);
  const double min_depth = o.min_depth_m > 0 ? o.min_depth_m : 0.02 * height;

  LeSearchResult best;
  best.factor_of_safety = std::numeric_limits<double>::infinity();
  const auto fs_of = [&](const LeCircle& c) {
    ++best.circles_tried;
    if (!(c.radius_m > 0)) return std::numeric_limits<double>::infinity();
    const auto slip = evaluate(sec, soil, c, o.slices);
    if (!slip || slip->depth < min_depth) return std::numeric_limits<double>::infinity();
    if (slip->fs < best.factor_of_safety) {
      best.factor_of_safety = slip->fs;
      best.circle = c;
      best.x_entry_m = slip->x_entry;
      best.x_exit_m = slip->x_exit;
    }
    return slip->fs;
  };
  // Radii from the nearest point of the surface to the farthest.
  const auto radius_range = [&](double xc, double zc) {
    double d_min = std::numeric_limits<double>::infinity(), d_max = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      d_max = std::max(d_max, std::hypot(p[i].first - xc, p[i].second - zc));
      if (i + 1 == p.size()) break;
      const double dx = p[i + 1].first - p[i].first, dz = p[i + 1].second - p[i].second;
      const double t = std::clamp(
          ((xc - p[i].first) * dx + (zc - p[i].second) * dz) / (dx * dx + dz * dz), 0.0, 1.0);
      d_min = std::min(d_min, std::hypot(p[i].first + t * dx - xc, p[i].second + t * dz - zc));
    }
    return std::pair{d_min, d_max};
  };

  // Grid: the best radius of every centre.
  const double hx = (x_max - x_min) / o.centres_x;
  const double hz = (z_hi + o.centre_height_factor * height - z_lo) / o.centres_z;
  struct Start {
    double fs;
    LeCircle c;
    double hr;
  };
  std::vector<Start> starts;
  for (int i = 0; i < o.centres_x; ++i)
    for (int j = 0; j < o.centres_z; ++j) {
      const double xc = x_min + (i + 0.5) * hx, zc = z_lo + (j + 0.5) * hz;
      const auto [d_min, d_max] = radius_range(xc, zc);
      const double hr = (d_max - d_min) / o.radii;
      Start s{std::numeric_limits<double>::infinity(), {}, hr};
      for (int k = 0; k < o.radii; ++k) {
        const LeCircle c{xc, zc, d_min + (k + 0.5) * hr};
        const double fs = fs_of(c);
        if (fs < s.fs) s.fs = fs, s.c = c;
      }
      if (std::isfinite(s.fs)) starts.push_back(s);
    }
  std::stable_sort(starts.begin(), starts.end(),
                   [](const Start& a, const Start& b) { return a.fs < b.fs; });

  // Pattern search from the best few: move to the best of the 26 neighbours
  // (centre and radius steps), halve the steps when none is better.
  const int n_starts = std::min<int>(o.refine_starts, static_cast<int>(starts.size()));
  for (int s = 0; s < n_starts; ++s) {
    LeCircle c = starts[s].c;
    double fs = starts[s].fs;
    std::array<double, 3> h{hx, hz, starts[s].hr};
    for (int it = 0; it < 2000 && h[0] > 1e-5 * height; ++it) {
      LeCircle next = c;
      double fs_next = fs;
      for (int a = -1; a <= 1; ++a)
        for (int bz = -1; bz <= 1; ++bz)
          for (int r = -1; r <= 1; ++r) {
            if (a == 0 && bz == 0 && r == 0) continue;
            const LeCircle t{c.xc_m + a * h[0], c.zc_m + bz * h[1], c.radius_m + r * h[2]};
            const double f = fs_of(t);
            if (f < fs_next) fs_next = f, next = t;
          }
      if (fs_next < fs)
        c = next, fs = fs_next;
      else
        for (double& v : h) v *= 0.5;
    }
  }
  if (std::isfinite(best.factor_of_safety)) {
    const auto& c = best.circle;
    for (int k = 0; k <= o.slices; ++k) {
      const double x = best.x_entry_m + (best.x_exit_m - best.x_entry_m) * k / o.slices;
      best.slip_surface.emplace_back(
          x, c.zc_m - std::sqrt(std::max(0.0, sq(c.radius_m) - sq(x - c.xc_m))));
    }
  }
  return best;
}

LeCriticalG critical_g_level(const LeSection& section, double cohesion_Pa,
                             double friction_angle_deg, double bulk_density_kg_m3,
                             const LeCriticalGOptions& o) {
  require(bulk_density_kg_m3 > 0, bulk_density_kg_m3, "bulk_density_kg_m3", "> 0 [kg/m^3]");
  require(o.n_lo > 0, o.n_lo, "options.n_lo", "> 0");
  require(o.n_hi > o.n_lo, o.n_hi, "options.n_hi", "> options.n_lo");
  require(o.fs_tolerance > 0, o.fs_tolerance, "options.fs_tolerance", "> 0");
  const auto search = [&](double n) {
    return critical_circle(
        section, {cohesion_Pa, friction_angle_deg, bulk_density_kg_m3 * kGravity * n}, o.search);
  };
  const auto found = [&](const LeCriticalG& r) {
    return std::abs(r.at_critical.factor_of_safety - 1) <= o.fs_tolerance;
  };
  LeCriticalG out{o.n_lo, false, search(o.n_lo)};
  if (found(out)) out.bracketed = true;
  if (out.bracketed || out.at_critical.factor_of_safety < 1) return out;
  LeCriticalG hi{o.n_hi, false, search(o.n_hi)};
  if (found(hi)) hi.bracketed = true;
  if (hi.bracketed || hi.at_critical.factor_of_safety > 1) return hi;

  // Illinois on f(x) = ln FS(e^x), f(a) > 0 > f(b).
  double a = std::log(o.n_lo), fa = std::log(out.at_critical.factor_of_safety);
  double b = std::log(o.n_hi), fb = std::log(hi.at_critical.factor_of_safety);
  LeCriticalG best = std::abs(fa) < std::abs(fb) ? out : hi;
  best.bracketed = true;
  int side = 0;
  for (int it = 0; it < o.max_iterations && b - a > 1e-12; ++it) {
    const double x = (a * fb - b * fa) / (fb - fa);
    LeCriticalG t{std::exp(x), true, search(std::exp(x))};
    const double f = std::log(t.at_critical.factor_of_safety);
    if (std::abs(f) < std::abs(std::log(best.at_critical.factor_of_safety))) best = t;
    if (found(t)) break;
    if (f > 0) {
      a = x, fa = f;
      if (side == 1) fb *= 0.5;
      side = 1;
    } else {
      b = x, fb = f;
      if (side == -1) fa *= 0.5;
      side = -1;
    }
  }
  return best;
}

} // namespace centridem
