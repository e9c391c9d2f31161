// The layers of src/ (docs/ARCHITECTURE.md "Layers"): every project #include
// in a file of one layer names a header of the same layer or of a layer below
// it. base < physics < engine < io < procedures < app, with no exceptions (the
// scenario readers of shear and slope, which build procedure settings, live in
// procedures/ since 2026-12-02).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {
const std::vector<std::string> kLayers = {"base", "physics", "engine", "io", "procedures", "app"};

int rank_of(const std::string& layer) {
  for (std::size_t k = 0; k < kLayers.size(); ++k)
    if (kLayers[k] == layer) return static_cast<int>(k);
  return -1;
}

// "from -> to" for every project include of src/ that points to a higher layer,
// or to a directory that is not a layer.
std::vector<std::string> violations(const fs::path& src) {
  std::vector<std::string> out;
  const std::regex include(R"(^\s*#\s*include\s+"([a-z_]+)/([^"]+)\")");
  for (const auto& entry : fs::recursive_directory_iterator(src)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = entry.path().extension().string();
    if (ext != ".hpp" && ext != ".cpp") continue;
    const fs::path rel = fs::relative(entry.path(), src);
    const std::string layer = rel.begin()->string();
    const int from = rank_of(layer);
    if (from < 0) {
      out.push_back(rel.generic_string() + " is in no layer");
      continue;
    }
    std::ifstream in(entry.path());
    std::string line;
    std::smatch m;
    while (std::getline(in, line)) {
      if (!std::regex_search(line, m, include)) continue;
      const std::string edge = rel.generic_string() + " -> " + m[1].str() + "/" + m[2].str();
      const int to = rank_of(m[1].str());
      if (to < 0 || to > from) out.push_back(edge);
    }
  }
  return out;
}
} // namespace

TEST(Layers, NoIncludeRunsAgainstTheLayers) {
  const fs::path src = fs::path(CENTRIDEM_SOURCE_DIR) / "src";
  ASSERT_TRUE(fs::is_directory(src)) << src;
  std::string list;
  for (const std::string& v : violations(src)) list += "\n  " + v;
  EXPECT_TRUE(list.empty()) << "includes against the layers "
                            << "(base < physics < engine < io < "
                            << "procedures < app):" << list;
}

// The check itself: a file of physics that includes the engine is caught.
TEST(Layers, AnIncludeOfAHigherLayerIsCaught) {
  const fs::path dir = fs::temp_directory_path() / "centridem_layers_test";
  fs::remove_all(dir);
  fs::create_directories(dir / "physics");
  fs::create_directories(dir / "engine");
  std::ofstream(dir / "physics" / "law.hpp") << "#include \"base/vec3.hpp\"\n"
                                             << "#include \"engine/world.hpp\"\n";
  std::ofstream(dir / "engine" / "world.hpp") << "#include \"physics/law.hpp\"\n";
  const auto v = violations(dir);
  fs::remove_all(dir);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0], "physics/law.hpp -> engine/world.hpp");
}
