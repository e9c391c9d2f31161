#include "io/vtk.hpp"

#include "engine/world.hpp"
#include "io/output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <iterator>
#include <stdexcept>
#include <zlib.h>

namespace centridem {

namespace {

// A VTK XML file in the appended, zlib-compressed binary form (the form
// ParaView itself writes): the XML names each DataArray with an `offset` into
// one <AppendedData encoding="raw"> section after it; each array there is a
// UInt64 header (number of blocks, uncompressed block size, size of the last
// partial block or 0, compressed size of each block) and the compressed
// blocks (VTK file formats, "XML File Formats", vtkZLibDataCompressor).
class XmlVtk {
public:
  explicit XmlVtk(const char* type) : type_(type) {
    fmt::format_to(std::back_inserter(xml_),
                   "<?xml version=\"1.0\"?>\n<VTKFile type=\"{}\" version=\"1.0\" "
                   "byte_order=\"LittleEndian\" header_type=\"UInt64\" "
                   "compressor=\"vtkZLibDataCompressor\">\n  <{}>\n",
                   type, type);
  }
  void line(std::string_view text) {
    xml_.append(text.data(), text.data() + text.size());
    xml_.push_back('\n');
  }
  // One DataArray of n tuples of `components` values of type T (VTK type name `vtk_type`).
  template <class T>
  void array(const char* vtk_type, std::string_view name, int components, const std::vector<T>& v) {
    fmt::format_to(std::back_inserter(xml_), "        <DataArray type=\"{}\" Name=\"{}\"", vtk_type,
                   name);
    if (components > 1)
      fmt::format_to(std::back_inserter(xml_), " NumberOfComponents=\"{}\"", components);
    fmt::format_to(std::back_inserter(xml_), " format=\"appended\" offset=\"{}\"/>\n",
                   appended_.size());
    append_compressed(reinterpret_cast<const unsigned char*>(v.data()), v.size() * sizeof(T));
  }
  void write(const std::string& path) {
    fmt::format_to(std::back_inserter(xml_), "  </{}>\n  <AppendedData encoding=\"raw\">\n   _",
                   type_);
    std::string all(xml_.data(), xml_.size());
    all.append(appended_.begin(), appended_.end());
    all += "\n  </AppendedData>\n</VTKFile>\n";
    write_text_file(path, all);
  }

private:
  void append_compressed(const unsigned char* data, std::size_t bytes) {
    constexpr std::uint64_t kBlock = 1u << 20; // uncompressed block size [bytes]
    const std::uint64_t blocks = (bytes + kBlock - 1) / kBlock;
    std::vector<std::uint64_t> header{blocks, kBlock, bytes % kBlock};
    std::vector<std::vector<unsigned char>> packed;
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const std::uint64_t len = std::min<std::uint64_t>(kBlock, bytes - b * kBlock);
      uLongf out_len = compressBound(static_cast<uLong>(len));
      std::vector<unsigned char> out(out_len);
      if (compress2(out.data(), &out_len, data + b * kBlock, static_cast<uLong>(len),
                    Z_BEST_SPEED) != Z_OK)
        throw std::runtime_error("zlib could not compress a VTK array");
      out.resize(out_len);
      header.push_back(out_len);
      packed.push_back(std::move(out));
    }
    const auto* h = reinterpret_cast<const char*>(header.data());
    appended_.insert(appended_.end(), h, h + header.size() * sizeof(std::uint64_t));
    for (const auto& blk : packed) appended_.insert(appended_.end(), blk.begin(), blk.end());
  }
  const char* type_;
  fmt::memory_buffer xml_;
  std::vector<char> appended_;
};

std::vector<double> xyz(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const Vec3& a : v) out.insert(out.end(), {a.x, a.y, a.z});
  return out;
}

// Single precision for the fields (about 7 significant digits, as the ASCII
// files had); positions and radii keep double precision.
template <class F> std::vector<float> xyz32(std::size_t n, F&& value) {
  std::vector<float> out;
  out.reserve(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = value(i);
    out.insert(out.end(),
               {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)});
  }
  return out;
}

template <class T, class F> std::vector<T> each(std::size_t n, F&& value) {
  std::vector<T> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<T>(value(i));
  return out;
}

} // namespace

