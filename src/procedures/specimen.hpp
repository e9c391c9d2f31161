// Specimen generation (DESIGN.md "Specimens"; Tao et al. section 3.1):
//
//   distribute  place particles uniformly at random in a periodic cell, with
//               overlaps allowed, drawing sizes so that the bin volume
//               fractions match, until the porosity ignoring overlaps reaches
//               the target (PFC `ball distribute`);
//   relax       frictionless linear contacts, local damping and periodic
//               velocity zeroing (PFC `calm`) until the mean unbalanced-force
//               ratio and the largest overlap are small; then optionally the
//               scenario's contact properties, cycled to equilibrium;
//   brick       the relaxed periodic cell with its contact state, saved to /
//               loaded from a JSON file (docs/specimens.md "Brick file");
//   assemble    copies of the brick side by side (nx x ny x nz) with their
//               contacts recreated across the joins, then everything whose
//               centre is outside the region deleted;
//   report      count, porosity, number density, volume fractions per bin and
//               d50 against the target (specimen.json).
//
// Reproducibility: one std::mt19937_64 seeded with specimen.seed drives
// every random choice, so a seed gives the same specimen bit for bit on the
// same build and thread count.
#pragma once

#include "engine/world.hpp"
#include "io/specimen_config.hpp"
#include "procedures/gsd.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace centridem {

using SpecimenLog = std::function<void(std::string_view)>;

// Radii drawn for `bins` at `porosity` ignoring overlaps in `cell` (periodic),
// placed uniformly at random (overlaps allowed), ids in random order.
// Returns how many particles were added.
std::size_t distribute(World& world, const std::vector<GradationBin>& bins, double porosity,
                       const Box& cell, double density_kg_m3, std::int32_t group,
                       SpecimenRandom& random);

struct RelaxResult {
  long packing_steps = 0;       // phase 1 (frictionless, calm)
  long contact_steps = 0;       // phase 2 (relax.contact), 0 when not used
  bool converged = false;       // the targets were reached within the step limits
  double ratio = 0;             // mean unbalanced-force ratio at the end [-]
  double max_overlap_ratio = 0; // largest overlap / smaller radius at the end [-]
  double coordination_number = 0;
  std::size_t contacts = 0;
};

// Relaxes a distributed assembly (see RelaxSpec). Velocities and spins are
// zero on return.
RelaxResult relax_packing(World& world, const RelaxSpec& relax, const SpecimenLog& log = {});

// A relaxed periodic cell and its contact state. Particle k has id k + 1 and
// lies in [0, size_m) on every axis; contact ids refer to those ids and each
// contact's image is that of end 2 relative to end 1 in the cell.
struct Brick {
  Vec3 size_m;
  double density_kg_m3 = 0;
  std::int32_t group = 0;
  std::vector<Vec3> position;
  std::vector<double> radius;
  std::vector<ContactRecord> contacts; // ball-ball only
  // Provenance (written to the file and the report).
  std::uint64_t seed = 0;
  double target_porosity = 0;
  RelaxResult relax;

  std::size_t size() const { return radius.size(); }
  bool operator==(const Brick& o) const;
};

// Settings of the World a brick is made in: local damping from relax, a
// tolerant instability guard (random placement makes deep overlaps).
WorldSettings brick_world_settings(const std::vector<GradationBin>& bins, const RelaxSpec& relax,
                                   int threads = 0);

// Smallest periodic cell side for these bins: 3 x (largest diameter + skin),
// skin = half the smallest radius (the World's automatic skin) [m].
double minimum_brick_side(const std::vector<GradationBin>& bins);

// distribute + relax in a periodic cell of size `size_m`, then capture.
// Throws InputError (key specimen.brick.size_m) for a cell that is too small.
Brick make_brick(const std::vector<GradationBin>& bins, double porosity, const Vec3& size_m,
                 double density_kg_m3, std::int32_t group, std::uint64_t seed,
                 const RelaxSpec& relax, const SpecimenLog& log = {}, int threads = 0);

// The brick held by a periodic World whose box starts at its lo corner:
// velocities zeroed, a neighbour rebuild forced (positions wrapped into the
// cell), particles and contact records by id.
Brick capture_brick(World& world);

// JSON brick file (docs/specimens.md): every double written so that it reads
// back exactly. read_brick throws InputError naming the file and the problem.
void write_brick(const Brick& brick, const std::string& path);
Brick read_brick(const std::string& path);

struct AssemblyOptions {
  Vec3 origin;                                       // where copy (0,0,0)'s cell starts [m]
  std::array<int, 3> copies{1, 1, 1};                // nx, ny, nz
  std::array<bool, 3> periodic{false, false, false}; // the assembly wraps along these axes
  std::optional<Box> keep;                           // delete particles whose centre is outside
};

