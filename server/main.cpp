// penumbra-coordinator: serves the farm's jobs and workers APIs.
//   penumbra-coordinator --listen 0.0.0.0:7420 --data-dir /var/lib/penumbra
//       --tls-cert server.pem --tls-key server.key --tokens-file tokens.txt
// Without --listen it serves 127.0.0.1:7420 (loopback only).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <thread>

#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"
#include "proto/support/shutdown_signals.h"
#include "server/auth.h"
#include "server/coordinator_server.h"
#include "server/http_frontend.h"
#include "server/tls.h"

int main(int argc, char** argv) {
  CLI::App app{"penumbra-coordinator: the Penumbra render farm's coordinator"};
  std::string listen = "127.0.0.1:7420";
  std::string data_dir = "penumbra-data";
  std::string port_file;
  std::string log_level = "info";
  double lease_seconds = 30;
  penumbra::farm::CoordinatorOptions options;
  size_t max_scene_mib = 256;
  app.add_option("--listen", listen,
                 "host:port to serve on (default 127.0.0.1:7420, loopback only; port 0: any free "
                 "port)");
  app.add_option("--data-dir", data_dir, "folder of the SQLite state (created when missing)");
  app.add_option("--port-file", port_file, "write the port it listens on to this file");
  app.add_option("--lease-seconds", lease_seconds,
                 "a lease not extended this long expires and its task is queued again")
      ->check(CLI::Range(0.05, 3600.0))
      ->capture_default_str();
  double heartbeat_seconds = 1, forget_worker_seconds = 300;
  app.add_option("--heartbeat-seconds", heartbeat_seconds,
                 "how often workers heartbeat (at most a third of --lease-seconds)")
      ->check(CLI::Range(0.01, 600.0))
      ->capture_default_str();
  app.add_option("--missed-heartbeats", options.missed_heartbeats,
                 "a worker silent this many heartbeats (and half one more) is dead: its tasks "
                 "are queued again at once (1: at its first missed heartbeat)")
      ->check(CLI::Range(1u, 100u))
      ->capture_default_str();
  app.add_option("--forget-worker-seconds", forget_worker_seconds,
                 "a dead worker leaves the worker list after this long (0: never)")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--tile-size", options.default_tile_size, "default tile side in pixels");
  app.add_option("--passes-per-task", options.default_passes_per_task,
                 "default passes in one task");
  app.add_option("--max-scene-mib", max_scene_mib, "largest scene package accepted");
  app.add_option("--max-queued-tasks", options.max_queued_tasks, "queue limit over all jobs");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  std::string tokens_file;
  penumbra::farm::ServerTlsFiles tls;
  penumbra::farm::ClientLimits client_limits;
  app.add_option("--tokens-file", tokens_file,
                 "lines \"role name token\" (roles client, worker, admin; # comments): require "
                 "a token on every call (without it authentication is off)");
  app.add_option("--tls-cert", tls.cert, "PEM certificate (chain) of this coordinator: serve TLS");
  app.add_option("--tls-key", tls.key, "PEM private key of --tls-cert");
  app.add_option("--tls-client-ca", tls.client_ca,
                 "PEM CA of client certificates: mutual TLS, required of workers");
  app.add_option("--max-queued-jobs-per-client", client_limits.max_queued_jobs_per_owner,
                 "unfinished jobs one client (token name) may have (0: no limit)");
  std::string http_listen;  // empty: no HTTP endpoint
  app.add_option("--http-listen", http_listen,
                 "serve /metrics, /healthz, /api and the dashboard on HOST:PORT (PORT or :PORT: "
                 "loopback; off when not given)");
  bool http_open_metrics = false;
  app.add_flag("--http-open-metrics", http_open_metrics,
               "serve /metrics without a token (by default, with --tokens-file, it needs a viewer "
               "or admin token like the rest of the HTTP side but /healthz)");
  CLI11_PARSE(app, argc, argv);

  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::flush_on(spdlog::level::info);
  options.data_dir = data_dir;
  options.lease_time = std::chrono::milliseconds(int64_t(lease_seconds * 1000));
  options.heartbeat_interval = std::chrono::milliseconds(int64_t(heartbeat_seconds * 1000));
  options.forget_worker_after = std::chrono::milliseconds(int64_t(forget_worker_seconds * 1000));
  options.max_scene_bytes = max_scene_mib << 20;

  // SIGINT and SIGTERM shut the server down (polled by a thread; the handler only counts).
  penumbra::farm::install_shutdown_signals();

  try {
    penumbra::farm::Coordinator coordinator(options, penumbra::farm::parse_wire_package);
    penumbra::farm::CoordinatorServerOptions server_options;
    server_options.address = listen;
    server_options.max_message_bytes = options.max_scene_bytes + (size_t(16) << 20);
    penumbra::farm::AuthPolicy auth;
    if (!tls.cert.empty() || !tls.key.empty() || !tls.client_ca.empty()) {
      server_options.credentials = penumbra::farm::make_server_tls_credentials(tls);
      auth.workers_need_client_certificate = !tls.client_ca.empty();
    } else if (!penumbra::farm::is_loopback_address(listen)) {
      spdlog::warn("serving {} without TLS: calls (and tokens) travel in the clear", listen);
    }
    if (!tokens_file.empty()) {
      auth.tokens = std::make_shared<const penumbra::farm::TokenTable>(
          penumbra::farm::TokenTable::load(tokens_file));
      spdlog::info("authentication on: {} tokens from {}", auth.tokens->size(), tokens_file);
    } else {
      spdlog::warn(
          "authentication off (no --tokens-file): anyone who can connect may submit "
          "jobs and lease tasks");
    }
    if (auth.tokens || auth.workers_need_client_certificate)
      server_options.configure.push_back([auth](grpc::ServerBuilder& builder) {
        std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>>
            interceptors;
        interceptors.push_back(std::make_unique<penumbra::farm::AuthInterceptorFactory>(auth));
        builder.experimental().SetInterceptorCreators(std::move(interceptors));
      });
    penumbra::farm::set_client_limits(client_limits);
    penumbra::farm::CoordinatorServer server(coordinator, server_options);
    spdlog::info("penumbra-coordinator listening on port {} (data in {})", server.port(), data_dir);
    std::unique_ptr<penumbra::farm::HttpFrontend> http;
    if (!http_listen.empty()) {
      // The same tokens and certificate as the gRPC side (no client certificates: browsers).
      penumbra::farm::HttpFrontendOptions http_options;
      http_options.address = http_listen;
      http_options.batches = &server.batches();
      http_options.tokens = auth.tokens;
      http_options.open_metrics = http_open_metrics;
      http_options.tls_cert = tls.cert;
      http_options.tls_key = tls.key;
      http = std::make_unique<penumbra::farm::HttpFrontend>(coordinator, http_options);
      spdlog::info("penumbra-coordinator HTTP{} (metrics, dashboard) on {}:{}{}",
                   tls.cert.empty() ? "" : "S", http->host(), http->port(),
                   auth.tokens ? (http_open_metrics ? " (tokens; /metrics open)" : " (tokens)")
                               : " (no tokens: open)");
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
