#include "io/picture.hpp"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <stdexcept>

namespace centridem {

namespace {

struct MapEntry {
  double index; // position in matplotlib's 256-entry table
  Rgb c;
};

// viridis (van der Walt & Smith, matplotlib, CC0): every 16th of its 256
// entries plus the last; linear interpolation between them stays within
// about 1/255 of the full table.
constexpr std::array<MapEntry, 17> viridis_table{{
    {0, {0.267004, 0.004874, 0.329415}},
    {16, {0.282327, 0.094955, 0.417331}},
    {32, {0.278826, 0.175490, 0.483397}},
    {48, {0.258965, 0.251537, 0.524736}},
    {64, {0.229739, 0.322361, 0.545706}},
    {80, {0.199430, 0.387607, 0.554642}},
    {96, {0.172719, 0.448791, 0.557885}},
    {112, {0.149039, 0.508051, 0.557250}},
    {128, {0.127568, 0.566949, 0.550556}},
    {144, {0.120638, 0.625828, 0.533488}},
    {160, {0.157851, 0.683765, 0.501686}},
    {176, {0.246070, 0.738910, 0.452024}},
    {192, {0.369214, 0.788888, 0.382914}},
    {208, {0.515992, 0.831158, 0.294279}},
    {224, {0.678489, 0.863742, 0.189503}},
    {240, {0.845561, 0.887322, 0.099702}},
    {255, {0.993248, 0.906157, 0.143936}},
}};

// turbo (Mikhailov 2019, Google, Apache-2.0): the published degree-5
// polynomial fit of the table.
Rgb turbo(double t) {
  auto poly = [t](double c0, double c1, double c2, double c3, double c4, double c5) {
    return std::clamp(c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * c5)))), 0.0, 1.0);
  };
  return {poly(0.13572138, 4.61539260, -42.66032258, 132.13108234, -152.94239396, 59.28637943),
          poly(0.09140261, 2.19418839, 4.84296658, -14.18503333, 4.27729857, 2.82956604),
          poly(0.10667330, 12.64194608, -60.58204836, 110.36276771, -89.90310912, 27.34824973)};
}

} // namespace

Rgb colour_map(ColourMap map, double t) {
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0);
  if (map == ColourMap::turbo) return turbo(t);
  const double idx = t * 255.0;
  std::size_t k = 1;
  while (k + 1 < viridis_table.size() && viridis_table[k].index < idx) ++k;
  const MapEntry& a = viridis_table[k - 1];
  const MapEntry& b = viridis_table[k];
  const double f = std::clamp((idx - a.index) / (b.index - a.index), 0.0, 1.0);
  return {a.c.r + f * (b.c.r - a.c.r), a.c.g + f * (b.c.g - a.c.g), a.c.b + f * (b.c.b - a.c.b)};
}

namespace {

// Fraction of the scale for `value`; < 0 below vmin (or invalid).
double scale_fraction(double value, double vmin, double vmax, bool log_scale) {
  if (!std::isfinite(value) || value < vmin) return -1;
  if (log_scale) {
    if (!(vmin > 0) || !(vmax > vmin)) return value >= vmax ? 1 : -1;
    return (std::log10(value) - std::log10(vmin)) / (std::log10(vmax) - std::log10(vmin));
  }
  if (!(vmax > vmin)) return 1;
  return (value - vmin) / (vmax - vmin);
}

} // namespace

Rgb scale_colour(double value, double vmin, double vmax, bool log_scale, ColourMap map) {
  const double f = scale_fraction(value, vmin, vmax, log_scale);
  if (f < 0) return below_scale_colour;
  return colour_map(map, std::min(f, 1.0));
}

