// Line plots: 1-2-5 ticks and their labels, PNG size, series colours from the
// palette, markers-only series without connecting lines, panels.
#include "io/plot.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

using namespace centridem;

namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path d = fs::temp_directory_path() /
               (std::string("centridem_plot_") + info->name() + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

struct Image {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface{
      nullptr, &cairo_surface_destroy};
  int width = 0, height = 0;
  explicit Image(const fs::path& path) {
    surface.reset(cairo_image_surface_create_from_png(path.c_str()));
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) return;
    cairo_surface_flush(surface.get());
    width = cairo_image_surface_get_width(surface.get());
    height = cairo_image_surface_get_height(surface.get());
  }
  bool ok() const { return width > 0; }
  std::array<int, 3> at(int x, int y) const {
    const unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    const auto v = *reinterpret_cast<const std::uint32_t*>(data + y * stride + 4 * x);
    return {static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff),
            static_cast<int>(v & 0xff)};
  }
};

bool close_to(const std::array<int, 3>& c, const Rgb& want, int tol = 3) {
  return std::abs(c[0] - static_cast<int>(std::lround(255 * want.r))) <= tol &&
         std::abs(c[1] - static_cast<int>(std::lround(255 * want.g))) <= tol &&
         std::abs(c[2] - static_cast<int>(std::lround(255 * want.b))) <= tol;
}

// Pixels of (about) colour c, and the longest horizontal run of them.
struct ColourCount {
  int pixels = 0, longest_run = 0;
};
ColourCount count_colour(const Image& img, const Rgb& c, int x0 = 0, int y0 = 0, int x1 = -1,
                         int y1 = -1) {
  if (x1 < 0) x1 = img.width;
  if (y1 < 0) y1 = img.height;
  ColourCount out;
  for (int y = y0; y < y1; ++y) {
    int run = 0;
    for (int x = x0; x < x1; ++x) {
      if (close_to(img.at(x, y), c)) {
        ++out.pixels;
        out.longest_run = std::max(out.longest_run, ++run);
      } else {
        run = 0;
      }
    }
  }
  return out;
}

std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(a + (b - a) * i / (n - 1));
  return v;
}

} // namespace

TEST(PlotTicks, OneTwoFiveSteps) {
  EXPECT_DOUBLE_EQ(nice_step(0, 1), 0.2);
  EXPECT_DOUBLE_EQ(nice_step(0, 120), 20);
  EXPECT_DOUBLE_EQ(nice_step(0, 15), 2);
  EXPECT_DOUBLE_EQ(nice_step(0, 0.006), 0.001);
  EXPECT_DOUBLE_EQ(nice_step(30, 90), 10);
  const auto t = nice_ticks(0, 120);
  ASSERT_EQ(t.size(), 7u);
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(t[i], 20.0 * i, 1e-9);
  // Only ticks inside the range, a zero that prints as zero.
  const auto u = nice_ticks(-0.3, 0.7);
  ASSERT_FALSE(u.empty());
  EXPECT_GE(u.front(), -0.3);
  EXPECT_LE(u.back(), 0.7);
  bool has_zero = false;
  for (double v : u) has_zero |= v == 0.0;
  EXPECT_TRUE(has_zero);
  EXPECT_TRUE(nice_ticks(1, 1).size() <= 1);
}

TEST(PlotTicks, Labels) {
  EXPECT_EQ(format_tick(0.30000000000000004, 0.1), "0.3");
  EXPECT_EQ(format_tick(-1e-17, 0.1), "0");
  EXPECT_EQ(format_tick(120, 20), "120");
  EXPECT_EQ(format_tick(0.25, 0.05), "0.25");
  EXPECT_EQ(format_tick(2e-4, 1e-4 / 2), "2e-4");
  EXPECT_EQ(format_tick(2.5e-5, 5e-6), "2.5e-5");
  EXPECT_EQ(format_tick(1.5e6, 5e5), "1.5e6");
  EXPECT_EQ(format_log_tick(1.2e-4), "1.2e-4");
  EXPECT_EQ(format_log_tick(1e-3), "1e-3");
  EXPECT_EQ(format_log_tick(5e-3), "5e-3");
  EXPECT_EQ(format_log_tick(10), "10");
  EXPECT_EQ(format_log_tick(0.5), "0.5");
}

TEST(PlotPalette, DistinctAndWrapping) {
  for (std::size_t i = 0; i < 10; ++i)
    for (std::size_t j = i + 1; j < 10; ++j) EXPECT_FALSE(palette_colour(i) == palette_colour(j));
  EXPECT_EQ(palette_colour(0), palette_colour(10));
}

