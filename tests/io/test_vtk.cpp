// ParaView files: binary (appended, zlib-compressed) VTK XML that VTK's own
// readers open, with the values the World holds, and a fraction of the size
// of the ASCII files written before (issue 19).
#include "engine/world.hpp"
#include "io/vtk.hpp"
#include "vtk_test_util.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <random>
#include <string>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace centridem;

namespace {

// A settled-looking random packing: n spheres on a jittered lattice in a box
// with a floor and one rectangle wall, each with a velocity and displacement.
World small_world(std::size_t n_side) {
  World w;
  ContactProperties p;
  p.effective_modulus_Pa = 1e8;
  p.friction = 0.5;
  w.set_ball_ball_defaults(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double pitch = 1e-3;
  for (std::size_t k = 0; k < n_side; ++k)
    for (std::size_t j = 0; j < n_side; ++j)
      for (std::size_t i = 0; i < n_side; ++i) {
        const Vec3 x{pitch * (0.5 + static_cast<double>(i)) + 1e-5 * u(rng),
                     pitch * (0.5 + static_cast<double>(j)) + 1e-5 * u(rng),
                     pitch * (0.5 + static_cast<double>(k)) + 1e-5 * u(rng)};
        // Radii slightly above half the pitch: neighbours overlap (force chains).
        w.add_particle(x, 0.51e-3 + 1e-5 * u(rng), 2650.0, static_cast<std::int32_t>(k % 3));
      }
  ParticleStore& P = w.particles_mut();
  for (std::size_t i = 0; i < P.size(); ++i) {
    P.velocity[i] = {1e-3 * u(rng), 2e-3 * u(rng), -3e-3 * u(rng)};
    P.displacement[i] = {1e-4 * u(rng), 0.0, -2e-4 * u(rng)};
  }
  w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), p);
  w.add_wall(Wall::rectangle("side", {0, 2e-3, 2e-3}, {1, 0, 0}, {0, 1, 0}, 4e-3, 3e-3), p);
  w.cycle(1); // contacts and forces
  return w;
}

fs::path temp_dir(const char* name) {
  const fs::path d = fs::temp_directory_path() / fmt::format("centridem_vtk_{}_{}", name, getpid());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs a Python script with Debian's python3 (where python3-vtk9 lives) and
// returns its stdout; the exit status must be 0.
std::string run_python(const fs::path& script, const fs::path& out) {
  const std::string cmd =
      fmt::format("/usr/bin/python3 '{}' > '{}' 2>&1", script.string(), out.string());
  const int rc = std::system(cmd.c_str());
  std::ifstream in(out);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0)
      << "VTK's Python reader failed (is python3-vtk9 installed? scripts/setup.sh installs it):\n"
      << text;
  return text;
}

} // namespace

// What we write is what the World holds: doubles exact, floats to float
// precision, the cells and the sliding flag as given.
TEST(Vtk, BinaryFramesHoldTheWorldsValues) {
  World w = small_world(4);
  const ParticleStore& P = w.particles();
  const fs::path d = temp_dir("values");
  PointField flag{"sliding", std::vector<float>(P.size(), 0.0f)};
  flag.values[5] = 1.0f;
  write_particles_vtu(w, (d / "p.vtu").string(), {flag});
  const vtktest::VtkFile f = vtktest::read_vtk(d / "p.vtu");
  const auto a = vtktest::arrays(f);
  ASSERT_EQ(a.at("radius").size(), P.size());
  for (std::size_t i = 0; i < P.size(); ++i) {
    EXPECT_EQ(a.at("radius")[i], P.radius[i]);
    EXPECT_EQ(a.at("id")[i], static_cast<double>(P.id[i]));
    EXPECT_EQ(a.at("group")[i], static_cast<double>(P.group[i]));
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(a.at("Points")[3 * i + c], P.position[i][c]);
      EXPECT_EQ(a.at("velocity")[3 * i + c],
                static_cast<double>(static_cast<float>(P.velocity[i][c])));
    }
    EXPECT_EQ(a.at("displacement")[3 * i + 2],
              static_cast<double>(static_cast<float>(P.displacement[i].z)));
    EXPECT_EQ(a.at("sliding")[i], i == 5 ? 1.0 : 0.0);
    EXPECT_EQ(a.at("connectivity")[i], static_cast<double>(i));
    EXPECT_EQ(a.at("offsets")[i], static_cast<double>(i + 1));
    EXPECT_EQ(a.at("types")[i], 1.0); // VTK_VERTEX
  }

  write_contacts_vtp(w, (d / "c.vtp").string());
  const vtktest::VtkFile fc = vtktest::read_vtk(d / "c.vtp");
  const auto c = vtktest::arrays(fc);
  const std::vector<ContactView> contacts = w.ball_ball_contacts();
  ASSERT_GT(contacts.size(), P.size()); // a packing, not loose spheres
  ASSERT_EQ(c.at("normal_force_N").size(), contacts.size());
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const double fn = dot(contacts[k].force_on_j, contacts[k].normal);
    EXPECT_NEAR(c.at("normal_force_N")[k], fn, 1e-6 * std::abs(fn));
    // Each line joins the two centres of its contact.
    const auto& pts = c.at("Points");
    const auto i1 = static_cast<std::size_t>(c.at("connectivity")[2 * k]);
    const auto i2 = static_cast<std::size_t>(c.at("connectivity")[2 * k + 1]);
    for (int q = 0; q < 3; ++q) {
      EXPECT_EQ(pts[3 * i1 + q], P.position[contacts[k].i][q]);
      EXPECT_EQ(pts[3 * i2 + q], P.position[contacts[k].j][q]);
    }
  }
  fs::remove_all(d);
}

