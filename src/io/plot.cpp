#include "io/plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

namespace centridem {

Rgb palette_colour(std::size_t index) {
  // Tableau 10.
  static constexpr std::array<Rgb, 10> tab10{{
      {0x1f / 255.0, 0x77 / 255.0, 0xb4 / 255.0}, // blue
      {0xff / 255.0, 0x7f / 255.0, 0x0e / 255.0}, // orange
      {0x2c / 255.0, 0xa0 / 255.0, 0x2c / 255.0}, // green
      {0xd6 / 255.0, 0x27 / 255.0, 0x28 / 255.0}, // red
      {0x94 / 255.0, 0x67 / 255.0, 0xbd / 255.0}, // purple
      {0x8c / 255.0, 0x56 / 255.0, 0x4b / 255.0}, // brown
      {0xe3 / 255.0, 0x77 / 255.0, 0xc2 / 255.0}, // pink
      {0x7f / 255.0, 0x7f / 255.0, 0x7f / 255.0}, // grey
      {0xbc / 255.0, 0xbd / 255.0, 0x22 / 255.0}, // olive
      {0x17 / 255.0, 0xbe / 255.0, 0xcf / 255.0}, // cyan
  }};
  return tab10[index % tab10.size()];
}

Series& LinePlot::add(std::string name, std::vector<double> x, std::vector<double> y) {
  Series s;
  s.name = std::move(name);
  s.x = std::move(x);
  s.y = std::move(y);
  series.push_back(std::move(s));
  return series.back();
}

// ---------------------------------------------------------------- ticks

double nice_step(double lo, double hi, int target) {
  const double range = std::abs(hi - lo);
  if (!(range > 0) || !std::isfinite(range)) return 1.0;
  const double raw = range / std::max(target, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / mag;
  const double f = norm < 1.5 ? 1 : norm < 3.0 ? 2 : norm < 7.0 ? 5 : 10;
  return f * mag;
}

namespace {

std::vector<double> ticks_with_step(double lo, double hi, double step) {
  std::vector<double> t;
  if (!(step > 0) || !(hi >= lo)) return t;
  const double eps = 1e-9 * step;
  const double first = std::ceil((lo - eps) / step);
  const double last = std::floor((hi + eps) / step);
  for (double k = first; k <= last && t.size() < 1000; k += 1) {
    double v = k * step;
    if (std::abs(v) < 1e-12 * step) v = 0; // no "-0"
    t.push_back(v);
  }
  return t;
}

} // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (hi < lo) std::swap(lo, hi);
  return ticks_with_step(lo, hi, nice_step(lo, hi, target));
}

std::string format_tick(double value, double step) {
  if (!std::isfinite(value)) return "";
  step = std::abs(step);
  if (step > 0 && std::abs(value) < 1e-9 * step) return "0";
  const double mag = std::max(std::abs(value), step);
  char buf[64];
  if (mag >= 1e6 || (step > 0 && step < 1e-4) || (step == 0 && mag < 1e-4)) {
    // Scientific with as many mantissa digits as the step needs.
    const int e = static_cast<int>(std::floor(std::log10(std::abs(value))));
    const double m = value / std::pow(10.0, e);
    int digits = 0;
    if (step > 0) {
      const double rel = step / std::pow(10.0, e);
      digits = std::clamp(static_cast<int>(std::ceil(-std::log10(rel) - 1e-9)), 0, 6);
    }
    std::snprintf(buf, sizeof buf, "%.*fe%d", digits, m, e);
    // "2.0e-4" -> "2e-4"
    std::string s(buf);
    const auto epos = s.find('e');
    if (s.find('.') != std::string::npos && epos != std::string::npos) {
      std::size_t k = epos;
      while (k > 0 && s[k - 1] == '0') --k;
      if (k > 0 && s[k - 1] == '.') --k;
      s.erase(k, epos - k);
    }
    return s;
  }
  int decimals = 0;
  if (step > 0 && step < 1)
    decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 8);
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  std::string s(buf);
  if (s == "-0" || s.find_first_not_of("-0.") == std::string::npos) return "0";
  return s;
}

std::string format_log_tick(double value) {
  if (!(value > 0) || !std::isfinite(value)) return "";
  const int e = static_cast<int>(std::floor(std::log10(value) + 1e-9));
  double m = value / std::pow(10.0, e);
  char buf[32];
  if (e >= -1 && e <= 3) {
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
  }
  // mantissa with up to two significant digits: 1, 1.2, 5
  m = std::round(m * 10.0) / 10.0;
  if (std::abs(m - std::round(m)) < 1e-9)
    std::snprintf(buf, sizeof buf, "%de%d", static_cast<int>(std::round(m)), e);
  else
    std::snprintf(buf, sizeof buf, "%.1fe%d", m, e);
  return buf;
}