struct AssemblyResult {
  std::size_t particles = 0; // added to the world
  std::size_t contacts = 0;  // contact records handed to the world
  std::array<int, 3> copies{1, 1, 1};
};

// Copies `brick` into `world`: copy (a,b,c) is translated by origin +
// (a Lx, b Ly, c Lz); its particles get ids next_id + copy * N + k (copy =
// a + nx (b + ny c)); a brick contact with image s from copy c is recreated
// between copy c and copy c + s, dropped when that copy does not exist unless
// the assembly is periodic along that axis (then it wraps). When any axis is
// periodic the world's periodic box is set to origin .. origin + n L along
// those axes. Contacts are matched at the world's next neighbour rebuild.
AssemblyResult assemble_bricks(const Brick& brick, World& world, const AssemblyOptions& options);

// Copies along each axis that cover `region` starting at its lo corner.
std::array<int, 3> copies_to_fill(const Vec3& cell, const Box& region);

struct BinReport {
  GradationBin target;
  double generated_volume_fraction = 0;
  std::size_t particles = 0;
};

struct SpecimenReport {
  std::string source; // "distribute", "brick file" or "particle file"
  Box region;
  std::size_t particles = 0; // centres inside the region
  double porosity = 0;       // ignoring overlaps, centre-based [-]
  double number_density_per_m3 = 0;
  double d50_m = 0;              // mass-median diameter of the particles [m]
  double target_porosity = 0;    // 0 when not given
  double target_d50_m = 0;       // 0 without a gradation
  double expected_particles = 0; // from the target gradation and porosity, 0 without
  std::vector<BinReport> bins;   // empty without a gradation
  double outside_bins_fraction = 0;
  std::size_t contacts = 0; // ball-ball contacts handed over (bricks)
  // Brick (distribute / brick file).
  bool has_brick = false;
  Vec3 brick_size_m;
  std::size_t brick_particles = 0;
  std::size_t brick_contacts = 0;
  std::array<int, 3> copies{1, 1, 1};
  std::uint64_t seed = 0;
  RelaxResult relax;
  double brick_seconds = 0; // time to distribute and relax the brick [s]
};

// Statistics of the particles of `world` whose centre lies in `region`.
SpecimenReport specimen_report(const World& world, const Box& region,
                               const std::vector<GradationBin>& bins, double target_porosity);
nlohmann::json to_json(const SpecimenReport& report);
std::string format_report(const SpecimenReport& report);

struct BuiltSpecimen {
  SpecimenReport report;
  std::optional<Brick> brick;
};

// Builds the specimen `spec` describes into `world` (fresh): a brick
// (distributed and relaxed, or read) assembled to fill the region, or a
// plain particle file. Resolves and checks the gradation before any work.
// The number of particles the distributed specimen will hold, estimated from
// the region, the porosity and the gradation (resolve_gradation) before
// anything is allocated.
double estimated_specimen_particles(const SpecimenSpec& spec,
                                    const std::vector<GradationBin>& bins);
// Throws InputError naming specimen.region when that estimate exceeds
// specimen.max_particles, with the memory it would take and the hint that
// lengths are in metres (a region in mm asks for 1e9 times too many).
void check_specimen_size(const SpecimenSpec& spec, const std::vector<GradationBin>& bins);

BuiltSpecimen build_specimen(const SpecimenSpec& spec, World& world, const SpecimenLog& log = {},
                             int threads = 0);

// Fits a specimen into walls built around its region: centres inside the
// region leave spheres poking through the walls; calm cycles (10 steps, then
// velocities and spins zeroed, PFC `calm`) under a tolerant overlap guard
// push them in until the largest overlap is below 5 % of the smaller radius
// (at most 20,000 steps). Returns the steps taken.
long calm_into_walls(World& world);

// Every existing ball-ball contact and the defaults for new ones become `c`
// (the preparation's switch from the compaction properties to the material,
// and back; PFC: the contact model assignment table plus a property change).
void assign_ball_ball_contacts(World& world, const ContactProperties& c);

// Total solid volume of the particles, sum of 4/3 pi r^3 [m^3].
double solid_volume_m3(const ParticleStore& particles);

// Writes the specimen's files into `dir` (created): specimen.vtu (ParaView),
// specimen.xyzr (x y z r per line, SI), specimen.json (the report),
// specimen.toml (the resolved [specimen] table) and brick.json (when a
// brick was made or read).
void write_specimen_outputs(const World& world, const BuiltSpecimen& built,
                            const SpecimenSpec& spec, const std::string& dir);

} // namespace centridem