// VTK's own XML readers (python3-vtk9, the reader ParaView uses) open the
// three kinds of file and see the same counts and values.
TEST(Vtk, VtksOwnReadersOpenTheFrames) {
  World w = small_world(5);
  const fs::path d = temp_dir("reader");
  write_particles_vtu(w, (d / "p.vtu").string(), {{"sliding", std::vector<float>(125, 1.0f)}});
  write_contacts_vtp(w, (d / "c.vtp").string());
  write_walls_vtp(w, (d / "w.vtp").string());
  double radius_sum = 0, z_sum = 0;
  for (std::size_t i = 0; i < w.particles().size(); ++i)
    radius_sum += w.particles().radius[i], z_sum += w.particles().position[i].z;
  std::ofstream(d / "read.py") << fmt::format(R"(
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLPolyDataReader
r = vtkXMLUnstructuredGridReader(); r.SetFileName("{0}/p.vtu"); r.Update()
g = r.GetOutput(); pd = g.GetPointData()
rad = pd.GetArray("radius"); sl = pd.GetArray("sliding")
print("points", g.GetNumberOfPoints(), "cells", g.GetNumberOfCells())
print("radius_sum %.17g" % sum(rad.GetValue(i) for i in range(rad.GetNumberOfTuples())))
print("z_sum %.17g" % sum(g.GetPoint(i)[2] for i in range(g.GetNumberOfPoints())))
print("sliding_sum", sum(sl.GetValue(i) for i in range(sl.GetNumberOfTuples())))
print("velocity_components", pd.GetArray("velocity").GetNumberOfComponents())
c = vtkXMLPolyDataReader(); c.SetFileName("{0}/c.vtp"); c.Update()
print("lines", c.GetOutput().GetNumberOfLines(), "force_tuples", c.GetOutput().GetCellData().GetArray("normal_force_N").GetNumberOfTuples())
k = vtkXMLPolyDataReader(); k.SetFileName("{0}/w.vtp"); k.Update()
print("polys", k.GetOutput().GetNumberOfPolys(), "wall_points", k.GetOutput().GetNumberOfPoints())
)",
                                              d.string());
  const std::string out = run_python(d / "read.py", d / "read.out");
  const std::size_t nc = w.ball_ball_contacts().size();
  EXPECT_NE(out.find("points 125 cells 125"), std::string::npos) << out;
  EXPECT_NE(out.find(fmt::format("radius_sum {:.17g}", radius_sum)), std::string::npos)
      << out << "\nexpected radius_sum " << fmt::format("{:.17g}", radius_sum);
  EXPECT_NE(out.find(fmt::format("z_sum {:.17g}", z_sum)), std::string::npos) << out;
  EXPECT_NE(out.find("sliding_sum 125.0"), std::string::npos) << out;
  EXPECT_NE(out.find("velocity_components 3"), std::string::npos) << out;
  EXPECT_NE(out.find(fmt::format("lines {} force_tuples {}", nc, nc)), std::string::npos) << out;
  EXPECT_NE(out.find("polys 2 wall_points 8"), std::string::npos) << out;
  fs::remove_all(d);
}

// Size: the ASCII frames were 266 bytes per particle (measured: 538,385 bytes
// for the 2,025 particles of examples/demo_settle.toml, 9 significant digits
// for positions and radii, 7 for the fields, ids and cells). The binary frames
// must be at least 3 x smaller: below 266 / 3 = 88 bytes per particle, here
// with random values in every field (nothing for zlib to find but the ids and
// cells).
TEST(Vtk, BinaryFramesAreAtLeastThreeTimesSmallerThanTheAsciiOnes) {
  World w = small_world(12); // 1,728 particles
  const fs::path d = temp_dir("size");
  write_particles_vtu(w, (d / "p.vtu").string());
  const double per_particle =
      static_cast<double>(fs::file_size(d / "p.vtu")) / static_cast<double>(w.particles().size());
  EXPECT_LT(per_particle, 266.0 / 3.0);
  fs::remove_all(d);
}
