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
//   GET /jobs/<id>                     a job's page: state, progress, preview, tasks by state,
//                                      this job's workers and their throughput on it,
//                                      convergence charts, errors, the comparison viewer of its
//                                      image and reference (a running job's: ?viewer=1)
//   GET /batches/<id>                  a batch's page: progress, runs, refusals, the comparison
//                                      viewer of its images (server/status_pages.h)
//
// Access (HttpFrontendOptions::tokens, the coordinator's --tokens-file; server/auth.h
// authorize_http): with tokens every route but /healthz needs a token, sent as an
// "Authorization: Bearer <token>" header (scripts, curl, Prometheus) or as a "token" query
// parameter (a browser: the pages carry it on in their links and image addresses, the dashboard's
// script sends it to the JSON API as a header). No or an unknown token: 401 with
// "WWW-Authenticate: Bearer"; a worker token: 403. A client token sees its own jobs and batches
// (another's are 404, like an unknown id) and the farm's aggregate figures (summary, workers),
// not /metrics (it names every job: 403); viewer and admin tokens see everything. /metrics is
// open without a token only with open_metrics. Nothing on this side changes the farm and no
// cookie is set, so a page of another site cannot make a browser act here (no CSRF); every
// answer carries "Referrer-Policy: no-referrer" so a token in an address does not leave in a
// Referer header. With tls_cert and tls_key the side serves HTTPS only.
//
// JSON bodies are the protobuf messages of penumbra/v1/farm.proto in the proto3 JSON mapping
// (field names as in the .proto, every field printed), except that 64-bit integers are JSON
// numbers (exact), not strings. GET / renders the farm's state on the server (tables, preview):
// the page is readable without JavaScript; its script then keeps it live.

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

#include "server/auth.h"
#include "server/coordinator.h"

namespace httplib {
class Server;
struct Request;
}  // namespace httplib

namespace penumbra::farm {

class BatchManager;

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
  int threads = 2;                           // request threads
  BatchManager* batches = nullptr;           // serves /batches/<id> when given
  std::shared_ptr<const TokenTable> tokens;  // null: authentication off, every route open
  bool open_metrics = false;                 // /metrics without a token
  std::string tls_cert, tls_key;             // PEM files: serve HTTPS (both or neither)
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
  HttpAuthorization authorize(const httplib::Request& request) const;
  void sample_loop(std::chrono::milliseconds period);

  Coordinator& coordinator_;
  BatchManager* batches_ = nullptr;
  std::shared_ptr<const TokenTable> tokens_;
  bool open_metrics_ = false;
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
