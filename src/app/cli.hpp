// Command-line conventions every subcommand shares: flag checks whose messages
// read as people write ranges, `--set` and `--check`, the error reporting of a
// subcommand's callback, and the process set-up before OpenMP starts.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
class Validator;
} // namespace CLI

namespace centridem::cli {

// The most threads per process and the most child processes one command
// takes: far above any machine this runs on, low enough that a typo (a count
// meant for particles) is refused instead of starting a million threads.
inline constexpr long kMaxThreads = 1024;
inline constexpr long kMaxJobs = 256;

// A whole number in [lo, hi]: "--threads: -1 is not allowed: a whole number
// from 0 to 1024".
CLI::Validator whole_number(long lo, long hi);
// A finite number > 0 (and <= hi): "--progress: nan is not allowed: a number > 0".
CLI::Validator positive_number(double hi = 0);

// Refuses a value that is a flag ("--out --threads 2": --out would take
// "--threads" as its folder and "2" would be left over): added to every
// option that takes a value by set_error_messages.
CLI::Validator not_a_flag();

// `--threads` (0 = the OpenMP default) and `--jobs` with those checks.
CLI::Option* add_threads_option(CLI::App& cmd, int& threads, const std::string& what);
CLI::Option* add_jobs_option(CLI::App& cmd, int& jobs, const std::string& what);
// `--set KEY=VALUE` (repeatable; TOML value) and `--check`.
CLI::Option* add_set_option(CLI::App& cmd, std::vector<std::string>& set);
CLI::Option* add_check_flag(CLI::App& cmd, bool& check);

// The subcommand's work with its exit code: 0, or the code of the exception
// it threw (report_current_exception: 2 bad input, 3 unstable, 128 + signal);
// `on_interrupt` prints how to continue. Exits the process on a non-zero code.
void run_subcommand(const std::function<int()>& work,
                    const std::function<void()>& on_interrupt = {});

// Messages for the command line's own errors (unknown subcommand or flag with
// did-you-mean, a value out of range, a flag where a value belongs),
// "centridem: error: ..." and exit 2. Call after every option is added.
void set_error_messages(CLI::App& app);
// Refuses an unknown subcommand (argv[1]) with the nearest one; returns the
// exit code (2) or 0 when argv[1] is a subcommand, a flag or absent.
int check_subcommand(const CLI::App& app, int argc, char** argv);

// How OpenMP's idle threads wait between the parallel regions of a step.
// Spinning long (libgomp's default, about 3 ms) makes a team beside another
// job on the same cores run many times slower; sleeping at once (passive)
// costs a wake-up through the kernel at every region, which made 2 threads
// 2.6x slower than a short spin on a 2,025-sphere column and 10 % slower on
// the 30,000-sphere bench on an idle machine (docs/results/bench.md,
// 2026-12-04). So: a short spin (GOMP_SPINCOUNT kShortSpinCount, tens of
// microseconds) then sleep when no other task is runnable as the program
// starts, and passive otherwise. libgomp reads its environment when the
// program loads, so this sets it and starts the program again (once); a
// user's own OMP_WAIT_POLICY or GOMP_SPINCOUNT is kept.
inline constexpr const char* kShortSpinCount = "3000";
void choose_openmp_wait(char** argv);
// The wait in use, for reports: "OMP_WAIT_POLICY=passive GOMP_SPINCOUNT=3000", or
// "libgomp default" when neither is set.
std::string openmp_wait_in_use();
// The CPU, for reports that give speeds: the "model name" of /proc/cpuinfo's
// first processor ("unknown" where there is none). A speed, and a ratio to
// another code's, depends on it (docs/results/bench.md: 1.86x LIGGGHTS on an
// AMD EPYC, 1.61x on an Intel Xeon, the same source the same day).
std::string cpu_model();
// The lanes the contact law runs in, for the same reports: "avx512bw, 8 doubles".
std::string simd_in_use();

// Prints each "centridem: warning: ..." line to stderr (a scenario's
// plausibility warnings: the run goes on).
void print_warnings(const std::vector<std::string>& warnings);

// Wall-clock seconds since t0, and a duration for progress lines and
// summaries: "45 s", "12.5 min", "3.2 h" ("?" when unknown or negative).
double seconds_since(std::chrono::steady_clock::time_point t0);
std::string format_duration(double seconds);

// "centridem 0.1.0 (Release, GCC 12.2.0)".
std::string version_string();

} // namespace centridem::cli