// ---------------------------------------------------------------- drawing

namespace {

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using ContextPtr = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

void check_size(int width, int height, const char* what) {
  if (width < 16 || height < 16 || width > 30000 || height > 30000)
    throw std::invalid_argument(std::string(what) + ": picture size " + std::to_string(width) +
                                " x " + std::to_string(height) + " px is outside 16..30000");
}

void write_png(cairo_surface_t* surface, const std::string& path) {
  cairo_surface_flush(surface);
  const cairo_status_t st = cairo_surface_write_to_png(surface, path.c_str());
  if (st != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write PNG " + path + ": " + cairo_status_to_string(st));
}

void set_colour(cairo_t* cr, const Rgb& c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha);
}

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

// Height of digits and capitals above the baseline in the current font.
double cap_height(cairo_t* cr) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, "0", &e);
  return -e.y_bearing;
}

// Draws `s` with its anchor at (x, y): ax 0 left, 0.5 centre, 1 right; the
// vertical anchor is the middle of the capitals when vmid, else the baseline.
void draw_text(cairo_t* cr, const std::string& s, double x, double y, double ax, bool vmid) {
  if (s.empty()) return;
  const double w = text_width(cr, s);
  const double yb = vmid ? y + 0.5 * cap_height(cr) : y;
  cairo_move_to(cr, x - ax * w, yb);
  cairo_show_text(cr, s.c_str());
  cairo_new_path(cr);
}

struct Box {
  double x0, y0, w, h;
};

struct Axis {
  double lo = 0, hi = 1;
  bool log = false;
  std::vector<double> major; // labelled ticks
  std::vector<double> minor; // unlabelled (log axes)
  double step = 1;           // linear: the tick step (for the labels)
  // value -> fraction of the axis length
  double frac(double v) const {
    if (log) return (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo));
    return (v - lo) / (hi - lo);
  }
  std::string label(double v) const { return log ? format_log_tick(v) : format_tick(v, step); }
};

bool usable(double v, bool log) {
  return std::isfinite(v) && (!log || v > 0);
}

Axis make_linear_axis(double dlo, double dhi, bool have_data, bool pad,
                      const std::optional<AxisRange>& fixed) {
  Axis a;
  if (fixed) {
    a.lo = std::min(fixed->min, fixed->max);
    a.hi = std::max(fixed->min, fixed->max);
    if (!(a.hi > a.lo)) a.hi = a.lo + 1;
    a.step = nice_step(a.lo, a.hi);
    a.major = ticks_with_step(a.lo, a.hi, a.step);
    return a;
  }
  if (!have_data) {
    dlo = 0;
    dhi = 1;
  }
  if (!(dhi > dlo)) {
    const double d = dlo == 0 ? 1.0 : 0.1 * std::abs(dlo);
    dlo -= d;
    dhi += d;
  }
  if (pad) {
    const double d = 0.04 * (dhi - dlo);
    dlo -= d;
    dhi += d;
  }
  a.step = nice_step(dlo, dhi);
  a.lo = std::floor(dlo / a.step + 1e-9) * a.step;
  a.hi = std::ceil(dhi / a.step - 1e-9) * a.step;
  if (!(a.hi > a.lo)) a.hi = a.lo + a.step;
  a.major = ticks_with_step(a.lo, a.hi, a.step);
  return a;
}

Axis make_log_axis(double dlo, double dhi, bool have_data, const std::optional<AxisRange>& fixed) {
  Axis a;
  a.log = true;
  if (fixed && fixed->min > 0 && fixed->max > 0) {
    a.lo = std::min(fixed->min, fixed->max);
    a.hi = std::max(fixed->min, fixed->max);
    if (!(a.hi > a.lo)) a.hi = a.lo * 10;
  } else {
    if (!have_data) {
      dlo = 1;
      dhi = 10;
    }
    a.lo = std::pow(10.0, std::floor(std::log10(dlo) + 1e-9));
    a.hi = std::pow(10.0, std::ceil(std::log10(dhi) - 1e-9));
    if (!(a.hi > a.lo)) a.hi = a.lo * 10;
  }
  const int e0 = static_cast<int>(std::floor(std::log10(a.lo) + 1e-9));
  const int e1 = static_cast<int>(std::ceil(std::log10(a.hi) - 1e-9));
  const bool few = (std::log10(a.hi) - std::log10(a.lo)) <= 2.05;
  const double tol = 1e-9;
  for (int e = e0; e <= e1; ++e) {
    const double dec = std::pow(10.0, e);
    for (int m = 1; m <= 9; ++m) {
      const double v = m * dec;
      if (v < a.lo * (1 - tol) || v > a.hi * (1 + tol)) continue;
      if (m == 1 || (few && (m == 2 || m == 5)))
        a.major.push_back(v);
      else
        a.minor.push_back(v);
    }
  }
  return a;
}

