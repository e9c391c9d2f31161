#include "app/cli.hpp"

#include "app/jobs.hpp"
#include "io/scenario.hpp"   // did_you_mean
#include "physics/lanes.hpp" // ContactLanes

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <omp.h>
#include <sched.h>
#include <sstream>
#include <string_view>
#include <unistd.h>

#ifndef CENTRIDEM_VERSION
#define CENTRIDEM_VERSION "unknown"
#endif
#ifndef CENTRIDEM_BUILD_TYPE
#define CENTRIDEM_BUILD_TYPE "unknown build"
#endif

namespace centridem::cli {

CLI::Validator whole_number(long lo, long hi) {
  const std::string allowed = fmt::format("a whole number from {} to {}", lo, hi);
  return CLI::Validator(
      [lo, hi, allowed](std::string& s) -> std::string {
        long v = 0;
        const char* end = s.data() + s.size();
        const auto [p, ec] = std::from_chars(s.data(), end, v);
        if (ec != std::errc() || p != end || v < lo || v > hi)
          return fmt::format("{} is not allowed: {}", s.empty() ? "\"\"" : s, allowed);
        return {};
      },
      allowed);
}

CLI::Validator positive_number(double hi) {
  const std::string allowed =
      hi > 0 ? fmt::format("a number > 0 and <= {:g}", hi) : std::string("a number > 0");
  return CLI::Validator(
      [hi, allowed](std::string& s) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        const bool ok = !s.empty() && end == s.c_str() + s.size() && errno == 0 &&
                        std::isfinite(v) && v > 0 && (hi <= 0 || v <= hi);
        return ok ? std::string()
                  : fmt::format("{} is not allowed: {}", s.empty() ? "\"\"" : s, allowed);
      },
      allowed);
}

CLI::Validator not_a_flag() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        // "--name" or "-x"; negative numbers ("-1", "-inf") are values.
        const bool flag =
            (s.size() > 2 && s.starts_with("--")) ||
            (s.size() == 2 && s[0] == '-' && std::isalpha(static_cast<unsigned char>(s[1])));
        return flag ? fmt::format("\"{}\" is a flag, not a value: give the value right after the "
                                  "option",
                                  s)
                    : std::string();
      },
      "");
}

CLI::Option* add_threads_option(CLI::App& cmd, int& threads, const std::string& what) {
  return cmd.add_option("--threads", threads, what)->check(whole_number(0, kMaxThreads));
}

CLI::Option* add_jobs_option(CLI::App& cmd, int& jobs, const std::string& what) {
  return cmd.add_option("--jobs", jobs, what)->check(whole_number(1, kMaxJobs));
}

CLI::Option* add_set_option(CLI::App& cmd, std::vector<std::string>& set) {
  return cmd.add_option("--set", set,
                        "override a scenario key, KEY=VALUE in TOML syntax (repeatable), e.g. "
                        "--set contact.ball_ball.friction=0.3; checked like the file's keys and "
                        "recorded in the resolved scenario");
}

CLI::Option* add_check_flag(CLI::App& cmd, bool& check) {
  return cmd.add_flag("--check", check,
                      "check the scenario and the flags, print the resolved scenario (TOML) and "
                      "stop without running");
}

void run_subcommand(const std::function<int()>& work, const std::function<void()>& on_interrupt) {
  int rc = 0;
  try {
    rc = work();
  } catch (...) {
    rc = report_current_exception("");
    if (rc > 128 && on_interrupt) on_interrupt();
  }
  if (rc != 0) {
    std::fflush(stdout);
    std::fflush(stderr);
    std::exit(rc);
  }
}

namespace {

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  std::sort(names.begin(), names.end());
  return names;
}

std::string listed(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return s;
}

std::string nearest(std::string_view word, const std::vector<std::string>& names) {
  std::vector<std::string_view> v(names.begin(), names.end());
  return did_you_mean(word, v);
}

// The subcommand that was being parsed, if any.
const CLI::App* chosen(const CLI::App* app) {
  for (const CLI::App* sub : app->get_subcommands())
    if (sub) return sub;
  return nullptr;
}

// "--thread": "; did you mean --threads?" among the subcommand's long flags.
std::string flag_hint(const CLI::App* sub, std::string_view arg) {
  if (!sub || !arg.starts_with("--")) return {};
  std::string name(arg.substr(2));
  if (const auto eq = name.find('='); eq != std::string::npos) name.resize(eq);
  std::vector<std::string> flags;
  for (const CLI::Option* opt : sub->get_options())
    for (const std::string& l : opt->get_lnames()) flags.push_back(l);
  const std::string best = nearest(name, flags);
  return best.empty() ? std::string() : "; did you mean --" + best + "?";
}

} // namespace

