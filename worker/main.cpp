// penumbra-worker: renders tasks for a Penumbra coordinator.
//   penumbra-worker --coordinator host:7420 --threads 8 --cache-dir ~/.cache/penumbra
#include <pthread.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <thread>

#include "worker/worker.h"

int main(int argc, char** argv) {
  CLI::App app{"penumbra-worker: renders tasks leased from a Penumbra coordinator"};
  penumbra::farm::WorkerOptions options;
  options.threads = int(std::max(1u, std::thread::hardware_concurrency()));
  char host[256] = "worker";
  gethostname(host, sizeof host - 1);
  options.name = host;
  std::string log_level = "info";
  if (const char* env = std::getenv("PENUMBRA_COORDINATOR")) options.coordinator = env;
  app.add_option("--coordinator", options.coordinator,
                 "host:port of the coordinator (or PENUMBRA_COORDINATOR)");
  app.add_option("--threads", options.threads, "render threads")->check(CLI::Range(1, 1024));
  app.add_option("--cache-dir", options.cache_dir, "folder for scenes cached by content hash");
  app.add_option("--name", options.name, "name shown by `penumbra workers`");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));

  // SIGTERM/SIGINT: drain (finish and deliver the tasks held); a second one exits at once.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  penumbra::farm::RenderWorker worker(options);
  std::thread signal_thread([&] {
    int signal = 0;
    sigwait(&signals, &signal);
    if (signal == 0) return;
    spdlog::info("signal {}: draining", signal);
    worker.drain();
    sigwait(&signals, &signal);
    if (signal == 0) return;
    spdlog::warn("second signal: exiting without draining");
    std::_Exit(1);
  });
  signal_thread.detach();
  return worker.run();
}
