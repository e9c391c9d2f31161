// Fuzz of the command line (issue 17: "the command-line flags of every subcommand and every
// scenario kind, 1,000 mutations each kind, no crash, no hang, every refusal exit 2 naming what
// was wrong").
//
// Each kind starts from command lines that work: `bench` on a packing of 8 spheres for 2 steps
// (run for real: cheap), and `run`, `generate` (a specimen and a slope foundation), `shear` and
// `slope` on the shipped examples with `--check`, which does every check the command does before
// its work and then stops (their work is minutes to hours; the other tests run it). `--check`
// itself is never mutated away. The first case is the command line as it is (it must be
// accepted); every other case applies 1 or 2 mutations, chosen with a fixed-seed
// std::mt19937_64 through `rng() % n`:
//   - a value replaced by one of: -1, 0, 1e308, nan, inf, "", abc, 1.5, a 20-digit number, a
//     300-character word, a path that does not exist, an existing file where a folder is wanted
//     and the reverse, a scenario of another kind;
//   - a token dropped (a flag loses its value, or a flag or the scenario disappears);
//   - an unknown flag inserted (a misspelt real one, or a made-up one);
//   - a real flag of the subcommand added with a value from the list above (--resume, --jobs,
//     --scale, --g, --search, --schedule, --pressure, ...), or one given twice;
//   - `--set KEY=VALUE` with a real, misspelt or malformed key and a value from the list;
//   - the subcommand misspelt.
// Each case must end in exit 0 (a harmless mutation) or exit 2 with "centridem: error:" and a
// message that names what the mutation changed: the flag, the value, the --set key, the missing
// scenario or the subcommand. Anything else (exit 1, a signal, a sanitizer abort, over
// kHangSeconds) fails the test with the command line.
#include "cli_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using centridem::testutil::run_centridem;
using centridem::testutil::TempDir;

const fs::path kExamples = fs::path(CENTRIDEM_SOURCE_DIR) / "examples";

// The sanitizer build (make test-sanitize) runs a part: each case there is a start of a
// sanitized process (a third of a second each), and the Release build runs them all.
#ifdef CENTRIDEM_SANITIZED_TESTS
constexpr int kCasesPerKind = 50;
#else
constexpr int kCasesPerKind = 1000;
#endif
// A case that takes longer is a hang. Every case is a start-up, a TOML read and checks (or 2
// steps of 8 spheres): well under a second even under the sanitizers.
constexpr double kHangSeconds = 60.0;
constexpr int kMaxReported = 8;

// What a mutated command line is and what a refusal of it must name.
struct Case {
  std::vector<std::string> args;
  std::vector<std::string> hints; // a refusal names at least one of these
};

struct Kind {
  std::string name;
  std::vector<std::string> base;            // args without the subcommand's --check
  bool check = true;                        // append --check (never mutated)
  std::vector<std::string> value_flags;     // the subcommand's flags that take a value
  std::vector<std::string> switches;        // its flags without a value
  std::vector<std::string> set_keys;        // real keys for --set
  std::vector<std::string> other_scenarios; // scenarios of another kind
};

bool is_flag(const std::string& s) {
  return s.size() > 1 && s[0] == '-' && s != "-1" && s != "-inf";
}

class Mutator {
public:
  Mutator(std::uint64_t seed, const TempDir& dir) : rng_(seed) {
    const fs::path file = dir / "a_file.txt";
    std::ofstream(file) << "not a folder\n";
    values_ = {"-1",
               "0",
               "1e308",
               "nan",
               "inf",
               "",
               "abc",
               "1.5",
               "99999999999999999999",
               std::string(300, 'x'),
               (dir / "does_not_exist" / "x").string(),
               file.string(),
               dir.path().string(),
               "=",
               "2"};
  }

  std::size_t pick(std::size_t n) { return static_cast<std::size_t>(rng_() % n); }
  const std::string& value() { return values_[pick(values_.size())]; }

