// Side-view pictures: the PNG has the promised size, and chosen pixels carry
// the promised colours (top of the map above vmax, the middle of the map at
// the log-middle of the scale, red along the outline, white background,
// near particles over far ones, slices).
#include "io/picture.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <unistd.h>

using namespace centridem;

namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path d = fs::temp_directory_path() / (std::string("centridem_picture_") + info->name() + "_" +
                                            std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

// A PNG read back into memory.
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
  // 0..255 per channel at pixel (x, y).
  std::array<int, 3> at(double xd, double yd) const {
    const int x = static_cast<int>(std::floor(xd)), y = static_cast<int>(std::floor(yd));
    EXPECT_TRUE(x >= 0 && x < width && y >= 0 && y < height) << x << ", " << y;
    const unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    const auto v = *reinterpret_cast<const std::uint32_t*>(data + y * stride + 4 * x);
    return {static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff),
            static_cast<int>(v & 0xff)};
  }
};

std::array<int, 3> bytes(const Rgb& c) {
  return {static_cast<int>(std::lround(255 * c.r)), static_cast<int>(std::lround(255 * c.g)),
          static_cast<int>(std::lround(255 * c.b))};
}

::testing::AssertionResult near_colour(const std::array<int, 3>& got,
                                       const std::array<int, 3>& want, int tol = 2) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(got[i] - want[i]) > tol)
      return ::testing::AssertionFailure()
             << "got (" << got[0] << ", " << got[1] << ", " << got[2] << "), want (" << want[0]
             << ", " << want[1] << ", " << want[2] << ")";
  return ::testing::AssertionSuccess();
}

bool is_red(const std::array<int, 3>& c) {
  return c[0] > 180 && c[1] < 90 && c[2] < 90;
}

// A few thousand random spheres in the lower part of a 40 mm x 20 mm window
// (z < 8 mm), values spread over the scale; the upper part is left empty for
// the test particles and lines.
SideViewInput random_specimen(int n) {
  SideViewInput in;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(1e-3, 39e-3), uy(0, 5e-3), uz(1e-3, 8e-3),
      ur(0.15e-3, 0.25e-3), ue(-4.5, -2.0);
  for (int i = 0; i < n; ++i) {
    in.x.push_back(ux(rng));
    in.y.push_back(uy(rng));
    in.z.push_back(uz(rng));
    in.radius.push_back(ur(rng));
    in.value.push_back(std::pow(10.0, ue(rng)));
  }
  in.window = SideViewWindow{0, 40e-3, 0, 20e-3};
  in.title = "test specimen — 40 g — t = 0.102 s";
  return in;
}

void add_particle(SideViewInput& in, double x, double y, double z, double r, double v) {
  in.x.push_back(x);
  in.y.push_back(y);
  in.z.push_back(z);
  in.radius.push_back(r);
  in.value.push_back(v);
}

} // namespace

TEST(ColourScale, EndsMiddleAndOutOfRange) {
  const double vmin = 1.2e-4, vmax = 5e-3;
  // viridis ends (matplotlib's first and last entries).
  EXPECT_TRUE(near_colour(bytes(colour_map(ColourMap::viridis, 0)), {68, 1, 84}, 1));
  EXPECT_TRUE(near_colour(bytes(colour_map(ColourMap::viridis, 1)), {253, 231, 37}, 1));
  // The middle of the map is viridis entry 128 (0.127568, 0.566949, 0.550556) within a step.
  EXPECT_TRUE(near_colour(bytes(colour_map(ColourMap::viridis, 0.5)), {33, 145, 140}, 2));
  // Log scale: the geometric mean of vmin and vmax is the middle of the map.
  EXPECT_TRUE(
      near_colour(bytes(scale_colour(std::sqrt(vmin * vmax), vmin, vmax, true, ColourMap::viridis)),
                  bytes(colour_map(ColourMap::viridis, 0.5)), 0));
  EXPECT_EQ(scale_colour(vmax, vmin, vmax, true, ColourMap::viridis),
            colour_map(ColourMap::viridis, 1));
  EXPECT_EQ(scale_colour(1.0, vmin, vmax, true, ColourMap::viridis),
            colour_map(ColourMap::viridis, 1));
  EXPECT_TRUE(near_colour(bytes(scale_colour(vmin, vmin, vmax, true, ColourMap::viridis)),
                          bytes(colour_map(ColourMap::viridis, 0)), 0));
  EXPECT_EQ(scale_colour(1e-5, vmin, vmax, true, ColourMap::viridis), below_scale_colour);
  EXPECT_EQ(scale_colour(0.0, vmin, vmax, true, ColourMap::viridis), below_scale_colour);
  EXPECT_EQ(scale_colour(NAN, vmin, vmax, true, ColourMap::viridis), below_scale_colour);
  // Linear scale middle.
  EXPECT_TRUE(near_colour(bytes(scale_colour(0.5, 0, 1, false, ColourMap::turbo)),
                          bytes(colour_map(ColourMap::turbo, 0.5)), 0));
  // turbo runs from blue through green to dark red.
  const Rgb t0 = colour_map(ColourMap::turbo, 0.1), t1 = colour_map(ColourMap::turbo, 0.95);
  EXPECT_GT(t0.b, t0.r);
  EXPECT_GT(t1.r, t1.b);
  EXPECT_GT(colour_map(ColourMap::turbo, 0.5).g, 0.8);
}

