#include "app/jobs.hpp"

#include "base/errors.hpp"
#include "base/interrupt.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fmt/format.h>
#include <stdexcept>
#include <string>
#include <sys/types.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace centridem {

int report_current_exception(std::string_view tag) {
  try {
    throw;
  } catch (const InputError& e) {
    fmt::print(stderr, "centridem: error: {}{}\n", tag, e.what());
    return 2;
  } catch (const InstabilityError& e) {
    fmt::print(stderr, "centridem: unstable: {}{}\n", tag, e.what());
    return 3;
  } catch (const Interrupted& e) {
    fmt::print(stderr, "centridem: interrupted: {}{}\n", tag, e.what());
    return 128 + e.signal();
  } catch (const std::exception& e) {
    fmt::print(stderr, "centridem: error: {}{}\n", tag, e.what());
    return 1;
  }
}

std::vector<int> run_jobs(std::size_t n, int jobs, const std::function<void(std::size_t)>& task,
                          const std::function<std::string(std::size_t)>& tag) {
  std::vector<int> rc(n, -1);
  if (jobs <= 1) {
    for (std::size_t k = 0; k < n; ++k) {
      if (stop_signal()) break;
      task(k);
      rc[k] = 0;
    }
    return rc;
  }
  std::fflush(stdout);
  std::fflush(stderr);
  std::vector<std::pair<pid_t, std::size_t>> running;
  std::size_t next = 0;
  int forwarded = 0;
  while ((next < n && !stop_signal()) || !running.empty()) {
    if (next < n && !stop_signal() && static_cast<int>(running.size()) < jobs) {
      const std::size_t k = next++;
      const pid_t pid = ::fork();
      if (pid < 0) throw std::runtime_error("fork failed");
      if (pid == 0) {
        int code = 0;
        try {
          task(k);
        } catch (...) {
          code = report_current_exception(tag(k) + ": ");
        }
        std::fflush(stdout);
        std::fflush(stderr);
        ::_exit(code);
      }
      running.emplace_back(pid, k);
      continue;
    }
    // Poll, so that a stop request reaches the children promptly.
    if (const int sig = stop_signal(); sig && forwarded != sig) {
      for (const auto& [pid, k] : running) ::kill(pid, sig);
      forwarded = sig;
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, WNOHANG);
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    if (pid < 0) throw std::runtime_error("waitpid failed");
    auto it =
        std::find_if(running.begin(), running.end(), [&](const auto& r) { return r.first == pid; });
    if (it == running.end()) continue;
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (code != 0)
      fmt::print(stderr, "centridem: {} ended with {}\n", tag(it->second),
                 WIFEXITED(status) ? fmt::format("exit code {}", code)
                                   : fmt::format("signal {}", WTERMSIG(status)));
    rc[it->second] = code;
    running.erase(it);
  }
  return rc;
}

} // namespace centridem
