#include "proto/support/shutdown_signals.h"

#include <atomic>
#include <csignal>

namespace penumbra::farm {

namespace {
std::atomic<int> signal_count{0};
extern "C" void count_signal(int) {
  signal_count.fetch_add(1);
}
}  // namespace

void install_shutdown_signals() {
  struct sigaction action {};
  action.sa_handler = count_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int shutdown_signal_count() {
  return signal_count.load();
}

}  // namespace penumbra::farm