TEST(SideView, PixelsCarryTheScaleTheOutlineAndTheBackground) {
  const fs::path dir = temp_dir();
  SideViewInput in = random_specimen(3000);
  // Test particles in the empty upper part, big enough to sample their centres.
  const double vmin = in.vmin, vmax = in.vmax;
  add_particle(in, 8e-3, 2e-3, 14e-3, 1.0e-3, 0.05);                    // above vmax
  add_particle(in, 16e-3, 2e-3, 14e-3, 1.0e-3, std::sqrt(vmin * vmax)); // log middle
  add_particle(in, 24e-3, 2e-3, 14e-3, 1.0e-3, 1e-6);                   // below vmin
  // Outline across the empty band between the specimen and the test particles.
  in.outline.x = {2e-3, 20e-3, 38e-3};
  in.outline.z = {10e-3, 11e-3, 10e-3};
  const fs::path png = dir / "side.png";
  const SideViewLayout lay = render_side_view(in, png.string());

  ASSERT_TRUE(fs::exists(png));
  const Image img(png);
  ASSERT_TRUE(img.ok());
  EXPECT_EQ(img.width, 1200);
  EXPECT_EQ(img.height, lay.height_px);
  // Equal scales: the window's aspect (2:1) is kept.
  EXPECT_NEAR(lay.plot_width / lay.plot_height, 2.0, 1e-9);
  EXPECT_GT(img.height, 0.5 * lay.plot_height);

  EXPECT_TRUE(near_colour(img.at(lay.px_x(8e-3), lay.px_y(14e-3)),
                          bytes(colour_map(ColourMap::viridis, 1.0))));
  EXPECT_TRUE(near_colour(img.at(lay.px_x(16e-3), lay.px_y(14e-3)),
                          bytes(colour_map(ColourMap::viridis, 0.5))));
  EXPECT_TRUE(near_colour(img.at(lay.px_x(24e-3), lay.px_y(14e-3)), bytes(below_scale_colour)));

  // Red along the outline's path (sampled on both segments).
  for (double t : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    const double xa = 2e-3 + t * 18e-3, za = 10e-3 + t * 1e-3;
    EXPECT_TRUE(is_red(img.at(lay.px_x(xa), lay.px_y(za)))) << "first segment at t = " << t;
    const double xb = 20e-3 + t * 18e-3, zb = 11e-3 - t * 1e-3;
    EXPECT_TRUE(is_red(img.at(lay.px_x(xb), lay.px_y(zb)))) << "second segment at t = " << t;
  }
  // White background: an empty corner of the plot area and the picture's corner.
  EXPECT_TRUE(near_colour(img.at(lay.px_x(1e-3), lay.px_y(19e-3)), {255, 255, 255}, 0));
  EXPECT_TRUE(near_colour(img.at(2, 2), {255, 255, 255}, 0));
  // The specimen is drawn: most of its region is covered.
  int covered = 0, samples = 0;
  for (double x = 2e-3; x < 38e-3; x += 0.5e-3)
    for (double z = 2e-3; z < 7e-3; z += 0.5e-3, ++samples) {
      const auto c = img.at(lay.px_x(x), lay.px_y(z));
      covered += !(c[0] == 255 && c[1] == 255 && c[2] == 255);
    }
  EXPECT_GT(covered, samples / 2);

  // A copy for people to look at.
  std::error_code ec;
  fs::copy_file(png, fs::temp_directory_path() / "centridem_test_side_view.png",
                fs::copy_options::overwrite_existing, ec);
  fs::remove_all(dir, ec);
}

