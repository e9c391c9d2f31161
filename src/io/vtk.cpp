#include "io/vtk.hpp"

#include "core/world.hpp"
#include "io/output.hpp"

#include <fmt/format.h>
#include <iterator>

namespace centridem {

namespace {

using Buffer = fmt::memory_buffer;

constexpr const char* kHeader = "<?xml version=\"1.0\"?>\n";

void open_array(Buffer& b, const char* type, const char* name, int components) {
  fmt::format_to(std::back_inserter(b), "        <DataArray type=\"{}\" Name=\"{}\"", type, name);
  if (components > 1)
    fmt::format_to(std::back_inserter(b), " NumberOfComponents=\"{}\"", components);
  fmt::format_to(std::back_inserter(b), " format=\"ascii\">\n");
}

void close_array(Buffer& b) {
  fmt::format_to(std::back_inserter(b), "\n        </DataArray>\n");
}

// Values of one array, several to a line so that the files stay readable.
template <class T, class F> void values(Buffer& b, std::size_t n, F&& value, const char* spec) {
  auto out = std::back_inserter(b);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string_view sep = i == 0 ? "          " : (i % 6 == 0 ? "\n          " : " ");
    b.append(sep.data(), sep.data() + sep.size());
    fmt::format_to(out, fmt::runtime(spec), static_cast<T>(value(i)));
  }
}

template <class F> void vectors(Buffer& b, std::size_t n, F&& value, const char* spec) {
  auto out = std::back_inserter(b);
  const std::string triple = std::string(spec) + " " + spec + " " + spec;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string_view sep = i == 0 ? "          " : (i % 2 == 0 ? "\n          " : "  ");
    b.append(sep.data(), sep.data() + sep.size());
    const Vec3 v = value(i);
    fmt::format_to(out, fmt::runtime(triple), v.x, v.y, v.z);
  }
}

constexpr const char* kPos = "{:.9g}"; // positions: 9 significant digits
constexpr const char* kVal = "{:.7g}"; // everything else

} // namespace

