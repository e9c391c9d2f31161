#include "core/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace centridem {

namespace {
std::atomic<int> g_stop{0};

extern "C" void on_stop_signal(int sig) {
  if (g_stop.load() == sig) { // second time: give up waiting for the chunk
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
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
