// ParaView output: VTK XML files in appended, zlib-compressed binary form
// (what ParaView writes itself; about 3.5 times smaller than the ASCII
// files of before), one per
// frame and kind, and .pvd series files that give each frame its time.
//   particles: UnstructuredGrid (.vtu), one vertex cell per particle centre,
//     point data radius (Float64), id, group, velocity, displacement, spin,
//     force (Float32, SI; ParaView offers each vector's magnitude itself),
//     plus any PointField a procedure adds (the slope's `sliding`: 1 in the
//     sliding mass).
//   contacts: PolyData (.vtp), one line per active ball-ball contact between
//     the two particle centres (force chains), cell data force_N (the force on
//     the second particle, vector), normal_force_N (its component along the
//     normal from the first to the second centre: > 0 in compression) and
//     overlap_m.
//   walls: PolyData (.vtp), one quadrilateral per wall (rectangles as they
//     are; infinite planes as squares around the particles), cell data
//     wall_index, force_N (the balls' force on it), velocity_m_per_s, contacts.
// In ParaView: open the .pvd; show particles with the "Point Gaussian"
// representation scaled by `radius` (or a Glyph filter, sphere, scale by
// radius, factor 2), force chains as lines or a Tube filter coloured by
// normal_force_N.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace centridem {

class World;

// A per-particle scalar written beside the standard fields (one value per
// particle, in the World's current order).
struct PointField {
  std::string name;
  std::vector<float> values;
};

void write_particles_vtu(const World& world, const std::string& path,
                         const std::vector<PointField>& extra = {});
void write_contacts_vtp(const World& world, const std::string& path);
void write_walls_vtp(const World& world, const std::string& path);

// A ParaView collection file (.pvd). Each add() rewrites the whole file, so
// the series is readable while a run is still going.
class PvdSeries {
public:
  PvdSeries() = default;
  explicit PvdSeries(std::string path) : path_(std::move(path)) {}
  // `file` is relative to the .pvd's folder.
  void add(double time_s, const std::string& file);
  // Replaces the entries (a resumed run's series so far) and writes the file.
  void assign(std::vector<std::pair<double, std::string>> entries);
  const std::vector<std::pair<double, std::string>>& entries() const { return entries_; }
  std::size_t size() const { return entries_.size(); }
  const std::string& path() const { return path_; }

private:
  void write() const;
  std::string path_;
  std::vector<std::pair<double, std::string>> entries_;
};

} // namespace centridem