SideViewWindow side_view_window(const SideViewInput& in) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, z0 = x0, z1 = -x0;
  const std::size_t n = std::min({in.x.size(), in.z.size(), in.radius.size()});
  const bool use_y = in.slice && in.y.size() >= n;
  for (std::size_t i = 0; i < n; ++i) {
    if (use_y && !(std::abs(in.y[i] - in.slice_y_mid) < in.slice_half_thickness)) continue;
    const double r = std::isfinite(in.radius[i]) ? in.radius[i] : 0.0;
    if (!std::isfinite(in.x[i]) || !std::isfinite(in.z[i])) continue;
    x0 = std::min(x0, in.x[i] - r);
    x1 = std::max(x1, in.x[i] + r);
    z0 = std::min(z0, in.z[i] - r);
    z1 = std::max(z1, in.z[i] + r);
  }
  auto add_line = [&](const SideViewPolyline& l) {
    for (std::size_t k = 0; k < std::min(l.x.size(), l.z.size()); ++k) {
      if (!std::isfinite(l.x[k]) || !std::isfinite(l.z[k])) continue;
      x0 = std::min(x0, l.x[k]);
      x1 = std::max(x1, l.x[k]);
      z0 = std::min(z0, l.z[k]);
      z1 = std::max(z1, l.z[k]);
    }
  };
  add_line(in.outline);
  if (!(x1 >= x0)) return {0, 1, 0, 1};
  if (!(x1 > x0)) {
    x0 -= 0.5;
    x1 += 0.5;
  }
  if (!(z1 > z0)) {
    z0 -= 0.5 * (x1 - x0);
    z1 += 0.5 * (x1 - x0);
  }
  const double m = 0.03 * std::max(x1 - x0, z1 - z0);
  return {x0 - m, x1 + m, z0 - m, z1 + m};
}

namespace {

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using ContextPtr = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

void set_font(cairo_t* cr, double size, bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

double text_width(cairo_t* cr, const std::string& s) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  return e.x_advance;
}

double cap_height(cairo_t* cr) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, "0", &e);
  return -e.y_bearing;
}

// Anchor (x, y): ax 0 left, 0.5 centre, 1 right; vertical: middle of the
// capitals when vmid, else the baseline.
void draw_text(cairo_t* cr, const std::string& s, double x, double y, double ax, bool vmid) {
  if (s.empty()) return;
  const double w = text_width(cr, s);
  cairo_move_to(cr, x - ax * w, vmid ? y + 0.5 * cap_height(cr) : y);
  cairo_show_text(cr, s.c_str());
  cairo_new_path(cr);
}

void set_colour(cairo_t* cr, const Rgb& c) {
  cairo_set_source_rgb(cr, c.r, c.g, c.b);
}

double crisp(double v) {
  return std::floor(v) + 0.5;
}

