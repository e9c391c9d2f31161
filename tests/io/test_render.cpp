// `centridem render`: pictures from a run's saved frames after the run (issue
// 19). On the tiny slope: the re-rendered picture at the cut is the trial's
// own picture pixel for pixel, the later ones all but the detected slip
// line; colouring by velocity colours particles that have not moved; the
// checks plot is written; bad options exit 2 naming them.
#include "cli_test_util.hpp"
#include "scenario_fixtures.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <string>

namespace fs = std::filesystem;
using namespace centridem::testutil;

namespace {

struct Png {
  int width = 0, height = 0;
  std::vector<std::uint32_t> pixels; // ARGB, row by row
};

Png load_png(const fs::path& p) {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> s{
      cairo_image_surface_create_from_png(p.string().c_str()), cairo_surface_destroy};
  Png out;
  if (cairo_surface_status(s.get()) != CAIRO_STATUS_SUCCESS) return out;
  cairo_surface_flush(s.get());
  out.width = cairo_image_surface_get_width(s.get());
  out.height = cairo_image_surface_get_height(s.get());
  const int stride = cairo_image_surface_get_stride(s.get());
  const unsigned char* data = cairo_image_surface_get_data(s.get());
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      out.pixels.push_back(*reinterpret_cast<const std::uint32_t*>(data + y * stride + 4 * x));
  return out;
}

// Share of pixels that differ between two pictures of the same size.
double differing_share(const Png& a, const Png& b) {
  if (a.pixels.size() != b.pixels.size() || a.pixels.empty()) return 1.0;
  std::size_t d = 0;
  for (std::size_t k = 0; k < a.pixels.size(); ++k) d += a.pixels[k] != b.pixels[k];
  return static_cast<double>(d) / static_cast<double>(a.pixels.size());
}

// Pixels of the light grey-blue that particles below the colour scale get.
std::size_t below_scale_pixels(const Png& p) {
  std::size_t n = 0;
  for (std::uint32_t v : p.pixels) {
    const int r = (v >> 16) & 0xff, g = (v >> 8) & 0xff, b = v & 0xff;
    n += std::abs(r - 204) <= 2 && std::abs(g - 214) <= 2 && std::abs(b - 227) <= 2;
  }
  return n;
}

} // namespace

TEST(Render, ReproducesATrialsPicturesAndColoursByVelocity) {
  TempDir dir("centridem_render");
  std::string tiny = kTinySlope;
  tiny.replace(tiny.find("vtk = false"), 11, "vtk = true");
  std::ofstream(dir / "tiny.toml") << tiny;
  const fs::path run = dir / "run", trial = run / "trial_20g";
  const CliRun slope = run_centridem({"slope", (dir / "tiny.toml").string(), "--out", run.string(),
                                      "--cache", (dir / "cache").string()},
                                     dir / "slope.log");
  ASSERT_EQ(slope.code, 0) << slope.output;

  const CliRun disp = run_centridem({"render", run.string()}, dir / "render.log");
  ASSERT_EQ(disp.code, 0) << disp.output;
  const fs::path out = trial / "render_displacement";
  std::size_t frames = 0;
  for (; fs::exists(trial / "pictures" / fmt::format("frame_{:04d}.png", frames)); ++frames) {
    const std::string name = fmt::format("frame_{:04d}.png", frames);
    SCOPED_TRACE(name);
    const Png original = load_png(trial / "pictures" / name), again = load_png(out / name);
    ASSERT_GT(original.width, 0);
    ASSERT_EQ(again.width, original.width);
    ASSERT_EQ(again.height, original.height);
    if (frames == 0)
      EXPECT_EQ(differing_share(original, again), 0.0) << "the cut: the same picture";
    else // float32 displacements in the frames; the detected slip line is not redrawn
      EXPECT_LT(differing_share(original, again), 0.03);
  }
  EXPECT_GE(frames, 4u);
  const Png checks = load_png(out / "checks.png");
  EXPECT_EQ(checks.width, 1800);

  // By velocity: at the cut nothing has moved (every particle below the
  // displacement scale) but the settled grains still creep.
  const CliRun vel = run_centridem({"render", trial.string(), "--field", "velocity", "--range",
                                    "1e-9,1e-3", "--out", (dir / "vel").string()},
                                   dir / "vel.log");
  ASSERT_EQ(vel.code, 0) << vel.output;
  const Png d0 = load_png(out / "frame_0000.png"), v0 = load_png(dir / "vel" / "frame_0000.png");
  ASSERT_EQ(v0.width, d0.width);
  EXPECT_GT(below_scale_pixels(d0), 1000u) << "a 300-pixel picture";
  EXPECT_LT(below_scale_pixels(v0), below_scale_pixels(d0) / 10) << below_scale_pixels(v0);

  // Bad options: exit 2, named.
  for (const auto& [args, word] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"render", trial.string(), "--range", "5,1"}, "--range"},
           {{"render", (dir / "nothing").string()}, "RUN_DIR"},
           {{"render", dir.path().string()}, "RUN_DIR"},
           {{"render", trial.string(), "--field", "pressure"}, "--field"}}) {
    const CliRun bad = run_centridem(args, dir / "bad.log");
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find(word), std::string::npos) << bad.output;
  }
}
