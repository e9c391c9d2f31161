// The docs against the program: every `--flag` written in README.md, docs/*.md
// (the results excepted) and bench/README.md is a flag of the subcommand the
// line talks about (`centridem SUB ...` on the line, or the last one named in
// its paragraph) or of the page's own subcommand (any, for README.md and
// ARCHITECTURE.md), as --help lists it, or of one of the other tools the docs
// name (cmake, ctest, the peers' script). A renamed or dropped flag fails here.
#include "cli_test_util.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace centridem::testutil;

namespace {

const std::vector<std::string> kSubcommands = {"bench", "run",    "generate", "shear",
                                               "slope", "render", "calibrate"};

// Flags of tools other than centridem that the docs show, by name.
const std::set<std::string> kOtherTools = {
    "--build",             // cmake --build
    "--output-on-failure", // ctest
    "--repeat",
    "--procs",
    "--codes",
    "--workdir", // bench/run_peers.sh
    "--rounds",
    "--cores",
    "--bin",
    "--packed-steps",
    "--flow-steps", // bench/side_by_side.sh, bench/interleave.sh
};

std::set<std::string> flags_in(const std::string& text) {
  std::set<std::string> out;
  const std::regex flag(R"((^|[^A-Za-z0-9_-])(--[a-z][a-z0-9-]*))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), flag); it != std::sregex_iterator();
       ++it)
    out.insert((*it)[2].str());
  return out;
}

std::map<std::string, std::set<std::string>> help_flags(const fs::path& tmp) {
  std::map<std::string, std::set<std::string>> out;
  const CliRun top = run_centridem({"--help"}, tmp / "help.log");
  EXPECT_EQ(top.code, 0) << top.output;
  for (const std::string& sub : kSubcommands) {
    const CliRun r = run_centridem({sub, "--help"}, tmp / "help.log");
    EXPECT_EQ(r.code, 0) << sub << ": " << r.output;
    out[sub] = flags_in(r.output);
    for (const std::string& f : flags_in(top.output)) out[sub].insert(f);
  }
  return out;
}

} // namespace

TEST(Docs, EveryDocumentedFlagExists) {
  TempDir tmp("centridem_docs_flags");
  const auto help = help_flags(tmp.path());
  std::set<std::string> any;
  for (const auto& [sub, f] : help) any.insert(f.begin(), f.end());
  ASSERT_TRUE(help.at("slope").contains("--search-auto")); // the help was read

  const fs::path root = CENTRIDEM_SOURCE_DIR;
  // Each page and the subcommand it documents ("" = all of them).
  const std::vector<std::pair<fs::path, std::string>> pages = {{"README.md", ""},
                                                               {"docs/ARCHITECTURE.md", ""},
                                                               {"docs/scenario.md", "run"},
                                                               {"docs/shear.md", "shear"},
                                                               {"docs/slope.md", "slope"},
                                                               {"docs/specimens.md", "generate"},
                                                               {"bench/README.md", "bench"},
                                                               {"docs/calibrate.md", "calibrate"}};
  std::vector<std::string> unknown;
  std::size_t checked = 0;
  for (const auto& [page, page_sub] : pages) {
    std::ifstream in(root / page);
    ASSERT_TRUE(in) << page;
    std::string line;
    std::string section_sub; // the subcommand the current paragraph last named
    for (int n = 1; std::getline(in, line); ++n) {
      if (line.starts_with("#") || line.find_first_not_of(" \t") == std::string::npos)
        section_sub.clear();         // a header or a blank line ends the paragraph
      std::string sub = section_sub; // "" = only the page's own
      const std::regex named(R"(centridem\s+([a-z]+))");
      for (auto it = std::sregex_iterator(line.begin(), line.end(), named);
           it != std::sregex_iterator(); ++it)
        if (help.contains((*it)[1].str())) {
          sub = section_sub = (*it)[1].str(); // the first subcommand the line names
          break;
        }
      for (const std::string& f : flags_in(line)) {
        ++checked;
        // The named subcommand's flags, and the page's own (all for an overview page).
        const bool named_has = !sub.empty() && help.at(sub).contains(f);
        const bool page_has = page_sub.empty() ? any.contains(f) : help.at(page_sub).contains(f);
        if (!named_has && !page_has && !kOtherTools.contains(f))
          unknown.push_back(fmt::format("{}:{}: {} is not a flag of centridem {}", page.string(), n,
                                        f, sub.empty() ? page_sub : sub + " or " + page_sub));
      }
    }
  }
  EXPECT_GT(checked, 50u);
  std::string list;
  for (const std::string& u : unknown) list += "\n  " + u;
  EXPECT_TRUE(unknown.empty()) << list;
}
