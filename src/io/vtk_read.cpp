#include "io/vtk_read.hpp"

#include "base/errors.hpp"

#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <regex>
#include <sstream>
#include <zlib.h>

namespace centridem {

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "(unreadable)", "a ParaView file written by centridem");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The value of attribute `name` in the tag text, or "".
std::string attribute(const std::string& tag, const std::string& name) {
  const std::regex re("\\b" + name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(tag, m, re) ? m[1].str() : std::string();
}

// An attribute's whole number; 0 when absent or not a number.
std::size_t whole_number(const std::string& text) {
  try {
    return text.empty() ? 0 : static_cast<std::size_t>(std::stoull(text));
  } catch (const std::exception&) {
    return 0;
  }
}

template <class T> void append_as_doubles(const std::string& raw, std::vector<double>& out) {
  const std::size_t n = raw.size() / sizeof(T);
  for (std::size_t k = 0; k < n; ++k) {
    T x;
    std::memcpy(&x, raw.data() + k * sizeof(T), sizeof(T));
    out.push_back(static_cast<double>(x));
  }
}

std::vector<double> decode(const std::string& type, const std::string& raw,
                           const std::string& where) {
  std::vector<double> v;
  if (type == "Float64")
    append_as_doubles<double>(raw, v);
  else if (type == "Float32")
    append_as_doubles<float>(raw, v);
  else if (type == "Int64")
    append_as_doubles<std::int64_t>(raw, v);
  else if (type == "Int32")
    append_as_doubles<std::int32_t>(raw, v);
  else if (type == "UInt8")
    append_as_doubles<std::uint8_t>(raw, v);
  else
    throw InputError(where, type,
                     "a DataArray type centridem writes (Float64, Float32, Int64, "
                     "Int32, UInt8)");
  return v;
}

// One appended array at `offset`: UInt64 header (blocks, block size, last
// partial block size, compressed sizes), then zlib blocks.
std::string uncompress_array(const std::string& data, std::size_t offset,
                             const std::string& where) {
  auto u64 = [&](std::size_t pos) {
    if (pos + 8 > data.size()) throw InputError(where, "(truncated)", "a complete appended array");
    std::uint64_t x;
    std::memcpy(&x, data.data() + pos, 8);
    return x;
  };
  const std::uint64_t blocks = u64(offset), block = u64(offset + 8), last = u64(offset + 16);
  std::size_t at = offset + 24 + 8 * blocks;
  std::string raw;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t csize = u64(offset + 24 + 8 * b);
    const std::uint64_t usize = (b + 1 == blocks && last != 0) ? last : block;
    if (at + csize > data.size() || usize > (1u << 30))
      throw InputError(where, "(truncated)", "a complete appended array");
    std::string out(usize, '\0');
    uLongf len = static_cast<uLongf>(usize);
    if (uncompress(reinterpret_cast<Bytef*>(out.data()), &len,
                   reinterpret_cast<const Bytef*>(data.data() + at),
                   static_cast<uLong>(csize)) != Z_OK ||
        len != usize)
      throw InputError(where, "(corrupt)", "zlib blocks of the stated sizes");
    raw += out;
    at += csize;
  }
  return raw;
}

} // namespace

const std::vector<double>& VtuArrays::get(const std::string& name, std::size_t components) const {
  const auto it = arrays.find(name);
  if (it == arrays.end())
    throw InputError(path, "(no array " + name + ")",
                     "a particle frame with the array " + name + " (centridem writes it)");
  if (it->second.size() != components * points)
    throw InputError(path + " array " + name, fmt::format("{} values", it->second.size()),
                     fmt::format("{} x {} points", components, points));
  return it->second;
}

VtuArrays read_vtu(const std::string& path) {
  const std::string s = slurp(path);
  VtuArrays out;
  out.path = path;
  const std::size_t appended = s.find("<AppendedData");
  const std::string head = s.substr(0, appended);
  const std::size_t piece = head.find("<Piece");
  if (piece == std::string::npos)
    throw InputError(path, "(no <Piece>)", "a VTK XML UnstructuredGrid written by centridem");
  out.points =
      whole_number(attribute(head.substr(piece, head.find('>', piece) - piece), "NumberOfPoints"));
  std::string data;
  if (appended != std::string::npos) {
    const std::size_t u = s.find('_', appended);
    const std::size_t end = s.rfind("</AppendedData>");
    if (u == std::string::npos || end == std::string::npos || end < u)
      throw InputError(path, "(malformed AppendedData)", "a complete VTK XML file");
    data = s.substr(u + 1, end - u - 1);
  }
  for (std::size_t at = head.find("<DataArray"); at != std::string::npos;
       at = head.find("<DataArray", at + 1)) {
    const std::size_t close = head.find('>', at);
    const std::string tag = head.substr(at, close - at);
    const std::string name = attribute(tag, "Name"), type = attribute(tag, "type");
    const std::string format = attribute(tag, "format");
    const std::string where = path + " array " + name;
    if (format == "appended") {
      out.arrays[name] = decode(
          type, uncompress_array(data, whole_number(attribute(tag, "offset")), where), where);
    } else if (format == "ascii") {
      std::vector<double> v;
      std::istringstream in(head.substr(close + 1, head.find("</DataArray>", close) - close - 1));
      for (double x; in >> x;) v.push_back(x);
      out.arrays[name] = std::move(v);
    } else {
      throw InputError(where, format, "format ascii or appended");
    }
  }
  return out;
}

std::vector<std::pair<double, std::string>> read_pvd(const std::string& path) {
  const std::string s = slurp(path);
  std::vector<std::pair<double, std::string>> out;
  for (std::size_t at = s.find("<DataSet"); at != std::string::npos;
       at = s.find("<DataSet", at + 1)) {
    const std::string tag = s.substr(at, s.find('>', at) - at);
    out.emplace_back(std::stod(attribute(tag, "timestep")), attribute(tag, "file"));
  }
  return out;
}

} // namespace centridem
