#pragma once
// The coordinator's HTTP side: Prometheus metrics, a health check, a read-only JSON API and the
// live dashboard, served by cpp-httplib (Debian's libcpp-httplib-dev) on its own port next to the
// gRPC one. Nothing here changes the farm: every endpoint reads the Coordinator.
//
//   GET /                              the dashboard (server/dashboard_page.h)
//   GET /healthz                       200 "ok" while the coordinator answers
//   GET /metrics                       Prometheus text format 0.0.4
//   GET /api/summary                   counters and gauges as JSON
//   GET /api/jobs                      every job's status (no curve)
//   GET /api/jobs/<id>                 one job's status with its error-against-time curve
//   GET /api/jobs/<id>/preview.png     the job's image so far, tone-mapped (?exposure=x)
//   GET /api/workers                   the workers the coordinator knows
//
// JSON bodies are the protobuf messages of penumbra/v1/farm.proto in the canonical proto3 JSON
// mapping (field names as in the .proto, every field printed, 64-bit integers as strings).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "server/coordinator.h"

namespace httplib {
class Server;
}

namespace penumbra::farm {

struct HttpAddress {
  std::string host;
  int port = 0;
};
// "HOST:PORT", ":PORT" or "PORT" (the last two on loopback, 127.0.0.1); "[::1]:PORT" for IPv6.
// Throws std::invalid_argument on anything else.
HttpAddress parse_http_address(const std::string& text);

// Upper bounds (seconds) of the job latency histogram's buckets (submission to done).
inline constexpr double kJobLatencyBuckets[] = {0.5, 1,   2,   5,   10,   30,
                                                60,  120, 300, 600, 1800, 3600};

// What the coordinator's counters cannot say by themselves: job latencies (seen by sampling the
// job list) and the task completion rate over the last minute. Thread-safe.
class FarmMonitor {
 public:
  explicit FarmMonitor(Coordinator& coordinator) : coordinator_(coordinator) {}
  // Looks at the jobs and counters once: jobs seen finished for the first time are added to the
  // latency histogram (jobs already finished at the first look are not: they ended before the
  // monitor existed), and the completion counter is added to the rate window.
  void sample();
  // Prometheus text exposition format 0.0.4 of every family (see the .cpp for the list).
  std::string metrics_text();
  // Tasks completed per second over the last `window` (shorter while the monitor is younger).
  double completion_rate(std::chrono::seconds window = std::chrono::seconds(60));

 private:
  struct Latencies {
    std::vector<uint64_t> bucket_counts = std::vector<uint64_t>(std::size(kJobLatencyBuckets), 0);
    uint64_t count = 0;
    double sum = 0;
  };
  double completion_rate_locked(std::chrono::seconds window) const;

  Coordinator& coordinator_;
  std::mutex mutex_;
  bool first_sample_done_ = false;
  std::set<std::string> finished_jobs_;
  Latencies latencies_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, uint64_t>> completions_;
};

struct HttpFrontendOptions {
  std::string address = "127.0.0.1:0";  // see parse_http_address; port 0 picks a free one
  std::chrono::milliseconds sample_period{200};
  int threads = 2;  // request threads
};

class HttpFrontend {
 public:
  // Binds and starts serving; throws std::runtime_error when it cannot listen.
  HttpFrontend(Coordinator& coordinator, const HttpFrontendOptions& options);
  ~HttpFrontend();  // stop()
  HttpFrontend(const HttpFrontend&) = delete;
  HttpFrontend& operator=(const HttpFrontend&) = delete;

  int port() const { return port_; }
  const std::string& host() const { return host_; }
  void stop();

 private:
  void route();
  void sample_loop(std::chrono::milliseconds period);

  Coordinator& coordinator_;
  FarmMonitor monitor_;
  std::unique_ptr<httplib::Server> server_;
  std::string host_;
  int port_ = 0;
  std::thread serve_thread_, sample_thread_;
  std::atomic<bool> serve_finished_{false};
  std::mutex stop_mutex_;
  std::condition_variable stop_wake_;
  bool stopping_ = false;
};

}  // namespace penumbra::farm