void set_error_messages(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    for (CLI::Option* opt : sub->get_options())
      if (opt->get_items_expected_max() > 0) opt->check(not_a_flag());
  app.failure_message([](const CLI::App* top, const CLI::Error& e) -> std::string {
    const CLI::App* sub = chosen(top);
    const std::string help =
        sub ? fmt::format("`centridem {} --help` lists its options", sub->get_name())
            : std::string("`centridem --help` lists the subcommands");
    std::string what = e.what();
    if (e.get_name() == "RequiredError" && what.find("subcommand") != std::string::npos && !sub)
      return fmt::format("centridem: error: give a subcommand: {} ({})\n",
                         listed(subcommand_names(*top)), help);
    if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
      // "The following arguments were not expected: 1 --thread" (CLI11 lists
      // them last first): back in the order typed, the first flag hinted at.
      const auto colon = what.find(": ");
      std::vector<std::string> words;
      std::istringstream in(colon == std::string::npos ? what : what.substr(colon + 2));
      for (std::string w; in >> w;) words.insert(words.begin(), w);
      std::string typed, flag;
      for (const std::string& w : words) {
        typed += (typed.empty() ? "" : " ") + w;
        if (flag.empty() && w.starts_with("-")) flag = w;
      }
      return fmt::format("centridem: error: \"{}\" not expected here{} ({})\n", typed,
                         flag_hint(sub, flag), help);
    }
    return fmt::format("centridem: error: {} ({})\n", what, help);
  });
}

int check_subcommand(const CLI::App& app, int argc, char** argv) {
  if (argc < 2) return 0;
  const std::string_view word = argv[1];
  if (word.empty() || word.front() == '-') return 0;
  const std::vector<std::string> names = subcommand_names(app);
  for (const std::string& n : names)
    if (n == word) return 0;
  const std::string best = nearest(word, names);
  fmt::print(stderr, "centridem: error: unknown subcommand \"{}\"{}; the subcommands are {}\n",
             word, best.empty() ? "" : " (did you mean \"" + best + "\"?)", listed(names));
  return 2;
}

namespace {

// Other runnable tasks right now, or -1 if unknown (no /proc/loadavg). The
// short spin is only for an otherwise idle machine: 0.
int other_runnable_tasks() {
  // "0.52 0.58 0.59 1/123 4567": the fourth field is runnable/total tasks,
  // this process (reading the file) among the runnable ones. The least of
  // ten looks 1 ms apart: a busy job is runnable in all of them, a passing
  // task (a shell, a kernel thread) not.
  int least = -1;
  for (int k = 0; k < 10; ++k) {
    if (k > 0) ::usleep(1000);
    std::FILE* f = std::fopen("/proc/loadavg", "r");
    if (f == nullptr) return -1;
    double l1 = 0, l5 = 0, l15 = 0;
    int running = 0, total = 0;
    const int got = std::fscanf(f, "%lf %lf %lf %d/%d", &l1, &l5, &l15, &running, &total);
    std::fclose(f);
    if (got != 5 || running < 1) return -1;
    least = least < 0 ? running - 1 : std::min(least, running - 1);
    if (least == 0) break;
  }
  return least;
}

// When OMP_PROC_BIND or OMP_PLACES asks for binding, libgomp binds this
// (initial) thread to the first place as the program loads, and that one-place
// CPU mask outlives execv: the restarted libgomp would find the other places
// without a usable CPU, drop them, and run every thread on one CPU (half speed
// on two cores, found 2026-12-07). So the mask goes back to the CPUs of all
// the places first. Without binding there are no places and nothing changes.
void restore_cpus_of_all_places() {
  const int places = omp_get_num_places();
  if (places < 2) return;
  cpu_set_t all;
  CPU_ZERO(&all);
  for (int p = 0; p < places; ++p) {
    std::vector<int> ids(static_cast<std::size_t>(omp_get_place_num_procs(p)));
    omp_get_place_proc_ids(p, ids.data());
    for (const int id : ids)
      if (id >= 0 && id < CPU_SETSIZE) CPU_SET(id, &all);
  }
  ::sched_setaffinity(0, sizeof all, &all); // on failure the restart keeps one place
}

} // namespace

void choose_openmp_wait(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr) return;
  // Passive with an explicit spin count: libgomp spins that many times, then
  // sleeps (and spins not at all when it runs more threads than CPUs).
  if (other_runnable_tasks() == 0 && ::setenv("GOMP_SPINCOUNT", kShortSpinCount, 1) != 0) return;
  if (::setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  restore_cpus_of_all_places();
  ::execv("/proc/self/exe", argv);
  // Not restarted (no /proc): go on with OpenMP's default policy.
}

std::string openmp_wait_in_use() {
  std::string out;
  for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"})
    if (const char* v = std::getenv(name))
      out += (out.empty() ? "" : " ") + std::string(name) + "=" + v;
  return out.empty() ? "libgomp default" : out;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    const auto first = line.find_first_not_of(" \t", colon == std::string::npos ? 0 : colon + 1);
    if (colon != std::string::npos && first != std::string::npos) return line.substr(first);
  }
  return "unknown";
}

std::string simd_in_use() {
  return fmt::format("{}, {} doubles", ContactLanes::arch_type::name(), ContactLanes::size);
}

void print_warnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) fmt::print(stderr, "centridem: warning: {}\n", w);
  std::fflush(stderr);
}

std::string version_string() {
  return fmt::format("centridem {} ({}, {} {})", CENTRIDEM_VERSION, CENTRIDEM_BUILD_TYPE,
#if defined(__clang__)
                     "Clang",
#else
                     "GCC",
#endif
                     __VERSION__);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 120) return fmt::format("{:.0f} s", s);
  if (s < 7200) return fmt::format("{:.1f} min", s / 60);
  return fmt::format("{:.1f} h", s / 3600);
}

} // namespace centridem::cli