std::vector<double> dash_pattern(double lw) {
  return {3.5 * lw + 2, 2.0 * lw + 2};
}

void draw_marker(cairo_t* cr, Marker m, double x, double y, double size, const Rgb& c) {
  const double r = 0.5 * size;
  cairo_new_path(cr);
  switch (m) {
  case Marker::none:
    return;
  case Marker::circle:
    cairo_arc(cr, x, y, r, 0, 2 * M_PI);
    break;
  case Marker::square:
    cairo_rectangle(cr, x - 0.85 * r, y - 0.85 * r, 1.7 * r, 1.7 * r);
    break;
  case Marker::triangle:
    cairo_move_to(cr, x, y - 1.1 * r);
    cairo_line_to(cr, x + 1.0 * r, y + 0.7 * r);
    cairo_line_to(cr, x - 1.0 * r, y + 0.7 * r);
    cairo_close_path(cr);
    break;
  case Marker::diamond:
    cairo_move_to(cr, x, y - 1.15 * r);
    cairo_line_to(cr, x + 0.85 * r, y);
    cairo_line_to(cr, x, y + 1.15 * r);
    cairo_line_to(cr, x - 0.85 * r, y);
    cairo_close_path(cr);
    break;
  case Marker::cross:
  case Marker::plus: {
    const double d = m == Marker::cross ? 0.8 * r : 1.05 * r;
    cairo_save(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_set_line_width(cr, std::max(1.5, 0.28 * size));
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    set_colour(cr, c);
    if (m == Marker::cross) {
      cairo_move_to(cr, x - d, y - d);
      cairo_line_to(cr, x + d, y + d);
      cairo_move_to(cr, x - d, y + d);
      cairo_line_to(cr, x + d, y - d);
    } else {
      cairo_move_to(cr, x - d, y);
      cairo_line_to(cr, x + d, y);
      cairo_move_to(cr, x, y - d);
      cairo_line_to(cr, x, y + d);
    }
    cairo_stroke(cr);
    cairo_restore(cr);
    return;
  }
  }
  // Filled shapes: the series colour with a thin darker edge.
  cairo_save(cr);
  cairo_set_dash(cr, nullptr, 0, 0);
  set_colour(cr, c);
  cairo_fill_preserve(cr);
  set_colour(cr, {0.55 * c.r, 0.55 * c.g, 0.55 * c.b});
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  cairo_restore(cr);
}

Rgb series_colour(const LinePlot& p, std::size_t i) {
  return p.series[i].colour ? *p.series[i].colour : palette_colour(i);
}

void draw_plot(cairo_t* cr, const LinePlot& p, const Box& box) {
  // Fonts scale with the panel so that small panels stay readable and large
  // ones are not spidery.
  const double s = std::clamp(std::min(box.w / 820.0, box.h / 540.0), 0.9, 2.5);
  const double f_title = 19 * s, f_label = 15.5 * s, f_tick = 13 * s, f_legend = 13 * s;
  const double tick_len = 5 * s, pad = 7 * s;

  cairo_save(cr);
  cairo_rectangle(cr, box.x0, box.y0, box.w, box.h);
  cairo_clip(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // Data extents.
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  bool have = false, any_markers = false;
  for (const auto& se : p.series) {
    const std::size_t n = std::min(se.x.size(), se.y.size());
    // Point charts get a margin so that no marker sits on the frame.
    if (!se.line && n > 0) any_markers = true;
    for (std::size_t k = 0; k < n; ++k) {
      if (!usable(se.x[k], p.log_x) || !std::isfinite(se.y[k])) continue;
      xlo = std::min(xlo, se.x[k]);
      xhi = std::max(xhi, se.x[k]);
      ylo = std::min(ylo, se.y[k]);
      yhi = std::max(yhi, se.y[k]);
      have = true;
    }
  }
  const Axis ax = p.log_x ? make_log_axis(xlo, xhi, have, p.x_range)
                          : make_linear_axis(xlo, xhi, have, any_markers, p.x_range);
  const Axis ay = make_linear_axis(ylo, yhi, have, any_markers, p.y_range);

  // Margins from the text that goes in them.
  set_font(cr, f_tick);
  const double tick_cap = cap_height(cr);
  double ytick_w = 0;
  for (double v : ay.major) ytick_w = std::max(ytick_w, text_width(cr, ay.label(v)));
  double xtick_last_w = ax.major.empty() ? 0 : text_width(cr, ax.label(ax.major.back()));
  set_font(cr, f_label);
  const double label_cap = cap_height(cr);
  const double top = p.title.empty() ? 18 * s : f_title * 2.1;
  const double left =
      pad * 2 + (p.y_label.empty() ? 0 : label_cap + pad * 1.6) + ytick_w + tick_len + 4 * s;
  const double bottom =
      tick_len + pad + tick_cap + (p.x_label.empty() ? pad : pad * 2.2 + label_cap + pad);
  const double right = std::max(20 * s, 0.5 * xtick_last_w + 8 * s);
  const Box pa{box.x0 + left, box.y0 + top, box.w - left - right, box.h - top - bottom};
  if (pa.w < 10 || pa.h < 10) {
    cairo_restore(cr);
    return;
  }

  auto px = [&](double v) { return pa.x0 + ax.frac(v) * pa.w; };
  auto py = [&](double v) { return pa.y0 + pa.h - ay.frac(v) * pa.h; };
  // Crisp one-pixel lines sit on half pixels.
  auto crisp = [](double v) { return std::floor(v) + 0.5; };

  // Grid.
  cairo_set_line_width(cr, 1.0);
  if (p.grid) {
    cairo_set_source_rgb(cr, 0.93, 0.93, 0.93);
    for (double v : ax.minor) {
      const double X = crisp(px(v));
      cairo_move_to(cr, X, pa.y0);
      cairo_line_to(cr, X, pa.y0 + pa.h);
    }
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.86, 0.86, 0.86);
    for (double v : ax.major) {
      const double X = crisp(px(v));
      cairo_move_to(cr, X, pa.y0);
      cairo_line_to(cr, X, pa.y0 + pa.h);
    }
    for (double v : ay.major) {
      const double Y = crisp(py(v));
      cairo_move_to(cr, pa.x0, Y);
      cairo_line_to(cr, pa.x0 + pa.w, Y);
    }
    cairo_stroke(cr);
  }

  // Series: lines clipped to the plot area, markers a little beyond it.
  for (std::size_t i = 0; i < p.series.size(); ++i) {
    const Series& se = p.series[i];
    const Rgb c = series_colour(p, i);
    const std::size_t n = std::min(se.x.size(), se.y.size());
    if (se.line && n > 1) {
      cairo_save(cr);
      cairo_rectangle(cr, pa.x0, pa.y0, pa.w, pa.h);
      cairo_clip(cr);
      set_colour(cr, c);
      cairo_set_line_width(cr, se.line_width_px * s);
      cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
      cairo_set_line_cap(cr, se.dashed ? CAIRO_LINE_CAP_BUTT : CAIRO_LINE_CAP_ROUND);
      if (se.dashed) {
        const auto d = dash_pattern(se.line_width_px * s);
        cairo_set_dash(cr, d.data(), static_cast<int>(d.size()), 0);
      }
      bool pen_down = false;
      for (std::size_t k = 0; k < n; ++k) {
        if (!usable(se.x[k], p.log_x) || !std::isfinite(se.y[k])) {
          pen_down = false;
          continue;
        }
        const double X = px(se.x[k]), Y = py(se.y[k]);
        if (pen_down)
          cairo_line_to(cr, X, Y);
        else
          cairo_move_to(cr, X, Y);
        pen_down = true;
      }
      cairo_stroke(cr);
      cairo_restore(cr);
    }
    const bool markers = se.marker != Marker::none || !se.line;
    if (markers) {
      const Marker m = se.marker == Marker::none ? Marker::circle : se.marker;
      const double ms = se.marker_size_px * s;
      cairo_save(cr);
      cairo_rectangle(cr, pa.x0 - ms, pa.y0 - ms, pa.w + 2 * ms, pa.h + 2 * ms);
      cairo_clip(cr);
      for (std::size_t k = 0; k < n; ++k) {
        if (!usable(se.x[k], p.log_x) || !std::isfinite(se.y[k])) continue;
        draw_marker(cr, m, px(se.x[k]), py(se.y[k]), ms, c);
      }
      cairo_restore(cr);
    }
  }

  // Frame and ticks.
  cairo_set_dash(cr, nullptr, 0, 0);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_set_line_width(cr, 1.0);
  const double fx0 = crisp(pa.x0), fy0 = crisp(pa.y0);
  const double fx1 = crisp(pa.x0 + pa.w), fy1 = crisp(pa.y0 + pa.h);
  cairo_rectangle(cr, fx0, fy0, fx1 - fx0, fy1 - fy0);
  cairo_stroke(cr);
  for (double v : ax.major) {
    const double X = crisp(px(v));
    cairo_move_to(cr, X, fy1);
    cairo_line_to(cr, X, fy1 + tick_len);
  }
  for (double v : ax.minor) {
    const double X = crisp(px(v));
    cairo_move_to(cr, X, fy1);
    cairo_line_to(cr, X, fy1 + 0.6 * tick_len);
  }
  for (double v : ay.major) {
    const double Y = crisp(py(v));
    cairo_move_to(cr, fx0, Y);
    cairo_line_to(cr, fx0 - tick_len, Y);
  }
  cairo_stroke(cr);

  // Tick labels.
  cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
  set_font(cr, f_tick);
  for (double v : ax.major)
    draw_text(cr, ax.label(v), px(v), fy1 + tick_len + pad * 0.6 + tick_cap, 0.5, false);
  for (double v : ay.major) draw_text(cr, ay.label(v), fx0 - tick_len - 4 * s, py(v), 1.0, true);

  // Axis labels and title.
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  set_font(cr, f_label);
  if (!p.x_label.empty())
    draw_text(cr, p.x_label, pa.x0 + 0.5 * pa.w,
              fy1 + tick_len + pad * 0.6 + tick_cap + pad * 1.6 + label_cap, 0.5, false);
  if (!p.y_label.empty()) {
    cairo_save(cr);
    cairo_translate(cr, box.x0 + pad * 1.6 + label_cap, pa.y0 + 0.5 * pa.h);
    cairo_rotate(cr, -M_PI / 2);
    draw_text(cr, p.y_label, 0, 0, 0.5, false);
    cairo_restore(cr);
  }
  if (!p.title.empty()) {
    // Shrunk to fit when long; centred on the plot area while it fits there.
    double size = f_title;
    set_font(cr, size, true);
    while (text_width(cr, p.title) > box.w - 16 && size > 9) set_font(cr, size *= 0.92, true);
    const double tw = text_width(cr, p.title);
    const double lo = box.x0 + 8 + 0.5 * tw, hi = box.x0 + box.w - 8 - 0.5 * tw;
    const double cx = lo <= hi ? std::clamp(pa.x0 + 0.5 * pa.w, lo, hi) : box.x0 + 0.5 * box.w;
    draw_text(cr, p.title, cx, box.y0 + top * 0.62, 0.5, false);
  }

  // Legend.
  std::vector<std::size_t> entries;
  for (std::size_t i = 0; i < p.series.size(); ++i)
    if (!p.series[i].name.empty()) entries.push_back(i);
  if (p.legend != LegendPlace::none && !entries.empty()) {
    set_font(cr, f_legend);
    const double row = f_legend * 1.45, sample = 30 * s, inner = 8 * s;
    double tw = 0;
    for (auto i : entries) tw = std::max(tw, text_width(cr, p.series[i].name));
    const double lw = inner * 2 + sample + 8 * s + tw;
    const double lh = inner * 2 + row * static_cast<double>(entries.size()) - (row - f_legend);
    const double m = 10 * s;
    const std::array<std::pair<LegendPlace, std::array<double, 2>>, 4> corners{{
        {LegendPlace::upper_right, {pa.x0 + pa.w - m - lw, pa.y0 + m}},
        {LegendPlace::upper_left, {pa.x0 + m, pa.y0 + m}},
        {LegendPlace::lower_right, {pa.x0 + pa.w - m - lw, pa.y0 + pa.h - m - lh}},
        {LegendPlace::lower_left, {pa.x0 + m, pa.y0 + pa.h - m - lh}},
    }};
    std::array<double, 2> at = corners[0].second;
    if (p.legend == LegendPlace::best) {
      // The corner whose box covers the fewest data points (lines sampled
      // along their segments too).
      std::size_t best_hits = std::numeric_limits<std::size_t>::max();
      for (const auto& [place, xy] : corners) {
        std::size_t hits = 0;
        auto inside = [&](double X, double Y) {
          return X >= xy[0] - 4 && X <= xy[0] + lw + 4 && Y >= xy[1] - 4 && Y <= xy[1] + lh + 4;
        };
        for (const auto& se : p.series) {
          const std::size_t n = std::min(se.x.size(), se.y.size());
          double pX = NAN, pY = NAN;
          for (std::size_t k = 0; k < n; ++k) {
            if (!usable(se.x[k], p.log_x) || !std::isfinite(se.y[k])) {
              pX = NAN;
              continue;
            }
            const double X = px(se.x[k]), Y = py(se.y[k]);
            if (se.line && std::isfinite(pX)) {
              const double len = std::hypot(X - pX, Y - pY);
              const int steps = std::min(200, static_cast<int>(len / 4.0));
              for (int j = 1; j < steps; ++j) {
                const double t = static_cast<double>(j) / steps;
                hits += inside(pX + t * (X - pX), pY + t * (Y - pY));
              }
            }
            hits += inside(X, Y) ? 3 : 0;
            pX = X;
            pY = Y;
          }
        }
        if (hits < best_hits) {
          best_hits = hits;
          at = xy;
        }
      }
    } else {
      for (const auto& [place, xy] : corners)
        if (place == p.legend) at = xy;
    }
    cairo_rectangle(cr, crisp(at[0]), crisp(at[1]), std::round(lw), std::round(lh));
    cairo_set_source_rgba(cr, 1, 1, 1, 0.88);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0.75, 0.75, 0.75);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
    double yrow = at[1] + inner + 0.5 * f_legend;
    for (auto i : entries) {
      const Series& se = p.series[i];
      const Rgb c = series_colour(p, i);
      const double x0 = at[0] + inner;
      if (se.line) {
        cairo_save(cr);
        set_colour(cr, c);
        cairo_set_line_width(cr, se.line_width_px * s);
        if (se.dashed) {
          const auto d = dash_pattern(se.line_width_px * s);
          cairo_set_dash(cr, d.data(), static_cast<int>(d.size()), 0);
        }
        cairo_move_to(cr, x0, yrow);
        cairo_line_to(cr, x0 + sample, yrow);
        cairo_stroke(cr);
        cairo_restore(cr);
      }
      if (se.marker != Marker::none || !se.line)
        draw_marker(cr, se.marker == Marker::none ? Marker::circle : se.marker, x0 + 0.5 * sample,
                    yrow, se.marker_size_px * s, c);
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      draw_text(cr, se.name, x0 + sample + 8 * s, yrow, 0.0, true);
      yrow += row;
    }
  }
  cairo_restore(cr);
}

} // namespace

