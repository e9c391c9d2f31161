// Running the `centridem` program from a test: start it with arguments, its
// stdout and stderr into one file, wait for it with a time limit, and read
// what it wrote. Used by the tests of the command line (exit codes, messages,
// kill-and-resume, fuzzed flags).
#pragma once

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace centridem::testutil {

namespace fs = std::filesystem;

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Child {
  pid_t pid = -1;
  fs::path log;
};

// Starts `centridem ARGS` (ARGS[0] is the subcommand) with stdout and stderr
// into `log`, one OpenMP thread unless the scenario says otherwise. `env`:
// "NAME=VALUE" sets a variable for the child, "NAME" removes it.
inline Child start_centridem(const std::vector<std::string>& args, const fs::path& log,
                             const std::vector<std::string>& env = {}) {
  Child c;
  c.log = log;
  std::fflush(stdout);
  std::fflush(stderr);
  c.pid = ::fork();
  if (c.pid == 0) {
    std::FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (f) ::dup2(::fileno(stdout), 2);
    std::vector<std::string> all = {CENTRIDEM_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::setenv("OMP_NUM_THREADS", "1", 1);
    for (const std::string& e : env) {
      const auto eq = e.find('=');
      if (eq == std::string::npos)
        ::unsetenv(e.c_str());
      else
        ::setenv(e.substr(0, eq).c_str(), e.substr(eq + 1).c_str(), 1);
    }
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return c;
}

// The exit code, or 128 + the signal that ended it. With timeout_s > 0, a
// child still running after that long is killed and -1 is returned (a hang).
inline int wait_for(const Child& c, double timeout_s = 0) {
  int status = 0;
  if (timeout_s <= 0) {
    ::waitpid(c.pid, &status, 0);
  } else {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    for (;;) {
      const pid_t r = ::waitpid(c.pid, &status, WNOHANG);
      if (r == c.pid) break;
      if (std::chrono::steady_clock::now() > end) {
        ::kill(c.pid, SIGKILL);
        ::waitpid(c.pid, &status, 0);
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

struct CliRun {
  int code = -1; // exit code; -1: killed at the time limit
  std::string output;
};

// Runs `centridem ARGS` to its end (or the time limit): exit code and output.
inline CliRun run_centridem(const std::vector<std::string>& args, const fs::path& log,
                            double timeout_s = 0, const std::vector<std::string>& env = {}) {
  CliRun r;
  r.code = wait_for(start_centridem(args, log, env), timeout_s);
  r.output = slurp(log);
  return r;
}

// A fresh, empty folder under the temporary directory, removed at the end of
// the scope.
class TempDir {
public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& s) const { return path_ / s; }

private:
  fs::path path_;
};

} // namespace centridem::testutil