TEST(LinePlotRender, TwoSeriesSizeColoursAndBackground) {
  const fs::path dir = temp_dir();
  LinePlot p;
  p.title = "Direct shear, humid sand";
  p.x_label = "shear strain (%)";
  p.y_label = "shear stress τ (kPa)";
  const auto x = linspace(0, 15, 61);
  std::vector<double> y1, y2;
  for (double e : x) {
    y1.push_back(40 * (1 - std::exp(-e)) + 5 * std::exp(-std::pow(e - 3, 2)));
    y2.push_back(80 * (1 - std::exp(-e)) + 10 * std::exp(-std::pow(e - 3, 2)));
  }
  p.add("σn = 40 kPa", x, y1);
  p.add("σn = 80 kPa", x, y2).dashed_line();
  const fs::path png = dir / "plot.png";
  p.render(png.string(), 900, 600);
  ASSERT_TRUE(fs::exists(png));
  const Image img(png);
  ASSERT_TRUE(img.ok());
  EXPECT_EQ(img.width, 900);
  EXPECT_EQ(img.height, 600);
  // White corners.
  for (auto [cx, cy] : {std::pair{1, 1}, {898, 1}, {1, 598}, {898, 598}}) {
    const auto c = img.at(cx, cy);
    EXPECT_EQ(c, (std::array<int, 3>{255, 255, 255})) << cx << ", " << cy;
  }
  // Both series appear in their palette colours; the solid one has long
  // runs of its colour (the plateau), the dashed one only short ones.
  const ColourCount a = count_colour(img, palette_colour(0));
  const ColourCount b = count_colour(img, palette_colour(1));
  EXPECT_GT(a.pixels, 500);
  EXPECT_GT(b.pixels, 300);
  EXPECT_GT(a.longest_run, 100);
  EXPECT_LT(b.longest_run, 40);
  fs::copy_file(png, fs::temp_directory_path() / "centridem_test_plot.png",
                fs::copy_options::overwrite_existing);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// A g-level campaign: stable and failed trials as two markers-only series.
TEST(LinePlotRender, MarkersOnlySeriesDrawNoLines) {
  const fs::path dir = temp_dir();
  LinePlot p;
  p.title = "g-level campaign";
  p.x_label = "g-level";
  p.y_label = "outcome";
  p.legend = LegendPlace::none;
  p.add("stable", {20, 30, 40}, {0, 0, 0}).markers_only(Marker::circle);
  p.add("failed", {50, 60, 70}, {1, 1, 1}).markers_only(Marker::square);
  const fs::path png = dir / "campaign.png";
  p.render(png.string(), 800, 500);
  const Image img(png);
  ASSERT_TRUE(img.ok());
  const ColourCount a = count_colour(img, palette_colour(0));
  const ColourCount b = count_colour(img, palette_colour(1));
  // Three markers each, nothing joining them.
  EXPECT_GT(a.pixels, 3 * 15);
  EXPECT_GT(b.pixels, 3 * 15);
  EXPECT_LT(a.pixels, 3 * 200);
  EXPECT_LT(b.pixels, 3 * 200);
  EXPECT_LT(a.longest_run, 20);
  EXPECT_LT(b.longest_run, 20);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

TEST(LinePlotRender, PanelsTileThePicture) {
  const fs::path dir = temp_dir();
  LinePlot shear, dilation, extra;
  shear.title = "shear stress";
  shear.add("40 kPa", linspace(0, 10, 11), linspace(0, 30, 11));
  dilation.title = "dilation";
  dilation.add("40 kPa", linspace(0, 10, 11), linspace(-0.05, 0.3, 11));
  extra.title = "log x";
  extra.log_x = true;
  extra.add("with a zero that is skipped", {0, 1e-4, 1e-3, 5e-3}, {0, 0.2, 0.6, 1.0});
  const fs::path png = dir / "panels.png";
  render_panels(png.string(), {shear, dilation, extra}, 2, 600, 400);
  const Image img(png);
  ASSERT_TRUE(img.ok());
  EXPECT_EQ(img.width, 1200);
  EXPECT_EQ(img.height, 800);
  // The fourth cell is empty: white throughout a probe grid.
  for (int x = 610; x < 1200; x += 37)
    for (int y = 410; y < 800; y += 29)
      EXPECT_EQ(img.at(x, y), (std::array<int, 3>{255, 255, 255})) << x << ", " << y;
  // Each of the three panels has its series colour somewhere inside.
  EXPECT_GT(count_colour(img, palette_colour(0), 0, 0, 600, 400).pixels, 100);
  EXPECT_GT(count_colour(img, palette_colour(0), 600, 0, 1200, 400).pixels, 100);
  EXPECT_GT(count_colour(img, palette_colour(0), 0, 400, 600, 800).pixels, 100);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

TEST(LinePlotRender, DegenerateDataAndBadArguments) {
  const fs::path dir = temp_dir();
  LinePlot empty;
  EXPECT_NO_THROW(empty.render((dir / "empty.png").string(), 400, 300));
  LinePlot one;
  one.add("one point", {1}, {2}).markers(Marker::diamond);
  one.add("gaps", {0, 1, NAN, 3, 4}, {1, 2, 3, NAN, 5});
  one.add("flat", {0, 1}, {7, 7});
  EXPECT_NO_THROW(one.render((dir / "one.png").string(), 400, 300));
  LinePlot fixed;
  fixed.x_range = AxisRange{0, 10};
  fixed.y_range = AxisRange{-1, 1};
  fixed.add("out of range", {-5, 5, 15}, {0, 3, 0});
  EXPECT_NO_THROW(fixed.render((dir / "fixed.png").string(), 400, 300));
  EXPECT_THROW(one.render((dir / "no_such_folder" / "x.png").string(), 400, 300),
               std::runtime_error);
  EXPECT_THROW(one.render((dir / "tiny.png").string(), 0, 300), std::invalid_argument);
  EXPECT_THROW(render_panels((dir / "none.png").string(), {}, 2), std::invalid_argument);
  std::error_code ec;
  fs::remove_all(dir, ec);
}
