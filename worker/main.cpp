// penumbra-worker: renders tasks for a Penumbra coordinator.
//   penumbra-worker --coordinator host:7420 --threads 8 --cache-dir ~/.cache/penumbra
//       --tls-ca ca.pem --token-file worker.token
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <thread>

#include "proto/support/farm_client.h"
#include "proto/support/shutdown_signals.h"
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
  uint64_t cache_max_mib = options.cache_max_bytes >> 20;
  app.add_option("--cache-max-mib", cache_max_mib,
                 "bound of the scene cache on disk; beyond it the least recently used scenes are "
                 "deleted")
      ->check(CLI::Range(uint64_t(1), uint64_t(1) << 30))
      ->capture_default_str();
  app.add_option("--name", options.name, "name shown by `penumbra workers`");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  std::string token, token_file;
  app.add_option("--tls-ca", options.tls_ca,
                 "PEM file of the CA that signed the coordinator's "
                 "certificate: connect with TLS");
  app.add_option("--tls-cert", options.tls_cert,
                 "PEM certificate of this worker, for mutual TLS (with --tls-key)");
  app.add_option("--tls-key", options.tls_key, "PEM private key of --tls-cert");
  app.add_option("--token", token,
                 "bearer token with the worker role (visible in ps: prefer "
                 "--token-file or PENUMBRA_TOKEN)");
  app.add_option("--token-file", token_file, "file whose first line is the token");
  CLI11_PARSE(app, argc, argv);
  options.cache_max_bytes = cache_max_mib << 20;
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::flush_on(spdlog::level::info);

  // SIGTERM/SIGINT: drain (finish and deliver the tasks held); a second one exits at once.
  penumbra::farm::install_shutdown_signals();
  std::unique_ptr<penumbra::farm::RenderWorker> created;
  try {
    options.token = penumbra::farm::resolve_token(token, token_file);
    created = std::make_unique<penumbra::farm::RenderWorker>(options);
  } catch (const std::exception& error) {
    spdlog::critical("{}", error.what());
    return 2;
  }
  penumbra::farm::RenderWorker& worker = *created;
  std::thread signal_watch([&worker] {
    while (penumbra::farm::shutdown_signal_count() == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    spdlog::info("signal: draining");
    worker.drain();
    while (penumbra::farm::shutdown_signal_count() < 2)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    spdlog::warn("second signal: exiting without draining");
    std::_Exit(1);
  });
  signal_watch.detach();
  return worker.run();
}
