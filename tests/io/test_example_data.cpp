// The example particle file examples/data/column_2k.xyzr and the example
// scenarios. The file is made by column_lattice() below (deterministic,
// integer arithmetic, so it is the same on every machine); the test checks
// that the checked-in file is what it makes. To remake it:
//   CENTRIDEM_WRITE_EXAMPLE_DATA=1 build/tests/centridem_tests --gtest_filter='ExampleData.*'
#include "base/errors.hpp"
#include "io/particle_file.hpp"
#include "io/scenario.hpp"

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <sstream>
#include <string>

namespace {

// 9 x 9 x 25 = 2,025 spheres on a loose cubic lattice of pitch 1.1 mm inside
// the box 0 < x, y < 10 mm, z > 0, radii uniform in 0.2-0.5 mm, centres
// jittered by up to 0.04 mm per axis. Neighbouring centres are at least
// 1.02 mm apart, more than the largest diameter (1.0 mm), so nothing
// overlaps; the gap to the walls x, y = 0, 10 mm and the floor z = 0 is at
// least 0.06 mm.
std::string column_lattice() {
  std::uint64_t state = 20240611;
  auto next = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return state >> 33;
  };
  constexpr std::int64_t pitch = 1'100'000, origin = 600'000, jitter = 40'000; // nm
  auto metres = [](std::int64_t nm) {
    return fmt::format("{}.{:09d}", nm / 1'000'000'000, nm % 1'000'000'000);
  };
  std::string out =
      "# column_2k.xyzr: 2,025 spheres, x y z r in metres (tests/io/test_example_data.cpp)\n";
  for (int k = 0; k < 25; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) {
        std::int64_t c[3] = {origin + i * pitch, origin + j * pitch, origin + k * pitch};
        for (auto& v : c) v += static_cast<std::int64_t>(next() % (2 * jitter + 1)) - jitter;
        const std::int64_t r = 200'000 + static_cast<std::int64_t>(next() % 300'001);
        out += fmt::format("{} {} {} {}\n", metres(c[0]), metres(c[1]), metres(c[2]), metres(r));
      }
  return out;
}

const std::string kSource = CENTRIDEM_SOURCE_DIR;

// The resolved TOML without its comments ("Read from", "named here").
std::string without_comments(const std::string& s) {
  std::istringstream in(s.substr(s.find("description")));
  std::string out, line;
  while (std::getline(in, line)) out += line.substr(0, line.find("  #")) + "\n";
  return out;
}

} // namespace

TEST(ExampleData, ColumnFileIsWhatTheGeneratorMakes) {
  const std::string path = kSource + "/examples/data/column_2k.xyzr";
  const std::string made = column_lattice();
  if (std::getenv("CENTRIDEM_WRITE_EXAMPLE_DATA")) {
    std::filesystem::create_directories(kSource + "/examples/data");
    std::ofstream(path, std::ios::binary) << made;
  }
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path;
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), made);
}

TEST(ExampleData, ColumnHasNoOverlaps) {
  const auto p = centridem::read_particle_file(kSource + "/examples/data/column_2k.xyzr");
  ASSERT_EQ(p.size(), 2025u);
  for (std::size_t a = 0; a < p.size(); ++a) {
    EXPECT_GE(p[a].radius, 0.2e-3 - 1e-12);
    EXPECT_LE(p[a].radius, 0.5e-3 + 1e-12);
    for (int c = 0; c < 2; ++c) {
      EXPECT_GT(p[a].position[c] - p[a].radius, 0.0);
      EXPECT_LT(p[a].position[c] + p[a].radius, 0.010);
    }
    EXPECT_GT(p[a].position.z - p[a].radius, 0.0);
    for (std::size_t b = a + 1; b < p.size(); ++b)
      EXPECT_GT(centridem::norm(p[b].position - p[a].position), p[a].radius + p[b].radius);
  }
}

TEST(ExampleData, ExampleScenariosParse) {
  for (const char* name : {"settle_column.toml", "demo_settle.toml"}) {
    SCOPED_TRACE(name);
    const auto sc = centridem::load_scenario(kSource + "/examples/" + name);
    EXPECT_FALSE(sc.stages.empty());
    EXPECT_EQ(sc.particles.records.size(), 2025u);
    // The resolved form reads back to the same resolved form.
    const std::string resolved = centridem::resolved_toml(sc);
    const auto again = centridem::parse_scenario(resolved, "resolved.toml", kSource + "/examples");
    EXPECT_EQ(without_comments(centridem::resolved_toml(again)), without_comments(resolved));
  }
}
