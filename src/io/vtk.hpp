// ParaView output: VTK XML files (ASCII), one pair per frame, and .pvd series
// files that give each frame its simulated time.
//   particles: UnstructuredGrid (.vtu), one vertex cell per particle centre,
//     point data radius, id, group, velocity, displacement,
//     displacement_magnitude, spin, force (all SI).
//   contacts: PolyData (.vtp), one line per active ball-ball contact between
//     the two particle centres (force chains), cell data force_N (the force on
//     the second particle, vector), normal_force_N (its component along the
//     normal from the first to the second centre: > 0 in compression) and
//     overlap_m.
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

void write_particles_vtu(const World& world, const std::string& path);
void write_contacts_vtp(const World& world, const std::string& path);

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
