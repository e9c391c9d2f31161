// Reading back centridem's ParaView files in tests: a minimal XML reader and
// the decoder of VTK's appended, zlib-compressed binary arrays (the layout
// io/vtk.cpp writes: a UInt64 block header, then the compressed blocks).
// VTK's own reader checks the same files in tests/io/test_vtk.cpp.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>
#include <zlib.h>

namespace vtktest {

namespace fs = std::filesystem;

// ---- a minimal XML reader: elements, attributes, text; throws on malformed input
struct Xml {
  std::string name;
  std::map<std::string, std::string> attr;
  std::string text;
  std::vector<std::unique_ptr<Xml>> children;

  const Xml* child(const std::string& n) const {
    for (const auto& c : children)
      if (c->name == n) return c.get();
    return nullptr;
  }
  void find_all(const std::string& n, std::vector<const Xml*>& out) const {
    if (name == n) out.push_back(this);
    for (const auto& c : children) c->find_all(n, out);
  }
};

class XmlParser {
public:
  explicit XmlParser(std::string s) : s_(std::move(s)) {}
  std::unique_ptr<Xml> document() {
    skip_space();
    if (s_.compare(i_, 5, "<?xml") == 0) i_ = s_.find("?>", i_) + 2;
    skip_space();
    auto root = element();
    skip_space();
    if (i_ != s_.size()) throw std::runtime_error("content after the root element");
    return root;
  }

private:
  void skip_space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  std::string ident() {
    const std::size_t b = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_'))
      ++i_;
    if (b == i_) throw std::runtime_error(fmt::format("name expected at {}", b));
    return s_.substr(b, i_ - b);
  }
  void expect(char c) {
    if (i_ >= s_.size() || s_[i_] != c)
      throw std::runtime_error(fmt::format("'{}' expected at {}", c, i_));
    ++i_;
  }
  std::unique_ptr<Xml> element() {
    auto e = std::make_unique<Xml>();
    expect('<');
    e->name = ident();
    for (;;) {
      skip_space();
      if (s_.compare(i_, 2, "/>") == 0) {
        i_ += 2;
        return e;
      }
      if (s_[i_] == '>') {
        ++i_;
        break;
      }
      const std::string a = ident();
      expect('=');
      expect('"');
      const std::size_t end = s_.find('"', i_);
      if (end == std::string::npos) throw std::runtime_error("unterminated attribute");
      if (!e->attr.emplace(a, s_.substr(i_, end - i_)).second)
        throw std::runtime_error("duplicate attribute " + a);
      i_ = end + 1;
    }
    for (;;) {
      const std::size_t lt = s_.find('<', i_);
      if (lt == std::string::npos) throw std::runtime_error("unclosed <" + e->name + ">");
      e->text += s_.substr(i_, lt - i_);
      i_ = lt;
      if (s_.compare(i_, 2, "</") == 0) {
        i_ += 2;
        if (ident() != e->name) throw std::runtime_error("mismatched </...> for " + e->name);
        skip_space();
        expect('>');
        return e;
      }
      e->children.push_back(element());
    }
  }
  std::string s_;
  std::size_t i_ = 0;
};

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A VTK XML file: its XML (up to the appended data) and the appended bytes.
struct VtkFile {
  std::unique_ptr<Xml> doc;
  std::string appended; // the bytes after AppendedData's '_'
  std::uintmax_t bytes = 0;
};

inline VtkFile read_vtk(const fs::path& p) {
  VtkFile f;
  std::string s = read_file(p);
  f.bytes = s.size();
  const std::size_t a = s.find("<AppendedData");
  if (a == std::string::npos) {
    f.doc = XmlParser(s).document();
    return f;
  }
  const std::size_t u = s.find('_', a);
  const std::size_t close = s.rfind("</AppendedData>");
  if (u == std::string::npos || close == std::string::npos || close < u)
    throw std::runtime_error(p.string() + ": malformed AppendedData");
  f.appended = s.substr(u + 1, close - u - 1);
  // The XML without the binary section.
  f.doc = XmlParser(s.substr(0, a) + "</VTKFile>\n").document();
  return f;
}

template <class T> std::vector<double> as_doubles(const std::string& raw) {
  if (raw.size() % sizeof(T) != 0)
    throw std::runtime_error("array size not a multiple of its type");
  std::vector<double> v(raw.size() / sizeof(T));
  for (std::size_t k = 0; k < v.size(); ++k) {
    T x;
    std::memcpy(&x, raw.data() + k * sizeof(T), sizeof(T));
    v[k] = static_cast<double>(x);
  }
  return v;
}

// The values of one DataArray element (appended and compressed, or ASCII).
inline std::vector<double> values(const VtkFile& f, const Xml& a) {
  if (a.attr.at("format") == "ascii") {
    std::vector<double> v;
    std::istringstream in(a.text);
    double x;
    while (in >> x) v.push_back(x);
    return v;
  }
  if (a.attr.at("format") != "appended") throw std::runtime_error("unknown DataArray format");
  std::size_t at = std::stoull(a.attr.at("offset"));
  auto u64 = [&](std::size_t pos) {
    if (pos + 8 > f.appended.size()) throw std::runtime_error("header beyond the appended data");
    std::uint64_t x;
    std::memcpy(&x, f.appended.data() + pos, 8);
    return x;
  };
  const std::uint64_t blocks = u64(at), block = u64(at + 8), last = u64(at + 16);
  std::size_t data = at + 24 + 8 * blocks;
  std::string raw;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t csize = u64(at + 24 + 8 * b);
    const std::uint64_t usize = (b + 1 == blocks && last != 0) ? last : block;
    std::string out(usize, '\0');
    uLongf len = static_cast<uLongf>(usize);
    if (data + csize > f.appended.size())
      throw std::runtime_error("block beyond the appended data");
    if (uncompress(reinterpret_cast<Bytef*>(out.data()), &len,
                   reinterpret_cast<const Bytef*>(f.appended.data() + data),
                   static_cast<uLong>(csize)) != Z_OK ||
        len != usize)
      throw std::runtime_error("a block does not uncompress to its stated size");
    raw += out;
    data += csize;
  }
  const std::string& t = a.attr.at("type");
  if (t == "Float64") return as_doubles<double>(raw);
  if (t == "Float32") return as_doubles<float>(raw);
  if (t == "Int64") return as_doubles<std::int64_t>(raw);
  if (t == "Int32") return as_doubles<std::int32_t>(raw);
  if (t == "UInt8") return as_doubles<std::uint8_t>(raw);
  throw std::runtime_error("unknown DataArray type " + t);
}

// Every DataArray of the file by name (the last one wins for repeated names).
inline std::map<std::string, std::vector<double>> arrays(const VtkFile& f) {
  std::vector<const Xml*> all;
  f.doc->find_all("DataArray", all);
  std::map<std::string, std::vector<double>> out;
  for (const Xml* a : all) out[a->attr.at("Name")] = values(f, *a);
  return out;
}

} // namespace vtktest
