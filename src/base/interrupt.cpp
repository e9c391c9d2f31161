#include "base/interrupt.hpp"

#include <atomic>
#include <csignal>
#include <ctime>

namespace centridem {

namespace {
std::atomic<int> g_stop{0};
std::atomic<long long> g_first_ns{0}; // when the stop request arrived (CLOCK_MONOTONIC)

long long now_ns() { // async-signal-safe
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<long long>(t.tv_sec) * 1'000'000'000LL + t.tv_nsec;
}

extern "C" void on_stop_signal(int sig) {
  if (g_stop.load() == sig) {
    // A second one a moment later is the same request arriving twice (Ctrl-C
    // reaches a forked job directly and through the parent that forwards
    // it); one at least a second later is an impatient user: give up waiting
    // for the chunk.
    if (now_ns() - g_first_ns.load() < 1'000'000'000LL) return;
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_first_ns.store(now_ns());
  g_stop.store(sig);
}
} // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int stop_signal() {
  return g_stop.load();
}

void set_stop_signal(int signal) {
  g_stop.store(signal);
}

} // namespace centridem