void write_particles_vtu(const World& world, const std::string& path,
                         const std::vector<PointField>& extra) {
  const ParticleStore& p = world.particles();
  const std::size_t n = p.size();
  for (const PointField& f : extra)
    if (f.values.size() != n)
      throw std::logic_error(fmt::format("VTK point field {} has {} values for {} particles",
                                         f.name, f.values.size(), n));
  XmlVtk v("UnstructuredGrid");
  v.line(fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">", n, n));
  v.line("      <PointData Scalars=\"radius\" Vectors=\"velocity\">");
  v.array("Float64", "radius", 1, p.radius);
  v.array("Int64", "id", 1, each<std::int64_t>(n, [&](std::size_t i) { return p.id[i]; }));
  v.array("Int32", "group", 1, each<std::int32_t>(n, [&](std::size_t i) { return p.group[i]; }));
  v.array("Float32", "velocity", 3, xyz32(n, [&](std::size_t i) { return p.velocity[i]; }));
  v.array("Float32", "displacement", 3, xyz32(n, [&](std::size_t i) { return p.displacement[i]; }));
  v.array("Float32", "spin", 3, xyz32(n, [&](std::size_t i) { return p.spin[i]; }));
  v.array("Float32", "force", 3, xyz32(n, [&](std::size_t i) { return p.force[i]; }));
  for (const PointField& f : extra) v.array("Float32", f.name, 1, f.values);
  v.line("      </PointData>");
  v.line("      <Points>");
  v.array("Float64", "Points", 3, xyz(p.position));
  v.line("      </Points>");
  v.line("      <Cells>");
  v.array("Int64", "connectivity", 1, each<std::int64_t>(n, [](std::size_t i) { return i; }));
  v.array("Int64", "offsets", 1, each<std::int64_t>(n, [](std::size_t i) { return i + 1; }));
  v.array("UInt8", "types", 1, std::vector<std::uint8_t>(n, 1)); // VTK_VERTEX
  v.line("      </Cells>");
  v.line("    </Piece>");
  v.write(path);
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
  XmlVtk v("PolyData");
  v.line(fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" "
                     "NumberOfStrips=\"0\" NumberOfPolys=\"0\">",
                     points.size(), nc));
  v.line("      <Points>");
  std::vector<double> xs;
  xs.reserve(3 * points.size());
  for (std::uint32_t k : points)
    xs.insert(xs.end(), {p.position[k].x, p.position[k].y, p.position[k].z});
  v.array("Float64", "Points", 3, xs);
  v.line("      </Points>");
  v.line("      <CellData Scalars=\"normal_force_N\" Vectors=\"force_N\">");
  v.array("Float32", "force_N", 3,
          xyz32(nc, [&](std::size_t k) { return contacts[k].force_on_j; }));
  v.array("Float32", "normal_force_N", 1, each<float>(nc, [&](std::size_t k) {
            return dot(contacts[k].force_on_j, contacts[k].normal);
          }));
  v.array("Float32", "overlap_m", 1,
          each<float>(nc, [&](std::size_t k) { return contacts[k].overlap_m; }));
  v.line("      </CellData>");
  v.line("      <Lines>");
  v.array("Int64", "connectivity", 1, each<std::int64_t>(2 * nc, [&](std::size_t k) {
            const ContactView& c = contacts[k / 2];
            return point_of[k % 2 == 0 ? c.i : c.j];
          }));
  v.array("Int64", "offsets", 1, each<std::int64_t>(nc, [](std::size_t k) { return 2 * (k + 1); }));
  v.line("      </Lines>");
  v.line("    </Piece>");
  v.write(path);
}

void write_walls_vtp(const World& world, const std::string& path) {
  const ParticleStore& p = world.particles();
  const std::vector<Wall>& walls = world.walls();
  // Infinite planes are drawn as squares centred on the particles' bounding
  // box (projected onto the plane), as wide as its diagonal.
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  if (p.size() > 0) {
    lo = hi = p.position[0];
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], p.position[i][a] - p.radius[i]);
        hi[a] = std::max(hi[a], p.position[i][a] + p.radius[i]);
      }
  }
  const Vec3 centre = 0.5 * (lo + hi);
  const double half = std::max(0.5 * norm(hi - lo), 1e-9);
  std::vector<double> xs;
  for (const Wall& w : walls) {
    Vec3 c = w.point, u = w.axis_u, vv = w.axis_v;
    double hu = w.half_u, hv = w.half_v;
    if (w.shape == WallShape::plane) {
      c = centre - dot(centre - w.point, w.normal) * w.normal;
      // Any unit vector across the normal, then the third one.
      const Vec3 t = std::abs(w.normal.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
      u = cross(w.normal, t);
      u = u * (1.0 / norm(u));
      vv = cross(w.normal, u);
      hu = hv = half;
    }
    for (const Vec3& q :
         {c - hu * u - hv * vv, c + hu * u - hv * vv, c + hu * u + hv * vv, c - hu * u + hv * vv})
      xs.insert(xs.end(), {q.x, q.y, q.z});
  }
  const std::size_t nw = walls.size();
  XmlVtk v("PolyData");
  v.line(fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" "
                     "NumberOfStrips=\"0\" NumberOfPolys=\"{}\">",
                     4 * nw, nw));
  v.line("      <Points>");
  v.array("Float64", "Points", 3, xs);
  v.line("      </Points>");
  v.line("      <CellData Scalars=\"wall_index\" Vectors=\"force_N\">");
  v.array("Int32", "wall_index", 1, each<std::int32_t>(nw, [](std::size_t k) { return k; }));
  v.array("Float32", "force_N", 3, xyz32(nw, [&](std::size_t k) { return walls[k].force; }));
  v.array("Float32", "velocity_m_per_s", 3,
          xyz32(nw, [&](std::size_t k) { return walls[k].velocity; }));
  v.array("Int32", "contacts", 1,
          each<std::int32_t>(nw, [&](std::size_t k) { return walls[k].contact_count; }));
  v.line("      </CellData>");
  v.line("      <Polys>");
  v.array("Int64", "connectivity", 1, each<std::int64_t>(4 * nw, [](std::size_t k) { return k; }));
  v.array("Int64", "offsets", 1, each<std::int64_t>(nw, [](std::size_t k) { return 4 * (k + 1); }));
  v.line("      </Polys>");
  v.line("    </Piece>");
  v.write(path);
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
  std::string s = "<?xml version=\"1.0\"?>\n";
  s += "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n";
  s += "  <Collection>\n";
  for (const auto& [t, f] : entries_)
    s += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t,
                     f);
  s += "  </Collection>\n</VTKFile>\n";
  replace_text_file(path_, s);
}

} // namespace centridem