// Labelled values of the colour bar: both ends, then 1-2-5 values inside
// (log) or nice ticks (linear), skipping any too close to one already placed.
std::vector<double> colour_bar_ticks(const SideViewInput& in, double bar_px, double min_gap_px) {
  std::vector<double> out{in.vmin, in.vmax};
  std::vector<double> cand;
  if (in.log_scale && in.vmin > 0 && in.vmax > in.vmin) {
    const int e0 = static_cast<int>(std::floor(std::log10(in.vmin))) - 1;
    const int e1 = static_cast<int>(std::ceil(std::log10(in.vmax))) + 1;
    // Decades first, so they win over 2 and 5 when space is short.
    for (int m : {1, 5, 2})
      for (int e = e0; e <= e1; ++e) cand.push_back(m * std::pow(10.0, e));
  } else {
    cand = nice_ticks(in.vmin, in.vmax, 6);
  }
  for (double v : cand) {
    if (v <= in.vmin * (1 + 1e-9) || v >= in.vmax * (1 - 1e-9)) continue;
    const double f = scale_fraction(v, in.vmin, in.vmax, in.log_scale);
    bool ok = true;
    for (double u : out)
      if (std::abs(f - scale_fraction(u, in.vmin, in.vmax, in.log_scale)) * bar_px < min_gap_px)
        ok = false;
    if (ok) out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Where draw_disc() paints: an RGB24 image (0x00RRGGBB per pixel) and the
// pixel rectangle [x0, x1) x [y0, y1) it may touch.
struct PixelTarget {
  std::uint32_t* data;
  int stride; // pixels per row
  int x0, y0, x1, y1;
};

// An antialiased filled disc centred at (cx, cy) px (pixel centres at
// half-integers), blended over what is there. Discs of radius >= 1.5 px get a
// thin darker rim so that touching particles of one colour stay apart.
void draw_disc(const PixelTarget& t, double cx, double cy, double r, const Rgb& c) {
  if (!(r > 0)) return;
  const double re = std::max(r, 0.5); // tiny discs still cover about a pixel
  const int ix0 = std::max(t.x0, static_cast<int>(std::floor(cx - re - 0.5)));
  const int ix1 = std::min(t.x1, static_cast<int>(std::ceil(cx + re + 0.5)));
  const int iy0 = std::max(t.y0, static_cast<int>(std::floor(cy - re - 0.5)));
  const int iy1 = std::min(t.y1, static_cast<int>(std::ceil(cy + re + 0.5)));
  if (ix0 >= ix1 || iy0 >= iy1) return;
  const bool rim = r >= 1.5;
  const double rim_w = std::clamp(0.09 * r, 0.55, 1.2);
  const double fr = 255.0 * c.r, fg = 255.0 * c.g, fb = 255.0 * c.b;
  const double dk = rim ? 0.7 : 1.0; // rim colour factor
  // Area scale so that sub-pixel discs keep their apparent weight.
  const double cov_scale = r < 0.5 ? std::max(0.25, (r * r) / 0.25) : 1.0;
  const double solid = std::max(0.0, re - 0.5 - (rim ? rim_w + 0.5 : 0.0)); // fully inside, no rim
  const double solid2 = solid * solid;
  const auto fill_px = static_cast<std::uint32_t>((static_cast<std::uint32_t>(fr + 0.5) << 16) |
                                                  (static_cast<std::uint32_t>(fg + 0.5) << 8) |
                                                  static_cast<std::uint32_t>(fb + 0.5));
  const double outer2 = (re + 0.5) * (re + 0.5);
  for (int py = iy0; py < iy1; ++py) {
    const double dy = py + 0.5 - cy;
    if (dy * dy >= outer2) continue;
    std::uint32_t* row = t.data + static_cast<std::ptrdiff_t>(py) * t.stride;
    // Pixels whose centres are inside the solid core are set directly; only
    // those near the edge get a coverage computed.
    const double half_out = std::sqrt(outer2 - dy * dy);
    const int px0 = std::max(ix0, static_cast<int>(std::floor(cx - half_out)));
    const int px1 = std::min(ix1, static_cast<int>(std::ceil(cx + half_out)));
    int core0 = 0, core1 = -1; // [core0, core1) set directly
    if (cov_scale == 1.0 && dy * dy < solid2) {
      const double half_in = std::sqrt(solid2 - dy * dy);
      core0 = std::max(px0, static_cast<int>(std::ceil(cx - half_in - 0.5)));
      core1 = std::min(px1, static_cast<int>(std::floor(cx + half_in - 0.5)) + 1);
    }
    auto edge = [&](int px) {
      const double dx = px + 0.5 - cx;
      const double d = std::sqrt(dx * dx + dy * dy);
      const double a = std::clamp(re - d + 0.5, 0.0, 1.0) * cov_scale;
      if (a <= 0) return;
      double k = 1.0;
      if (rim) {
        const double w = std::clamp(d - (r - rim_w) + 0.5, 0.0, 1.0); // 0 inside, 1 on the rim
        k = 1.0 + w * (dk - 1.0);
      }
      const std::uint32_t dst = row[px];
      const double dr = (dst >> 16) & 0xff, dg = (dst >> 8) & 0xff, db = dst & 0xff;
      const double b = 1.0 - a;
      const auto out = [](double v) {
        return static_cast<std::uint32_t>(std::clamp(v + 0.5, 0.0, 255.0));
      };
      row[px] = (out(dr * b + fr * k * a) << 16) | (out(dg * b + fg * k * a) << 8) |
                out(db * b + fb * k * a);
    };
    if (core1 > core0) {
      for (int px = px0; px < core0; ++px) edge(px);
      std::fill(row + core0, row + core1, fill_px);
      for (int px = core1; px < px1; ++px) edge(px);
    } else {
      for (int px = px0; px < px1; ++px) edge(px);
    }
  }
}

std::string bar_label(const SideViewInput& in, double v) {
  const double f = in.value_display_factor;
  if (in.log_scale) return format_log_tick(v * f);
  return format_tick(v * f, f * nice_step(in.vmin, in.vmax, 6));
}

} // namespace

namespace {

// The layout and the sizes render_side_view() draws with.
struct Frame {
  SideViewLayout layout;
  double s = 1, f_title = 20, f_label = 15, f_tick = 13, top = 0, bar_min = 0;
  bool any_key = false;
};

Frame frame_for(const SideViewInput& in) {
  if (in.width_px < 200 || in.width_px > 20000)
    throw std::invalid_argument("render_side_view: width_px = " + std::to_string(in.width_px) +
                                " is outside 200..20000");
  Frame f;
  SideViewLayout& L = f.layout;
  L.window = in.window ? *in.window : side_view_window(in);
  const SideViewWindow& win = L.window;
  if (!(win.x_max > win.x_min) || !(win.z_max > win.z_min) ||
      !std::isfinite(win.x_max - win.x_min) || !std::isfinite(win.z_max - win.z_min))
    throw std::invalid_argument("render_side_view: the window is empty");
  // Title on top (with a key of the lines under it), z axis on the left, x
  // axis below, colour bar on the right. Sizes scale with the width (1200 px
  // is the reference).
  const double W = in.width_px;
  f.s = std::clamp(W / 1200.0, 0.85, 3.0); // below 0.85 text gets hard to read
  f.f_title = 20 * f.s;
  f.f_label = 15 * f.s;
  f.f_tick = 13 * f.s;
  f.any_key = std::any_of(in.extra_lines.begin(), in.extra_lines.end(),
                          [](const auto& l) { return !l.label.empty() && !l.x.empty(); }) ||
              (!in.outline.label.empty() && !in.outline.x.empty());
  f.top = (in.title.empty() ? 14 * f.s : 2.2 * f.f_title) + (f.any_key ? 1.7 * f.f_tick : 0);
  const double left = 78 * f.s, right = 150 * f.s, bottom = 62 * f.s;
  f.bar_min = 190 * f.s; // the colour bar needs at least this much height
  L.plot_width = std::max(10.0, W - left - right);
  L.px_per_m = L.plot_width / (win.x_max - win.x_min);
  L.plot_height = (win.z_max - win.z_min) * L.px_per_m;
  const double H = std::ceil(f.top + std::max(L.plot_height, f.bar_min) + bottom);
  if (H > 30000)
    throw std::invalid_argument("render_side_view: the picture would be " + std::to_string(H) +
                                " px tall; give a wider window or a smaller width");
  L.width_px = in.width_px;
  L.height_px = static_cast<int>(H);
  L.plot_x0 = left;
  // Vertically centred in the space left when the colour bar needs more
  // height than the model.
  L.plot_y0 = f.top + 0.5 * (std::max(L.plot_height, f.bar_min) - L.plot_height);
  return f;
}

} // namespace

SideViewLayout side_view_layout(const SideViewInput& in) {
  return frame_for(in).layout;
}

SideViewLayout render_side_view(const SideViewInput& in, const std::string& png_path) {
  const std::size_t n = in.x.size();
  if (in.z.size() != n || in.radius.size() != n)
    throw std::invalid_argument("render_side_view: x, z and radius must have the same length (" +
                                std::to_string(n) + ", " + std::to_string(in.z.size()) + ", " +
                                std::to_string(in.radius.size()) + ")");
  if (!in.value.empty() && in.value.size() != n)
    throw std::invalid_argument("render_side_view: value has " + std::to_string(in.value.size()) +
                                " entries for " + std::to_string(n) + " particles");
  if (!in.y.empty() && in.y.size() != n)
    throw std::invalid_argument("render_side_view: y has " + std::to_string(in.y.size()) +
                                " entries for " + std::to_string(n) + " particles");
  if (in.slice && in.y.empty())
    throw std::invalid_argument("render_side_view: a slice needs the particles' y");
  for (const auto* l : {&in.outline})
    if (l->x.size() != l->z.size())
      throw std::invalid_argument("render_side_view: the outline's x and z differ in length");
  for (const auto& l : in.extra_lines)
    if (l.x.size() != l.z.size())
      throw std::invalid_argument("render_side_view: an extra line's x and z differ in length");

  const Frame fr = frame_for(in);
  const SideViewLayout& lay = fr.layout;
  const SideViewWindow& win = lay.window;
  const double s = fr.s, f_title = fr.f_title, f_label = fr.f_label, f_tick = fr.f_tick;
  const double tick_len = 5 * s, top = fr.top, bar_min = fr.bar_min;
  const bool any_key = fr.any_key;
  const double plot_w = lay.plot_width, plot_h = lay.plot_height, k = lay.px_per_m;
  const int Wi = lay.width_px, H = lay.height_px;

  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, Wi, H), &cairo_surface_destroy);
  ContextPtr ctx(cairo_create(surface.get()), &cairo_destroy);
  cairo_t* cr = ctx.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  const double pa_x0 = lay.plot_x0, pa_y0 = lay.plot_y0;
  auto X = [&](double x) { return lay.px_x(x); };
  auto Z = [&](double z) { return lay.px_y(z); };

  // Particles, far to near (largest y first).
  std::vector<std::uint32_t> order;
  order.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (in.slice && !(std::abs(in.y[i] - in.slice_y_mid) < in.slice_half_thickness)) continue;
    const double r = in.radius[i];
    if (!std::isfinite(in.x[i]) || !std::isfinite(in.z[i]) || !(r > 0)) continue;
    if (in.x[i] + r < win.x_min || in.x[i] - r > win.x_max || in.z[i] + r < win.z_min ||
        in.z[i] - r > win.z_max)
      continue;
    order.push_back(static_cast<std::uint32_t>(i));
  }
  if (!in.y.empty())
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return in.y[a] > in.y[b]; });

  // The discs are rasterised straight into the image (cairo's path filling
  // costs ~8 us a circle, ~30x more), clipped to the plot area.
  {
    cairo_surface_flush(surface.get());
    PixelTarget target{
        reinterpret_cast<std::uint32_t*>(cairo_image_surface_get_data(surface.get())),
        cairo_image_surface_get_stride(surface.get()) / 4,
        static_cast<int>(std::floor(pa_x0)),
        static_cast<int>(std::floor(pa_y0)),
        static_cast<int>(std::ceil(pa_x0 + plot_w)),
        static_cast<int>(std::ceil(pa_y0 + plot_h))};
    for (std::uint32_t i : order) {
      const double v = in.value.empty() ? std::numeric_limits<double>::quiet_NaN() : in.value[i];
      const Rgb c = scale_colour(v, in.vmin, in.vmax, in.log_scale, in.colour_map);
      draw_disc(target, X(in.x[i]), Z(in.z[i]), in.radius[i] * k, c);
    }
    cairo_surface_mark_dirty(surface.get());
  }

  cairo_save(cr);
  cairo_rectangle(cr, pa_x0, pa_y0, plot_w, plot_h);
  cairo_clip(cr);
  // Lines on top: extra lines, then the outline.
  auto stroke_line = [&](const SideViewPolyline& l) {
    if (l.x.size() < 2) return;
    cairo_save(cr);
    cairo_set_line_width(cr, l.width_px * s);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_set_line_cap(cr, l.dashed ? CAIRO_LINE_CAP_BUTT : CAIRO_LINE_CAP_ROUND);
    if (l.dashed) {
      const double d[2] = {4.0 * l.width_px * s + 2, 2.5 * l.width_px * s + 2};
      cairo_set_dash(cr, d, 2, 0);
    }
    bool pen = false;
    for (std::size_t j = 0; j < l.x.size(); ++j) {
      if (!std::isfinite(l.x[j]) || !std::isfinite(l.z[j])) {
        pen = false;
        continue;
      }
      if (pen)
        cairo_line_to(cr, X(l.x[j]), Z(l.z[j]));
      else
        cairo_move_to(cr, X(l.x[j]), Z(l.z[j]));
      pen = true;
    }
    if (l.dashed) {
      // A light halo under dashes keeps them visible on dark particles.
      cairo_save(cr);
      cairo_set_dash(cr, nullptr, 0, 0);
      cairo_set_source_rgba(cr, 1, 1, 1, 0.55);
      cairo_set_line_width(cr, l.width_px * s + 2.0 * s);
      cairo_stroke_preserve(cr);
      cairo_restore(cr);
    }
    set_colour(cr, l.colour);
    cairo_stroke(cr);
    cairo_restore(cr);
  };
  for (const auto& l : in.extra_lines) stroke_line(l);
  stroke_line(in.outline);
  cairo_restore(cr); // clip

  // Frame, ticks and labels in mm.
  cairo_set_source_rgb(cr, 0.25, 0.25, 0.25);
  cairo_set_line_width(cr, 1.0);
  const double fx0 = crisp(pa_x0), fy0 = crisp(pa_y0);
  const double fx1 = crisp(pa_x0 + plot_w), fy1 = crisp(pa_y0 + plot_h);
  cairo_rectangle(cr, fx0, fy0, fx1 - fx0, fy1 - fy0);
  cairo_stroke(cr);
  const double xmm0 = win.x_min * 1e3, xmm1 = win.x_max * 1e3;
  const double zmm0 = win.z_min * 1e3, zmm1 = win.z_max * 1e3;
  const int xt = std::max(2, static_cast<int>(plot_w / (110 * s)));
  const int zt = std::max(2, static_cast<int>(plot_h / (70 * s)));
  const double xstep = nice_step(xmm0, xmm1, xt), zstep = nice_step(zmm0, zmm1, zt);
  const auto xticks = nice_ticks(xmm0, xmm1, xt), zticks = nice_ticks(zmm0, zmm1, zt);
  for (double v : xticks) {
    const double px = crisp(X(v * 1e-3));
    cairo_move_to(cr, px, fy1);
    cairo_line_to(cr, px, fy1 + tick_len);
  }
  for (double v : zticks) {
    const double py = crisp(Z(v * 1e-3));
    cairo_move_to(cr, fx0, py);
    cairo_line_to(cr, fx0 - tick_len, py);
  }
  cairo_stroke(cr);
  set_font(cr, f_tick);
  const double tick_cap = cap_height(cr);
  cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
  for (double v : xticks)
    draw_text(cr, format_tick(v, xstep), X(v * 1e-3), fy1 + tick_len + 5 * s + tick_cap, 0.5,
              false);
  for (double v : zticks)
    draw_text(cr, format_tick(v, zstep), fx0 - tick_len - 4 * s, Z(v * 1e-3), 1.0, true);
  set_font(cr, f_label);
  const double label_cap = cap_height(cr);
  draw_text(cr, "x (mm)", pa_x0 + 0.5 * plot_w,
            fy1 + tick_len + 5 * s + tick_cap + 10 * s + label_cap, 0.5, false);
  {
    cairo_save(cr);
    cairo_translate(cr, 14 * s + label_cap, pa_y0 + 0.5 * plot_h);
    cairo_rotate(cr, -M_PI / 2);
    draw_text(cr, "z (mm)", 0, 0, 0.5, false);
    cairo_restore(cr);
  }

  // Title.
  if (!in.title.empty()) {
    // Shrunk to fit when long; centred on the plot area while it fits there.
    double size = f_title;
    set_font(cr, size, true);
    while (text_width(cr, in.title) > Wi - 16 && size > 9) set_font(cr, size *= 0.92, true);
    const double tw = text_width(cr, in.title);
    const double lo = 8 + 0.5 * tw, hi = Wi - 8 - 0.5 * tw;
    const double cx = lo <= hi ? std::clamp(pa_x0 + 0.5 * plot_w, lo, hi) : 0.5 * Wi;
    cairo_set_source_rgb(cr, 0.05, 0.05, 0.05);
    draw_text(cr, in.title, cx, 1.45 * f_title, 0.5, false);
  }

  // Key of the lines, right-aligned above the plot.
  if (any_key) {
    set_font(cr, f_tick);
    std::vector<const SideViewPolyline*> keyed;
    if (!in.outline.label.empty() && !in.outline.x.empty()) keyed.push_back(&in.outline);
    for (const auto& l : in.extra_lines)
      if (!l.label.empty() && !l.x.empty()) keyed.push_back(&l);
    const double sample = 30 * s, gap = 8 * s, between = 22 * s;
    double total = 0;
    for (const auto* l : keyed) total += sample + gap + text_width(cr, l->label) + between;
    total -= between;
    double x = std::max(pa_x0, pa_x0 + plot_w - total);
    const double y = pa_y0 - 0.9 * f_tick;
    for (const auto* l : keyed) {
      cairo_save(cr);
      cairo_set_line_width(cr, l->width_px * s);
      if (l->dashed) {
        const double d[2] = {4.0 * l->width_px * s + 2, 2.5 * l->width_px * s + 2};
        cairo_set_dash(cr, d, 2, 0);
      }
      set_colour(cr, l->colour);
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + sample, y);
      cairo_stroke(cr);
      cairo_restore(cr);
      cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
      draw_text(cr, l->label, x + sample + gap, y, 0.0, true);
      x += sample + gap + text_width(cr, l->label) + between;
    }
  }

  // Colour bar: vertical, right of the plot, with a triangle below for
  // values under the scale (grey-blue) and one above for values over it.
  {
    const double bar_w = 20 * s;
    const double avail = std::max(plot_h, bar_min);
    const double bar_h = std::min(avail - 2 * 18 * s, std::max(150 * s, 0.8 * plot_h));
    const double bx = pa_x0 + plot_w + 26 * s;
    const double by = top + 0.5 * (avail - bar_h); // top of the bar
    const int steps = std::max(2, static_cast<int>(bar_h));
    for (int j = 0; j < steps; ++j) {
      const double f0 = static_cast<double>(j) / steps, f1 = static_cast<double>(j + 1) / steps;
      set_colour(cr, colour_map(in.colour_map, 0.5 * (f0 + f1)));
      const double y0 = by + bar_h * (1 - f1), y1 = by + bar_h * (1 - f0);
      cairo_rectangle(cr, bx, std::floor(y0), bar_w, std::ceil(y1) - std::floor(y0));
      cairo_fill(cr);
    }
    const double tri = 0.9 * bar_w;
    cairo_move_to(cr, bx, by);
    cairo_line_to(cr, bx + bar_w, by);
    cairo_line_to(cr, bx + 0.5 * bar_w, by - tri);
    cairo_close_path(cr);
    set_colour(cr, colour_map(in.colour_map, 1.0));
    cairo_fill(cr);
    cairo_move_to(cr, bx, by + bar_h);
    cairo_line_to(cr, bx + bar_w, by + bar_h);
    cairo_line_to(cr, bx + 0.5 * bar_w, by + bar_h + tri);
    cairo_close_path(cr);
    set_colour(cr, below_scale_colour);
    cairo_fill(cr);
    // Outline of bar and triangles.
    cairo_move_to(cr, bx, by);
    cairo_line_to(cr, bx + 0.5 * bar_w, by - tri);
    cairo_line_to(cr, bx + bar_w, by);
    cairo_line_to(cr, bx + bar_w, by + bar_h);
    cairo_line_to(cr, bx + 0.5 * bar_w, by + bar_h + tri);
    cairo_line_to(cr, bx, by + bar_h);
    cairo_close_path(cr);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);

    set_font(cr, f_tick);
    const auto ticks = colour_bar_ticks(in, bar_h, 1.6 * f_tick);
    double label_w = 0;
    for (double v : ticks) {
      const double f = std::clamp(scale_fraction(v, in.vmin, in.vmax, in.log_scale), 0.0, 1.0);
      const double y = crisp(by + bar_h * (1 - f));
      cairo_move_to(cr, bx + bar_w, y);
      cairo_line_to(cr, bx + bar_w + tick_len, y);
      cairo_set_source_rgb(cr, 0.25, 0.25, 0.25);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
      const std::string t = bar_label(in, v);
      draw_text(cr, t, bx + bar_w + tick_len + 4 * s, y, 0.0, true);
      label_w = std::max(label_w, text_width(cr, t));
    }
    set_font(cr, f_label);
    cairo_save(cr);
    cairo_translate(cr, bx + bar_w + tick_len + 4 * s + label_w + 12 * s + label_cap,
                    by + 0.5 * bar_h);
    cairo_rotate(cr, -M_PI / 2);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    draw_text(cr, in.value_label, 0, 0, 0.5, false);
    cairo_restore(cr);
  }

  cairo_surface_flush(surface.get());
  const cairo_status_t st = cairo_surface_write_to_png(surface.get(), png_path.c_str());
  if (st != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write PNG " + png_path + ": " + cairo_status_to_string(st));
  return lay;
}

} // namespace centridem