  void mutate(const Kind& k, Case& c) {
    std::vector<std::string>& a = c.args; // a[0] is the subcommand
    switch (pick(8)) {
    case 0: { // replace a value (or the scenario)
      std::vector<std::size_t> slots;
      for (std::size_t i = 1; i < a.size(); ++i)
        if (!is_flag(a[i])) slots.push_back(i);
      if (slots.empty()) break;
      const std::size_t i = slots[pick(slots.size())];
      const std::string v = pick(4) == 0 && !k.other_scenarios.empty()
                                ? k.other_scenarios[pick(k.other_scenarios.size())]
                                : value();
      c.hints.push_back(is_flag(a[i - 1]) ? a[i - 1] : "scenario");
      if (!v.empty()) c.hints.push_back(v);
      a[i] = v;
      break;
    }
    case 1: { // drop a token
      if (a.size() < 2) break;
      const std::size_t i = 1 + pick(a.size() - 1);
      c.hints.push_back(a[i]);
      if (is_flag(a[i - 1])) c.hints.push_back(a[i - 1]);
      if (i + 1 < a.size()) c.hints.push_back(a[i + 1]);
      c.hints.push_back("scenario");
      a.erase(a.begin() + static_cast<long>(i));
      break;
    }
    case 2: { // an unknown flag
      static const std::vector<std::string> unknown = {
          "--bogus", "-x", "--thread", "--outt", "--resum", "--sett", "--", "--g-level"};
      std::string f = unknown[pick(unknown.size())];
      if (!k.value_flags.empty() && pick(2) == 0) {
        f = k.value_flags[pick(k.value_flags.size())];
        f.insert(f.begin() + 2 + static_cast<long>(pick(f.size() - 2)), 'q'); // misspelt
      }
      c.hints.push_back(f);
      a.insert(a.begin() + 1 + static_cast<long>(pick(a.size())), f);
      break;
    }
    case 3:
    case 4: { // a real flag with a value from the list
      if (k.value_flags.empty()) break;
      const std::string f = k.value_flags[pick(k.value_flags.size())];
      const std::string v = value();
      c.hints.push_back(f);
      if (!v.empty()) c.hints.push_back(v);
      a.push_back(f);
      a.push_back(v);
      if (pick(3) == 0) { // a second value (--search, --schedule take two or three)
        a.push_back(value());
        c.hints.push_back(a.back());
      }
      break;
    }
    case 5: { // a switch, or a flag given twice
      if (!k.switches.empty() && pick(2) == 0) {
        const std::string s = k.switches[pick(k.switches.size())];
        c.hints.push_back(s);
        a.push_back(s);
        break;
      }
      for (std::size_t i = 1; i + 1 < a.size(); ++i)
        if (is_flag(a[i]) && !is_flag(a[i + 1])) {
          c.hints.push_back(a[i]);
          a.push_back(a[i]);
          a.push_back(a[i + 1]);
          break;
        }
      break;
    }
    case 6: { // --set KEY=VALUE
      std::string key =
          k.set_keys.empty() ? "simulation.threads" : k.set_keys[pick(k.set_keys.size())];
      switch (pick(5)) {
      case 0:
        key.insert(key.begin() + static_cast<long>(pick(key.size())), 'z');
        break;
      case 1:
        key = std::vector<std::string>{"", "=", "a..b", "[x]", "\"", "x.y.z"}[pick(6)];
        break;
      default:
        break;
      }
      const std::string v = value();
      const std::string kv = pick(6) == 0 ? key : key + "=" + v;
      c.hints.push_back("--set");
      if (!key.empty()) c.hints.push_back(key);
      if (!v.empty()) c.hints.push_back(v);
      a.push_back("--set");
      a.push_back(kv);
      break;
    }
    default: { // the subcommand misspelt
      static const std::vector<std::string> subs = {"slop", "sheer", "runn", "gen",
                                                    "",     "RUN",   "--run"};
      c.hints.push_back("subcommand");
      c.hints.push_back(a[0]);
      a[0] = subs[pick(subs.size())];
      break;
    }
    }
  }

private:
  std::mt19937_64 rng_;
  std::vector<std::string> values_;
};

