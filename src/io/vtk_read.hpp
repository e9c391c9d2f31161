// Reading centridem's own ParaView files back (for `centridem render`): the
// particle frames (.vtu, appended zlib-compressed binary as io/vtk.cpp writes
// them, or the ASCII files of earlier versions) and the .pvd series that list
// them. Not a general VTK reader: ParaView and VTK read any of these files.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace centridem {

struct VtuArrays {
  std::size_t points = 0;
  // Every DataArray by name, as doubles, tuples flattened (x0 y0 z0 x1 ...).
  std::map<std::string, std::vector<double>> arrays;
  // The named array with `components` values per point; throws InputError
  // naming the file and the array when it is missing or of another size.
  const std::vector<double>& get(const std::string& name, std::size_t components) const;
  std::string path;
};

// Throws InputError naming the file for anything it cannot read.
VtuArrays read_vtu(const std::string& path);

// (time, file) of each DataSet of a .pvd collection, in file order.
std::vector<std::pair<double, std::string>> read_pvd(const std::string& path);

} // namespace centridem