void write_particles_vtu(const World& world, const std::string& path) {
  const ParticleStore& p = world.particles();
  const std::size_t n = p.size();
  Buffer b;
  auto out = std::back_inserter(b);
  fmt::format_to(out, "{}", kHeader);
  fmt::format_to(out, "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
  fmt::format_to(out, "  <UnstructuredGrid>\n");
  fmt::format_to(out, "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n, n);
  fmt::format_to(out, "      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n");
  open_array(b, "Float64", "radius", 1);
  values<double>(
      b, n, [&](std::size_t i) { return p.radius[i]; }, kPos);
  close_array(b);
  open_array(b, "Int64", "id", 1);
  values<long long>(
      b, n, [&](std::size_t i) { return p.id[i]; }, "{}");
  close_array(b);
  open_array(b, "Int32", "group", 1);
  values<int>(
      b, n, [&](std::size_t i) { return p.group[i]; }, "{}");
  close_array(b);
  open_array(b, "Float64", "velocity", 3);
  vectors(
      b, n, [&](std::size_t i) { return p.velocity[i]; }, kVal);
  close_array(b);
  open_array(b, "Float64", "displacement", 3);
  vectors(
      b, n, [&](std::size_t i) { return p.displacement[i]; }, kVal);
  close_array(b);
  open_array(b, "Float64", "displacement_magnitude", 1);
  values<double>(
      b, n, [&](std::size_t i) { return norm(p.displacement[i]); }, kVal);
  close_array(b);
  open_array(b, "Float64", "spin", 3);
  vectors(
      b, n, [&](std::size_t i) { return p.spin[i]; }, kVal);
  close_array(b);
  open_array(b, "Float64", "force", 3);
  vectors(
      b, n, [&](std::size_t i) { return p.force[i]; }, kVal);
  close_array(b);
  fmt::format_to(out, "      </PointData>\n");
  fmt::format_to(out, "      <Points>\n");
  open_array(b, "Float64", "Points", 3);
  vectors(
      b, n, [&](std::size_t i) { return p.position[i]; }, kPos);
  close_array(b);
  fmt::format_to(out, "      </Points>\n");
  fmt::format_to(out, "      <Cells>\n");
  open_array(b, "Int64", "connectivity", 1);
  values<std::size_t>(
      b, n, [](std::size_t i) { return i; }, "{}");
  close_array(b);
  open_array(b, "Int64", "offsets", 1);
  values<std::size_t>(
      b, n, [](std::size_t i) { return i + 1; }, "{}");
  close_array(b);
  open_array(b, "UInt8", "types", 1);
  values<int>(
      b, n, [](std::size_t) { return 1; }, "{}"); // VTK_VERTEX
  close_array(b);
  fmt::format_to(out, "      </Cells>\n");
  fmt::format_to(out, "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
  write_text_file(path, std::string_view(b.data(), b.size()));
}

void write_contacts_vtp(const World& world, const std::string& path) {
  const ParticleStore& p = world.particles();
  const std::vector<ContactView> contacts = world.ball_ball_contacts();
  // Points: the centres of the particles that have a contact, in index order.
  std::vector<std::int64_t> point_of(p.size(), -1);
  std::vector<std::uint32_t> points;
  for (const ContactView& c : contacts)
    for (std::uint32_t k : {c.i, c.j})
      if (point_of[k] < 0) point_of[k] = 0;
  for (std::size_t k = 0; k < p.size(); ++k)
    if (point_of[k] == 0) {
      point_of[k] = static_cast<std::int64_t>(points.size());
      points.push_back(static_cast<std::uint32_t>(k));
    }
  const std::size_t nc = contacts.size();
  Buffer b;
  auto out = std::back_inserter(b);
  fmt::format_to(out, "{}", kHeader);
  fmt::format_to(out, "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                      "header_type=\"UInt64\">\n");
  fmt::format_to(out, "  <PolyData>\n");
  fmt::format_to(out,
                 "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" "
                 "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
                 points.size(), nc);
  fmt::format_to(out, "      <Points>\n");
  open_array(b, "Float64", "Points", 3);
  vectors(
      b, points.size(), [&](std::size_t k) { return p.position[points[k]]; }, kPos);
  close_array(b);
  fmt::format_to(out, "      </Points>\n");
  fmt::format_to(out, "      <CellData Scalars=\"normal_force_N\" Vectors=\"force_N\">\n");
  open_array(b, "Float64", "force_N", 3);
  vectors(
      b, nc, [&](std::size_t k) { return contacts[k].force_on_j; }, kVal);
  close_array(b);
  open_array(b, "Float64", "normal_force_N", 1);
  values<double>(
      b, nc, [&](std::size_t k) { return dot(contacts[k].force_on_j, contacts[k].normal); }, kVal);
  close_array(b);
  open_array(b, "Float64", "overlap_m", 1);
  values<double>(
      b, nc, [&](std::size_t k) { return contacts[k].overlap_m; }, kVal);
  close_array(b);
  fmt::format_to(out, "      </CellData>\n");
  fmt::format_to(out, "      <Lines>\n");
  open_array(b, "Int64", "connectivity", 1);
  values<long long>(
      b, 2 * nc,
      [&](std::size_t k) {
        const ContactView& c = contacts[k / 2];
        return point_of[k % 2 == 0 ? c.i : c.j];
      },
      "{}");
  close_array(b);
  open_array(b, "Int64", "offsets", 1);
  values<std::size_t>(
      b, nc, [](std::size_t k) { return 2 * (k + 1); }, "{}");
  close_array(b);
  fmt::format_to(out, "      </Lines>\n");
  fmt::format_to(out, "    </Piece>\n  </PolyData>\n</VTKFile>\n");
  write_text_file(path, std::string_view(b.data(), b.size()));
}

void PvdSeries::add(double time_s, const std::string& file) {
  entries_.emplace_back(time_s, file);
  write();
}

void PvdSeries::assign(std::vector<std::pair<double, std::string>> entries) {
  entries_ = std::move(entries);
  write();
}

void PvdSeries::write() const {
  std::string s = kHeader;
  s += "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n";
  s += "  <Collection>\n";
  for (const auto& [t, f] : entries_)
    s += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t,
                     f);
  s += "  </Collection>\n</VTKFile>\n";
  replace_text_file(path_, s);
}

} // namespace centridem