struct Tally {
  int accepted = 0, refused = 0, bad = 0;
  std::vector<std::string> reports;
};

std::string shown(const std::vector<std::string>& args) {
  std::string s = "centridem";
  for (const std::string& a : args) s += " '" + a + "'";
  return s;
}

Tally fuzz_kind(const Kind& k, std::uint64_t seed) {
  TempDir dir("centridem_fuzz_cli_" + k.name);
  Mutator m(seed, dir);
  Tally t;
  for (int n = 0; n < kCasesPerKind; ++n) {
    Case c;
    c.args = k.base;
    // Case 0 is the command line as it is: it must be accepted (the seed works).
    const int mutations = n == 0 ? 0 : 1 + static_cast<int>(m.pick(2));
    for (int i = 0; i < mutations; ++i) m.mutate(k, c);
    if (k.check) c.args.push_back("--check");
    // OMP_WAIT_POLICY set: no restart of the program for it (tested in test_command_line.cpp).
    const auto r =
        run_centridem(c.args, dir / "log.txt", kHangSeconds, {"OMP_WAIT_POLICY=passive"});
    std::string why;
    if (r.code == 0) {
      ++t.accepted;
      continue;
    }
    if (n == 0) {
      ++t.bad;
      t.reports.push_back(
          shown(c.args) +
          "\n  -> the unmutated command line is refused\n  output: " + r.output.substr(0, 600));
      continue;
    }
    if (r.code == 2) {
      // An empty value is named as "".
      const bool named = std::any_of(c.hints.begin(), c.hints.end(), [&](const std::string& h) {
        return r.output.find(h.empty() ? std::string("\"\"") : h) != std::string::npos;
      });
      if (r.output.find("centridem: error: ") == std::string::npos)
        why = "exit 2 without \"centridem: error: \"";
      else if (!named)
        why = "the refusal names none of: " + [&] {
          std::string s;
          for (const auto& h : c.hints) s += "'" + h.substr(0, 60) + "' ";
          return s;
        }();
      else {
        ++t.refused;
        continue;
      }
    } else {
      why = r.code < 0 ? fmt::format("no end within {} s (a hang)", kHangSeconds)
                       : fmt::format("exit {}", r.code);
    }
    ++t.bad;
    if (static_cast<int>(t.reports.size()) < kMaxReported)
      t.reports.push_back(shown(c.args) + "\n  -> " + why +
                          "\n  output: " + r.output.substr(0, 600));
  }
  fmt::print("{}: {} cases, {} accepted, {} refused with exit 2 and a name, {} bad\n", k.name,
             kCasesPerKind, t.accepted, t.refused, t.bad);
  return t;
}

void expect_clean(const Tally& t, const std::string& kind) {
  EXPECT_EQ(t.bad, 0) << kind << ":\n"
                      << [&] {
                           std::string s;
                           for (const auto& r : t.reports) s += r + "\n";
                           return s;
                         }();
  // The mutations bite, and the seeds work.
  EXPECT_GT(t.refused, kCasesPerKind / 4) << kind;
  EXPECT_GT(t.accepted, 0) << kind;
}

std::string ex(const std::string& rel) {
  return (kExamples / rel).string();
}

} // namespace

