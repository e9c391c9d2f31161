// `centridem shear --report DIR`: the summary and plots of a run folder as it
// is now, with a finished pressure (in the fits) and an unfinished one (its
// curve so far, read from the CSV the running test rewrites; not in the
// fits), and a clear exit-2 error naming the line of a damaged CSV.
#include "scenario_fixtures.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

int run(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> v;
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

// A reduced test (tests/scenario_fixtures.hpp): the CI box, one pressure,
// sheared 0.15 mm, a few seconds.
using centridem::testutil::kSmallShearBox;

// A fresh folder under the temporary directory holding kSmallShearBox as
// scenario_in.toml.
fs::path fresh_dir_with_scenario(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scenario_in.toml") << kSmallShearBox;
  return dir;
}

} // namespace

TEST(ShearReport, FinishedAndUnfinishedRunsAreReportedAndABadCsvLineIsNamed) {
  const fs::path dir = fresh_dir_with_scenario("centridem_shear_report_test");
  const fs::path out = dir / "run";
  const std::string bin = CENTRIDEM_BINARY;
  ASSERT_EQ(run(bin + " shear " + (dir / "scenario_in.toml").string() + " --out " + out.string() +
                " > " + (dir / "run.log").string() + " 2>&1"),
            0)
      << slurp(dir / "run.log");
  ASSERT_TRUE(fs::exists(out / "shear_100kPa.json"));

  // A second pressure still running: the first half of a curve, no result yet.
  const std::vector<std::string> rows = lines_of(out / "shear_100kPa.csv");
  ASSERT_GT(rows.size(), 6u);
  const std::size_t keep = rows.size() / 2;
  {
    std::ofstream csv(out / "shear_150kPa.csv");
    for (std::size_t k = 0; k < keep; ++k) csv << rows[k] << "\n";
    std::ofstream(out / "pressures.json") << R"({"normal_stresses_Pa": [100000.0, 150000.0]})";
  }
  const double last_displacement = [&] {
    std::stringstream r(rows[keep - 1]);
    std::string f;
    for (int k = 0; k < 3; ++k) std::getline(r, f, ',');
    return std::stod(f);
  }();
  fs::remove(out / "summary.json");
  fs::remove(out / "shear_curves.png");

  ASSERT_EQ(run(bin + " shear --report " + out.string() + " > " + (dir / "report.log").string() +
                " 2>&1"),
            0)
      << slurp(dir / "report.log");
  std::ifstream in(out / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  ASSERT_EQ(s["runs"].size(), 1u); // only the finished pressure is in the results and fits
  EXPECT_DOUBLE_EQ(s["runs"][0]["normal_stress_target_Pa"].get<double>(), 100e3);
  ASSERT_EQ(s["unfinished_Pa"].size(), 1u);
  EXPECT_DOUBLE_EQ(s["unfinished_Pa"][0].get<double>(), 150e3);
  EXPECT_NEAR(s["unfinished_shear_displacement_m"][0].get<double>(), last_displacement,
              1e-9 * last_displacement);
  EXPECT_TRUE(fs::exists(out / "shear_curves.png"));
  EXPECT_NE(slurp(dir / "report.log").find("150 kPa unfinished"), std::string::npos);

  // A damaged number on the CSV's third line: exit 2, the file and line named.
  {
    std::ofstream csv(out / "shear_150kPa.csv");
    for (std::size_t k = 0; k < keep; ++k) csv << (k == 2 ? "1,2,abc,4,5,6,7,8" : rows[k]) << "\n";
  }
  EXPECT_EQ(
      run(bin + " shear --report " + out.string() + " > " + (dir / "bad.log").string() + " 2>&1"),
      2);
  const std::string bad = slurp(dir / "bad.log");
  EXPECT_NE(bad.find("shear_150kPa.csv line 3 column 3"), std::string::npos) << bad;
  EXPECT_NE(bad.find("abc"), std::string::npos) << bad;
  fs::remove_all(dir);
}

// Pressures run in the order given (here the higher first), but the summary,
// its table and the fits list them by rising normal stress. A pressure given
// twice is refused before anything runs: both runs would write shear_100kPa.*.
TEST(ShearReport, RunsAreListedByRisingPressureAndAPressureGivenTwiceIsRefused) {
  const fs::path dir = fresh_dir_with_scenario("centridem_shear_order_test");
  const fs::path out = dir / "run";
  const std::string bin = CENTRIDEM_BINARY;
  const std::string scen = (dir / "scenario_in.toml").string();
  ASSERT_EQ(run(bin + " shear " + scen + " --pressure 150 --pressure 100 --out " + out.string() +
                " > " + (dir / "run.log").string() + " 2>&1"),
            0)
      << slurp(dir / "run.log");
  const nlohmann::json order = nlohmann::json::parse(slurp(out / "pressures.json"));
  EXPECT_EQ(order["normal_stresses_Pa"], nlohmann::json({150e3, 100e3})) << "the run order";
  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  ASSERT_EQ(s["runs"].size(), 2u);
  EXPECT_DOUBLE_EQ(s["runs"][0]["normal_stress_target_Pa"].get<double>(), 100e3);
  EXPECT_DOUBLE_EQ(s["runs"][1]["normal_stress_target_Pa"].get<double>(), 150e3);
  EXPECT_EQ(s["runs"][0]["curve_csv"], "shear_100kPa.csv");
  const std::string log = slurp(dir / "run.log");
  const auto table = log.find("phi_peak"); // the summary table's header
  ASSERT_NE(table, std::string::npos) << log;
  const auto row100 = log.find("  100 kPa", table), row150 = log.find("  150 kPa", table);
  ASSERT_NE(row100, std::string::npos) << log;
  ASSERT_NE(row150, std::string::npos) << log;
  EXPECT_LT(row100, row150) << "the table reads upwards\n" << log;

  const fs::path out2 = dir / "twice";
  EXPECT_EQ(run(bin + " shear " + scen + " --pressure 100 --pressure 100 --out " + out2.string() +
                " > " + (dir / "twice.log").string() + " 2>&1"),
            2);
  const std::string twice = slurp(dir / "twice.log");
  EXPECT_NE(twice.find("--pressure = 100 kPa (given twice)"), std::string::npos) << twice;
  EXPECT_FALSE(fs::exists(out2 / "pressures.json")) << "nothing may run";
  fs::remove_all(dir);
}
