// penumbra-coordinator: serves the farm's jobs and workers APIs.
//   penumbra-coordinator --listen 0.0.0.0:7420 --data-dir /var/lib/penumbra
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <thread>

#include "proto/support/scene_packing.h"
#include "proto/support/shutdown_signals.h"
#include "server/coordinator_server.h"
#include "server/http_frontend.h"

int main(int argc, char** argv) {
  CLI::App app{"penumbra-coordinator: the Penumbra render farm's coordinator"};
  std::string listen = "0.0.0.0:7420";
  std::string data_dir = "penumbra-data";
  std::string port_file;
  std::string log_level = "info";
  double lease_seconds = 30;
  penumbra::farm::CoordinatorOptions options;
  size_t max_scene_mib = 256;
  app.add_option("--listen", listen, "host:port to serve on (port 0: any free port)");
  app.add_option("--data-dir", data_dir, "folder of the SQLite state (created when missing)");
  app.add_option("--port-file", port_file, "write the port it listens on to this file");
  app.add_option("--lease-seconds", lease_seconds, "a lease not extended this long expires")
      ->check(CLI::Range(0.05, 3600.0));
  app.add_option("--tile-size", options.default_tile_size, "default tile side in pixels");
  app.add_option("--passes-per-task", options.default_passes_per_task,
                 "default passes in one task");
  app.add_option("--max-scene-mib", max_scene_mib, "largest scene package accepted");
  app.add_option("--max-queued-tasks", options.max_queued_tasks, "queue limit over all jobs");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  std::string http_listen;  // empty: no HTTP endpoint
  app.add_option("--http-listen", http_listen,
                 "serve /metrics, /healthz, /api and the dashboard on HOST:PORT (PORT or :PORT: "
                 "loopback; off when not given)");
  CLI11_PARSE(app, argc, argv);

  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::flush_on(spdlog::level::info);
  options.data_dir = data_dir;
  options.lease_time = std::chrono::milliseconds(int64_t(lease_seconds * 1000));
  options.max_scene_bytes = max_scene_mib << 20;

  // SIGINT and SIGTERM shut the server down (polled by a thread; the handler only counts).
  penumbra::farm::install_shutdown_signals();

  try {
    penumbra::farm::Coordinator coordinator(options, penumbra::farm::parse_wire_package);
    penumbra::farm::CoordinatorServer server(coordinator, listen,
                                             options.max_scene_bytes + (size_t(16) << 20));
    spdlog::info("penumbra-coordinator listening on port {} (data in {})", server.port(), data_dir);
    std::unique_ptr<penumbra::farm::HttpFrontend> http;
    if (!http_listen.empty()) {
      http = std::make_unique<penumbra::farm::HttpFrontend>(
          coordinator, penumbra::farm::HttpFrontendOptions{.address = http_listen});
      spdlog::info("penumbra-coordinator HTTP (metrics, dashboard) on {}:{}", http->host(),
                   http->port());
    }
    if (!port_file.empty()) {
      std::string temporary = port_file + ".tmp";
      std::ofstream(temporary) << server.port() << "\n";
      std::rename(temporary.c_str(), port_file.c_str());
    }
    std::atomic<bool> stopped{false};
    std::thread signal_watch([&] {
      while (penumbra::farm::shutdown_signal_count() == 0 && !stopped)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (stopped) return;
      spdlog::info("signal: shutting down");
      server.shutdown();
    });
    server.wait();
    stopped = true;
    signal_watch.join();
  } catch (const std::exception& error) {
    spdlog::critical("{}", error.what());
    return 1;
  }
  return 0;
}
