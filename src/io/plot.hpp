// Line plots for result figures, written as PNG with cairo (no other
// dependency): shear stress vs shear strain per normal pressure, dilation vs
// strain, a g-level campaign (markers only), calibration misfit, ...
//
//   LinePlot p;
//   p.title = "Humid sand, direct shear";
//   p.x_label = "shear strain (%)";
//   p.y_label = "shear stress (kPa)";
//   p.add("NDST 40 kPa", strain, tau);                  // colour from the palette
//   p.add("EDST 40 kPa", strain_e, tau_e).dashed_line();
//   p.render("shear.png", 900, 600);
//   render_panels("shear_and_dilation.png", {p, q}, 2); // side by side
//
// Ticks follow the 1-2-5 rule; automatic ranges are widened to whole ticks.
// Text is drawn with cairo's toy text API in the system sans-serif font
// (UTF-8: "τ (kPa)", "σn = 40 kPa" are fine).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace centridem {

// A colour with components in [0, 1].
struct Rgb {
  double r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

// Qualitative palette (Tableau 10, matplotlib's default cycle); wraps around.
Rgb palette_colour(std::size_t index);

enum class Marker { none, circle, square, triangle, diamond, cross, plus };

struct Series {
  std::string name;          // legend entry; empty: not in the legend
  std::vector<double> x, y;  // same length; non-finite points break the line
  std::optional<Rgb> colour; // empty: palette_colour(index of the series)
  bool line = true;          // false: markers only (a point chart)
  bool dashed = false;
  Marker marker = Marker::none;
  double line_width_px = 2.0;
  double marker_size_px = 9.0; // marker diameter

  // Chainable setters for the common cases.
  Series& dashed_line() {
    dashed = true;
    return *this;
  }
  Series& markers(Marker m = Marker::circle) {
    marker = m;
    return *this;
  }
  Series& markers_only(Marker m = Marker::circle) {
    marker = m;
    line = false;
    return *this;
  }
  Series& with_colour(Rgb c) {
    colour = c;
    return *this;
  }
};

enum class LegendPlace { best, upper_left, upper_right, lower_left, lower_right, none };

struct AxisRange {
  double min = 0, max = 1;
};

struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  bool log_x = false;               // base-10 x axis; points with x <= 0 are skipped
  bool grid = true;                 // light grid lines at the major ticks
  std::optional<AxisRange> x_range; // empty: from the data, widened to whole ticks
  std::optional<AxisRange> y_range;
  LegendPlace legend = LegendPlace::best; // best: the corner hiding the fewest points

  // Appends a series and returns it for chaining; the reference is valid
  // until the next add().
  Series& add(std::string name, std::vector<double> x, std::vector<double> y);

  // Writes a PNG of width x height pixels. Throws std::runtime_error when the
  // file cannot be written.
  void render(const std::string& png_path, int width = 900, int height = 600) const;
};

// Several plots in one picture, row by row, `columns` per row, each panel
// panel_width x panel_height pixels.
void render_panels(const std::string& png_path, const std::vector<LinePlot>& plots, int columns = 2,
                   int panel_width = 700, int panel_height = 500);

// Shared helpers (also used by the side view in picture.hpp).
// The multiples of a 1-2-5 step (1, 2 or 5 times a power of ten) that lie in
// [lo, hi], about `target` of them.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);
// The 1-2-5 step nice_ticks() uses for [lo, hi].
double nice_step(double lo, double hi, int target = 6);
// A tick label for `value` on an axis whose ticks are `step` apart: as few
// decimals as the step needs, scientific ("2e-4", "1.5e6") for very small or
// very large magnitudes, "0" for round-off zeros.
std::string format_tick(double value, double step);
// A compact label for a value on a log axis: "1e-3", "5e-3", "1.2e-4", "1", "20".
std::string format_log_tick(double value);

} // namespace centridem