TEST(FuzzCommandLine, Bench) {
  TempDir dir("centridem_fuzz_cli_bench_packing");
  {
    std::ofstream p(dir / "p.xyzr");
    for (int i = 0; i < 8; ++i)
      p << fmt::format("{} {} {} 0.0004\n", 0.001 * (1 + i % 2), 0.001 * (1 + (i / 2) % 2),
                       0.001 * (1 + i / 4));
  }
  const Kind k{"bench",
               {"bench", "--packing", (dir / "p.xyzr").string(), "--steps", "2", "--warmup", "0",
                "--threads", "1"},
               false,
               {"--packing", "--steps", "--warmup", "--threads"},
               {"--help"},
               {},
               {ex("demo_settle.toml")}};
  expect_clean(fuzz_kind(k, 0xC11'0001), "bench");
}

TEST(FuzzCommandLine, Run) {
  const Kind k{"run",
               {"run", ex("demo_settle.toml"), "--out", "runs_fuzz/x", "--threads", "1"},
               true,
               {"--out", "--resume", "--threads", "--set"},
               {},
               {"simulation.threads", "simulation.timestep_s", "particles.density_kg_m3",
                "contact.ball_ball.friction", "gravity.g_level", "simulation.local_damping"},
               {ex("shear_small.toml"), ex("demo_slope.toml"), ex("data/column_2k.xyzr")}};
  expect_clean(fuzz_kind(k, 0xC11'0002), "run");
}

TEST(FuzzCommandLine, Generate) {
  const Kind k{
      "generate",
      {"generate", ex("specimens/paper_shear_box.toml"), "--out", "runs_fuzz/x", "--threads", "1"},
      true,
      {"--out", "--threads", "--set", "--scale", "--cache"},
      {},
      {"specimen.seed", "specimen.porosity", "specimen.density_kg_m3",
       "contact.ball_ball.friction"},
      {ex("demo_settle.toml"), ex("demo_slope.toml"), ex("data/hiroshima_sand_gsd.csv")}};
  expect_clean(fuzz_kind(k, 0xC11'0003), "generate");
  // A slope scenario's foundation (--scale and --cache have a meaning there).
  const Kind f{"generate_foundation",
               {"generate", ex("demo_slope.toml"), "--scale", "0.02", "--cache", "runs_fuzz/c"},
               true,
               {"--out", "--threads", "--set", "--scale", "--cache"},
               {},
               {"preparation.compaction_g_level", "slope.size_reduction_factor",
                "specimen.porosity", "preparation.overfill"},
               {ex("shear_small.toml")}};
  expect_clean(fuzz_kind(f, 0xC11'0004), "generate (slope foundation)");
}

TEST(FuzzCommandLine, Shear) {
  const Kind k{
      "shear",
      {"shear", ex("shear_small.toml"), "--out", "runs_fuzz/x", "--jobs", "1", "--pressure", "50",
       "--threads", "1", "--progress", "5"},
      true,
      {"--out", "--resume", "--report", "--jobs", "--pressure", "--progress", "--threads", "--set"},
      {},
      {"shear.normal_stresses_Pa", "shear.shear_rate_m_per_s", "shear.max_shear_displacement_m",
       "contact.ball_ball.friction", "shear.during_shear", "specimen.seed"},
      {ex("demo_settle.toml"), ex("demo_slope.toml")}};
  expect_clean(fuzz_kind(k, 0xC11'0005), "shear");
}

TEST(FuzzCommandLine, Slope) {
  const Kind k{"slope",
               {"slope", ex("demo_slope.toml"), "--out", "runs_fuzz/x", "--g", "20", "--jobs", "1",
                "--threads", "1", "--cache", "runs_fuzz/c", "--progress", "5"},
               true,
               {"--out", "--resume", "--g", "--search", "--schedule", "--set", "--scale",
                "--tolerance", "--jobs", "--threads", "--cache", "--progress"},
               {"--search-auto"},
               {"trial.min_time_s", "trial.max_time_s", "campaign.g_levels",
                "slope.size_reduction_factor", "trial.after_cut", "contact.ball_ball.friction"},
               {ex("demo_settle.toml"), ex("shear_small.toml")}};
  expect_clean(fuzz_kind(k, 0xC11'0006), "slope");
}