TEST(SideView, NearParticlesCoverFarOnesAndSlicesHideTheRest) {
  const fs::path dir = temp_dir();
  SideViewInput in;
  in.window = SideViewWindow{0, 10e-3, 0, 5e-3};
  // Same x, z: the far one (y = 4 mm, below the scale) is listed last, the
  // near one (y = 1 mm, above vmax) first; the near one must show.
  add_particle(in, 3e-3, 1e-3, 2.5e-3, 1e-3, 1.0);
  add_particle(in, 3e-3, 4e-3, 2.5e-3, 1e-3, 0.0);
  // Outside the slice |y - 2.5 mm| < 2 mm once slicing is on.
  add_particle(in, 7e-3, 4.8e-3, 2.5e-3, 1e-3, 1.0);
  in.outline.x.clear();
  in.outline.z.clear();
  const fs::path a = dir / "depth.png";
  SideViewLayout lay = render_side_view(in, a.string());
  {
    const Image img(a);
    ASSERT_TRUE(img.ok());
    EXPECT_TRUE(near_colour(img.at(lay.px_x(3e-3), lay.px_y(2.5e-3)),
                            bytes(colour_map(ColourMap::viridis, 1.0))));
    EXPECT_TRUE(near_colour(img.at(lay.px_x(7e-3), lay.px_y(2.5e-3)),
                            bytes(colour_map(ColourMap::viridis, 1.0))));
  }
  in.slice = true;
  in.slice_y_mid = 2.5e-3;
  in.slice_half_thickness = 2e-3;
  const fs::path b = dir / "slice.png";
  lay = render_side_view(in, b.string());
  {
    const Image img(b);
    ASSERT_TRUE(img.ok());
    EXPECT_TRUE(near_colour(img.at(lay.px_x(3e-3), lay.px_y(2.5e-3)),
                            bytes(colour_map(ColourMap::viridis, 1.0))));
    EXPECT_TRUE(near_colour(img.at(lay.px_x(7e-3), lay.px_y(2.5e-3)), {255, 255, 255}, 0));
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

TEST(SideView, DefaultWindowHoldsEveryParticleAndWidthIsKept) {
  const fs::path dir = temp_dir();
  SideViewInput in = random_specimen(500);
  in.window.reset();
  in.width_px = 800;
  const SideViewWindow w = side_view_window(in);
  for (std::size_t i = 0; i < in.x.size(); ++i) {
    EXPECT_LE(w.x_min, in.x[i] - in.radius[i]);
    EXPECT_GE(w.x_max, in.x[i] + in.radius[i]);
    EXPECT_LE(w.z_min, in.z[i] - in.radius[i]);
    EXPECT_GE(w.z_max, in.z[i] + in.radius[i]);
  }
  const fs::path png = dir / "auto.png";
  const SideViewLayout lay = render_side_view(in, png.string());
  const SideViewLayout predicted = side_view_layout(in);
  EXPECT_EQ(lay.height_px, predicted.height_px);
  const Image img(png);
  ASSERT_TRUE(img.ok());
  EXPECT_EQ(img.width, 800);
  EXPECT_EQ(img.height, lay.height_px);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

TEST(SideView, BadInputIsRefused) {
  const fs::path dir = temp_dir();
  SideViewInput in = random_specimen(10);
  in.radius.pop_back();
  EXPECT_THROW(render_side_view(in, (dir / "a.png").string()), std::invalid_argument);
  in = random_specimen(10);
  in.value.resize(3);
  EXPECT_THROW(render_side_view(in, (dir / "b.png").string()), std::invalid_argument);
  in = random_specimen(10);
  in.outline.x = {0, 1e-3};
  in.outline.z = {0};
  EXPECT_THROW(render_side_view(in, (dir / "c.png").string()), std::invalid_argument);
  in = random_specimen(10);
  EXPECT_THROW(render_side_view(in, (dir / "no_such_folder" / "d.png").string()),
               std::runtime_error);
  // Nothing to draw is not an error: an empty frame.
  SideViewInput empty;
  EXPECT_NO_THROW(render_side_view(empty, (dir / "e.png").string()));
  EXPECT_TRUE(fs::exists(dir / "e.png"));
  std::error_code ec;
  fs::remove_all(dir, ec);
}