void LinePlot::render(const std::string& png_path, int width, int height) const {
  check_size(width, height, "LinePlot::render");
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height),
                     &cairo_surface_destroy);
  ContextPtr cr(cairo_create(surface.get()), &cairo_destroy);
  cairo_set_antialias(cr.get(), CAIRO_ANTIALIAS_BEST);
  draw_plot(cr.get(), *this, {0, 0, static_cast<double>(width), static_cast<double>(height)});
  write_png(surface.get(), png_path);
}

void render_panels(const std::string& png_path, const std::vector<LinePlot>& plots, int columns,
                   int panel_width, int panel_height) {
  if (plots.empty()) throw std::invalid_argument("render_panels: no plots to draw");
  const int n = static_cast<int>(plots.size());
  columns = std::clamp(columns, 1, n);
  const int rows = (n + columns - 1) / columns;
  check_size(panel_width, panel_height, "render_panels");
  check_size(columns * panel_width, rows * panel_height, "render_panels");
  SurfacePtr surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, columns * panel_width, rows * panel_height),
      &cairo_surface_destroy);
  ContextPtr cr(cairo_create(surface.get()), &cairo_destroy);
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  for (int i = 0; i < n; ++i) {
    const double x0 = (i % columns) * panel_width, y0 = (i / columns) * panel_height;
    draw_plot(cr.get(), plots[static_cast<std::size_t>(i)],
              {x0, y0, static_cast<double>(panel_width), static_cast<double>(panel_height)});
  }
  write_png(surface.get(), png_path);
}

} // namespace centridem
