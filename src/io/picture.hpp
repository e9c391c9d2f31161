// Side views of a particle model as PNG pictures (cairo, no other
// dependency), like the paper's Figs 12-13: spheres projected on the x-z
// plane, coloured by a scalar (displacement magnitude) on a log scale, a
// colour bar, the undeformed slope outline in red, optional extra lines (the
// detected slip surface), a title ("lower first bench — 40 g — t = 0.102 s")
// and axes in mm. Engine independent: it takes plain arrays, so a procedure
// calls it with whatever it has, once per frame.
//
//   SideViewInput in;
//   in.x = ...; in.y = ...; in.z = ...; in.radius = ...; in.value = disp;  // SI
//   in.outline = {{x0, x1, ...}, {z0, z1, ...}};
//   in.title = "lower first bench — 40 g — t = 0.102 s";
//   in.window = side_view_window(first_frame_input);  // same framing for a series
//   render_side_view(in, "frame_0007.png");
//
// Depth: the viewer looks along +y (x to the right, z up, y into the page),
// so particles are drawn from the largest y to the smallest and the nearest
// ones end on top. With `slice`, only |y - slice_y_mid| < slice_half_thickness
// are drawn.
#pragma once

#include "io/plot.hpp" // Rgb

#include <optional>
#include <string>
#include <vector>

namespace centridem {

enum class ColourMap { viridis, turbo };

// The colour map at t in [0, 1] (clamped), interpolated from a small table.
Rgb colour_map(ColourMap map, double t);

// The colour of `value` on the scale [vmin, vmax] (log10 when `log_scale`):
// below vmin (or non-finite) the neutral `below_colour`, above vmax the top
// of the map.
Rgb scale_colour(double value, double vmin, double vmax, bool log_scale, ColourMap map);

// Light grey-blue for values below the scale (particles that have not moved).
inline constexpr Rgb below_scale_colour{0.80, 0.84, 0.89};

// The outline of the undeformed slope surface, drawn in red.
inline constexpr Rgb outline_red{0.86, 0.08, 0.08};

struct SideViewPolyline {
  std::vector<double> x, z; // m
  Rgb colour{0.05, 0.05, 0.05};
  double width_px = 2.0;
  bool dashed = true;
  std::string label; // shown in a small key when not empty
};

// The model region a picture shows, m.
struct SideViewWindow {
  double x_min = 0, x_max = 1, z_min = 0, z_max = 1;
};

struct SideViewInput {
  // Particles (same length; y may be empty when not slicing: then drawn in
  // the given order).
  std::vector<double> x, y, z, radius; // m
  std::vector<double> value;           // per particle, e.g. |displacement| (m)

  // Colour scale.
  double vmin = 1.2e-4, vmax = 5e-3;
  bool log_scale = true;
  ColourMap colour_map = ColourMap::viridis;
  std::string value_label = "displacement (mm)"; // colour bar caption, in the shown unit
  // The colour bar's labels show value x this (1e3: values in m shown in mm,
  // as the axes; vmin, vmax and the values stay SI).
  double value_display_factor = 1e3;

  // Optional slice through the breadth.
  bool slice = false;
  double slice_y_mid = 0, slice_half_thickness = 0;

  // Lines on top of the particles.
  SideViewPolyline outline{{}, {}, outline_red, 2.0, false, "undeformed surface"};
  std::vector<SideViewPolyline> extra_lines; // e.g. the slip surface (dashed by default)

  std::string title;                    // one line above the picture
  int width_px = 1200;                  // picture width; the height follows the data
  std::optional<SideViewWindow> window; // empty: bounding box of particles and outline
};

// The region render_side_view() shows by default: the particles' bounding box
// (radii included) and the outline, with a 3 % margin. Compute it once from a
// series' first frame and set SideViewInput::window to frame all alike.
SideViewWindow side_view_window(const SideViewInput& in);

// Where things land in the picture: its size, the plot area (pixels, origin
// at the top left) and the model-to-pixel map (equal scales on x and z).
struct SideViewLayout {
  int width_px = 0, height_px = 0;
  double plot_x0 = 0, plot_y0 = 0, plot_width = 0, plot_height = 0; // px
  double px_per_m = 1;
  SideViewWindow window;
  double px_x(double x) const { return plot_x0 + (x - window.x_min) * px_per_m; }
  double px_y(double z) const { return plot_y0 + plot_height - (z - window.z_min) * px_per_m; }
};

// The layout render_side_view() will use for `in`, without drawing.
SideViewLayout side_view_layout(const SideViewInput& in);

// Draws the picture and writes it to png_path; returns its layout. Throws
// std::invalid_argument on arrays of mismatched lengths or an empty window,
// std::runtime_error when the file cannot be written.
SideViewLayout render_side_view(const SideViewInput& in, const std::string& png_path);

} // namespace centridem
