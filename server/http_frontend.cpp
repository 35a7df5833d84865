#include "server/http_frontend.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "server/dashboard_page.h"

namespace penumbra::farm {

namespace {

bool is_terminal(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

int64_t unix_milliseconds_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A label value in the exposition format: backslash, double quote and newline escaped.
std::string escape_label(const std::string& value) {
  std::string out;
  out.reserve(value.size());
  for (char c : value) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '"')
      out += "\\\"";
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out;
}

// Shortest round-trip decimal; the format's spellings of the non-finite values.
std::string number(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  return fmt::format("{}", value);
}

class MetricsWriter {
 public:
  void family(const std::string& name, const char* type, const std::string& help) {
    out_ << "# HELP " << name << ' ' << help << "\n# TYPE " << name << ' ' << type << '\n';
  }
  void sample(const std::string& name, double value,
              const std::vector<std::pair<std::string, std::string>>& labels = {}) {
    out_ << name;
    if (!labels.empty()) {
      out_ << '{';
      for (size_t i = 0; i < labels.size(); ++i)
        out_ << (i ? "," : "") << labels[i].first << "=\"" << escape_label(labels[i].second) << '"';
      out_ << '}';
    }
    out_ << ' ' << number(value) << '\n';
  }
  void single(const std::string& name, const char* type, const std::string& help, double value) {
    family(name, type, help);
    sample(name, value);
  }
  std::string text() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

std::string to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string json;
  auto status = google::protobuf::util::MessageToJsonString(message, &json, options);
  if (!status.ok()) throw std::runtime_error("JSON encoding failed: " + status.ToString());
  return json;
}

double srgb_encode(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// 8-bit sRGB PNG bytes of `color` scaled by `exposure` (clamped; non-finite pixels black).
std::string encode_preview_png(const Image& color, double exposure) {
  if (color.width <= 0 || color.height <= 0) throw std::runtime_error("empty preview image");
  std::vector<uint8_t> pixels(color.rgb.size());
  for (size_t i = 0; i < color.rgb.size(); ++i) {
    double value = double(color.rgb[i]) * exposure;
    if (!std::isfinite(value)) value = 0;
    pixels[i] = uint8_t(std::lround(srgb_encode(std::clamp(value, 0.0, 1.0)) * 255.0));
  }
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  auto output = OIIO::ImageOutput::create("png");
  if (!output || !output->supports("ioproxy") || !output->set_ioproxy(&proxy))
    throw std::runtime_error("no in-memory PNG writer");
  OIIO::ImageSpec spec(color.width, color.height, 3, OIIO::TypeDesc::UINT8);
  if (!output->open("preview.png", spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, pixels.data()) || !output->close())
    throw std::runtime_error("PNG encoding failed: " + output->geterror());
  return std::string(bytes.begin(), bytes.end());
}

int http_status(FarmErrorCode code) {
  switch (code) {
    case FarmErrorCode::InvalidArgument:
      return 400;
    case FarmErrorCode::NotFound:
      return 404;
    case FarmErrorCode::ResourceExhausted:
      return 503;
    case FarmErrorCode::FailedPrecondition:
      return 409;
    case FarmErrorCode::Internal:
      return 500;
  }
  return 500;
}

// Runs a handler body; domain errors become their HTTP status with a JSON error body.
template <typename Body>
void guarded(httplib::Response& response, Body&& body) {
  auto fail = [&](int status, const std::string& message) {
    response.status = status;
    response.set_content(nlohmann::json{{"error", message}}.dump() + "\n", "application/json");
  };
  try {
    body();
  } catch (const FarmError& error) {
    fail(http_status(error.code()), error.what());
  } catch (const std::exception& error) {
    fail(500, error.what());
  }
}

void set_json(httplib::Response& response, const std::string& json) {
  response.set_header("Cache-Control", "no-store");
  response.set_content(json + "\n", "application/json");
}

}  // namespace

HttpAddress parse_http_address(const std::string& text) {
  auto bad = [&] {
    return std::invalid_argument("HTTP address '" + text +
                                 "': expected HOST:PORT, :PORT or PORT (port 0-65535)");
  };
  std::string host = "127.0.0.1", port_text = text;
  if (!text.empty() && text.front() == '[') {  // [v6]:port
    size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':')
      throw bad();
    host = text.substr(1, close - 1);
    port_text = text.substr(close + 2);
  } else if (size_t colon = text.rfind(':'); colon != std::string::npos) {
    if (colon > 0) host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
  }
  if (port_text.empty() || port_text.size() > 5 ||
      !std::all_of(port_text.begin(), port_text.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw bad();
  int port = std::stoi(port_text);
  if (port > 65535 || host.empty()) throw bad();
  return {host, port};
}

void FarmMonitor::sample() {
  std::vector<v1::JobStatus> jobs = coordinator_.list();
  CoordinatorCounters counters = coordinator_.counters();
  auto now = std::chrono::steady_clock::now();
  int64_t now_ms = unix_milliseconds_now();
  std::lock_guard lock(mutex_);
  for (const v1::JobStatus& job : jobs) {
    if (!is_terminal(job.state()) || finished_jobs_.count(job.job_id())) continue;
    finished_jobs_.insert(job.job_id());
    // Jobs finished before the first look ended at an unknown time: not observed.
    if (!first_sample_done_ || job.state() != v1::JOB_STATE_DONE) continue;
    double seconds = std::max(0.0, double(now_ms - job.submitted_unix_ms()) / 1000.0);
    for (size_t i = 0; i < std::size(kJobLatencyBuckets); ++i)
      if (seconds <= kJobLatencyBuckets[i]) ++latencies_.bucket_counts[i];
    ++latencies_.count;
    latencies_.sum += seconds;
  }
  first_sample_done_ = true;
  completions_.emplace_back(now, counters.tasks_completed);
  // Keep one sample older than the longest window so a full minute is always covered.
  while (completions_.size() > 2 && now - completions_[1].first > std::chrono::seconds(61))
    completions_.pop_front();
}

double FarmMonitor::completion_rate(std::chrono::seconds window) {
  std::lock_guard lock(mutex_);
  return completion_rate_locked(window);
}

double FarmMonitor::completion_rate_locked(std::chrono::seconds window) const {
  if (completions_.size() < 2) return 0;
  const auto& newest = completions_.back();
  // The oldest sample inside the window (or the oldest there is).
  auto oldest = completions_.front();
  for (const auto& sample : completions_)
    if (newest.first - sample.first <= window) {
      oldest = sample;
      break;
    }
  double seconds = std::chrono::duration<double>(newest.first - oldest.first).count();
  if (seconds <= 0) return 0;
  return double(newest.second - oldest.second) / seconds;
}

std::string FarmMonitor::metrics_text() {
  CoordinatorCounters counters = coordinator_.counters();
  std::vector<v1::JobStatus> jobs = coordinator_.list();
  std::vector<v1::WorkerInfo> workers = coordinator_.workers();
  MetricsWriter out;

  out.single("penumbra_queue_depth", "gauge", "Tasks waiting for a worker.",
             double(counters.queued_tasks));
  out.single("penumbra_leased_tasks", "gauge", "Tasks held by workers now.",
             double(counters.leased_tasks));
  out.single("penumbra_tasks_leased_total", "counter", "Task leases granted since start.",
             double(counters.tasks_leased));
  out.single("penumbra_tasks_completed_total", "counter", "Task results accepted since start.",
             double(counters.tasks_completed));
  out.single("penumbra_tasks_failed_total", "counter", "Tasks failed by workers since start.",
             double(counters.tasks_failed));
  out.single("penumbra_late_results_total", "counter",
             "Late or duplicate task results dropped since start.", double(counters.late_results));
  out.single("penumbra_leases_expired_total", "counter",
             "Leases that timed out and went back to the queue.", double(counters.leases_expired));
  out.single("penumbra_jobs_submitted_total", "counter", "Jobs submitted since start.",
             double(counters.jobs_submitted));
  {
    std::lock_guard lock(mutex_);
    out.single("penumbra_tasks_completed_per_second", "gauge",
               "Task results accepted per second over the last minute.",
               completion_rate_locked(std::chrono::seconds(60)));
    out.family("penumbra_job_latency_seconds", "histogram",
               "Seconds from a job's submission to its result (jobs done while this coordinator "
               "ran).");
    for (size_t i = 0; i < std::size(kJobLatencyBuckets); ++i)
      out.sample("penumbra_job_latency_seconds_bucket", double(latencies_.bucket_counts[i]),
                 {{"le", number(kJobLatencyBuckets[i])}});
    out.sample("penumbra_job_latency_seconds_bucket", double(latencies_.count), {{"le", "+Inf"}});
    out.sample("penumbra_job_latency_seconds_sum", latencies_.sum);
    out.sample("penumbra_job_latency_seconds_count", double(latencies_.count));
  }

  std::map<std::string, int> by_state;
  for (int state = v1::JOB_STATE_QUEUED; state <= v1::JOB_STATE_CANCELLED; ++state)
    by_state[v1::JobState_Name(v1::JobState(state))] = 0;
  for (const v1::JobStatus& job : jobs) ++by_state[v1::JobState_Name(job.state())];
  out.family("penumbra_jobs", "gauge", "Jobs the coordinator holds, by state.");
  for (const auto& [state, count] : by_state) {
    std::string name = state.rfind("JOB_STATE_", 0) == 0 ? state.substr(10) : state;
    std::transform(name.begin(), name.end(), name.begin(), ::tolower);
    out.sample("penumbra_jobs", count, {{"state", name}});
  }
  out.family("penumbra_job_passes_complete", "gauge",
             "Passes every tile of an unfinished job has (its image's spp so far).");
  for (const v1::JobStatus& job : jobs)
    if (!is_terminal(job.state()))
      out.sample("penumbra_job_passes_complete", job.passes_complete(), {{"job", job.job_id()}});

  int alive = 0;
  double alive_threads = 0;
  for (const v1::WorkerInfo& worker : workers)
    if (worker.alive()) {
      ++alive;
      alive_threads += worker.threads();
    }
  out.single("penumbra_workers_registered", "gauge", "Workers that registered since start.",
             double(workers.size()));
  out.single("penumbra_workers_active", "gauge", "Workers heard from within the lease time.",
             alive);
  out.single("penumbra_worker_threads_active", "gauge", "Render threads of the active workers.",
             alive_threads);
  auto labels = [](const v1::WorkerInfo& worker) {
    return std::vector<std::pair<std::string, std::string>>{{"worker", worker.worker_id()},
                                                            {"name", worker.name()}};
  };
  out.family("penumbra_worker_tasks_leased", "gauge", "Tasks a worker holds now.");
  for (const v1::WorkerInfo& worker : workers)
    out.sample("penumbra_worker_tasks_leased", worker.tasks_leased(), labels(worker));
  out.family("penumbra_worker_tasks_completed_total", "counter", "Tasks a worker completed.");
  for (const v1::WorkerInfo& worker : workers)
    out.sample("penumbra_worker_tasks_completed_total", double(worker.tasks_completed()),
               labels(worker));
  out.family("penumbra_worker_compute_seconds_total", "counter",
             "Render seconds a worker reported (summed over its threads).");
  for (const v1::WorkerInfo& worker : workers)
    out.sample("penumbra_worker_compute_seconds_total", worker.compute_seconds(), labels(worker));
  return out.text();
}

HttpFrontend::HttpFrontend(Coordinator& coordinator, const HttpFrontendOptions& options)
    : coordinator_(coordinator),
      monitor_(coordinator),
      server_(std::make_unique<httplib::Server>()) {
  HttpAddress address = parse_http_address(options.address);
  int threads = std::max(1, options.threads);
  server_->new_task_queue = [threads] { return new httplib::ThreadPool(size_t(threads)); };
  server_->set_read_timeout(std::chrono::seconds(5));
  server_->set_write_timeout(std::chrono::seconds(5));
  route();
  host_ = address.host;
  if (address.port == 0) {
    port_ = server_->bind_to_any_port(address.host);
    if (port_ <= 0) throw std::runtime_error("HTTP: cannot listen on " + options.address);
  } else {
    if (!server_->bind_to_port(address.host, address.port))
      throw std::runtime_error("HTTP: cannot listen on " + options.address);
    port_ = address.port;
  }
  monitor_.sample();
  serve_thread_ = std::thread([this] {
    server_->listen_after_bind();
    serve_finished_ = true;
  });
  // stop() only reaches a server that is already accepting: wait for it (a few milliseconds).
  while (!server_->is_running() && !serve_finished_)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  sample_thread_ = std::thread([this, period = options.sample_period] { sample_loop(period); });
}

HttpFrontend::~HttpFrontend() {
  stop();
}

void HttpFrontend::stop() {
  {
    std::lock_guard lock(stop_mutex_);
    stopping_ = true;
  }
  stop_wake_.notify_all();
  if (server_) server_->stop();
  if (serve_thread_.joinable()) serve_thread_.join();
  if (sample_thread_.joinable()) sample_thread_.join();
}

void HttpFrontend::sample_loop(std::chrono::milliseconds period) {
  std::unique_lock lock(stop_mutex_);
  while (!stop_wake_.wait_for(lock, period, [this] { return stopping_; })) {
    lock.unlock();
    try {
      monitor_.sample();
    } catch (const std::exception& error) {
      spdlog::warn("HTTP monitor: {}", error.what());
    }
    lock.lock();
  }
}

void HttpFrontend::route() {
  httplib::Server& server = *server_;
  server.Get("/", [](const httplib::Request&, httplib::Response& response) {
    response.set_header("Cache-Control", "no-store");
    response.set_content(std::string(dashboard_page()), "text/html; charset=utf-8");
  });
  server.Get("/healthz", [this](const httplib::Request&, httplib::Response& response) {
    guarded(response, [&] {
      coordinator_.counters();  // answers only when the coordinator's lock is not stuck
      response.set_header("Cache-Control", "no-store");
      response.set_content("ok\n", "text/plain");
    });
  });
  server.Get("/metrics", [this](const httplib::Request&, httplib::Response& response) {
    guarded(response, [&] {
      response.set_content(monitor_.metrics_text(), "text/plain; version=0.0.4; charset=utf-8");
    });
  });
  server.Get("/api/summary", [this](const httplib::Request&, httplib::Response& response) {
    guarded(response, [&] {
      CoordinatorCounters c = coordinator_.counters();
      int alive = 0;
      for (const v1::WorkerInfo& worker : coordinator_.workers()) alive += worker.alive();
      nlohmann::json json = {{"queue_depth", c.queued_tasks},
                             {"leased_tasks", c.leased_tasks},
                             {"tasks_leased", c.tasks_leased},
                             {"tasks_completed", c.tasks_completed},
                             {"tasks_failed", c.tasks_failed},
                             {"late_results", c.late_results},
                             {"leases_expired", c.leases_expired},
                             {"jobs_submitted", c.jobs_submitted},
                             {"tasks_per_second", monitor_.completion_rate()},
                             {"workers_active", alive}};
      set_json(response, json.dump());
    });
  });
  server.Get("/api/jobs", [this](const httplib::Request&, httplib::Response& response) {
    guarded(response, [&] {
      v1::ListJobsResponse list;
      for (v1::JobStatus& job : coordinator_.list()) *list.add_jobs() = std::move(job);
      set_json(response, to_json(list));
    });
  });
  server.Get(R"(/api/jobs/([A-Za-z0-9_.-]+))",
             [this](const httplib::Request& request, httplib::Response& response) {
               guarded(response, [&] {
                 set_json(response, to_json(coordinator_.status(request.matches[1], true)));
               });
             });
  server.Get(R"(/api/jobs/([A-Za-z0-9_.-]+)/preview\.png)", [this](const httplib::Request& request,
                                                                   httplib::Response& response) {
    guarded(response, [&] {
      double exposure = 1;
      if (request.has_param("exposure")) {
        try {
          exposure = std::stod(request.get_param_value("exposure"));
        } catch (const std::exception&) {
          exposure = -1;
        }
        if (!std::isfinite(exposure) || exposure < 0)
          throw FarmError(FarmErrorCode::InvalidArgument, "exposure must be a finite number >= 0");
      }
      uint32_t passes = 0;
      Film film = coordinator_.preview_film(request.matches[1], &passes);
      response.set_header("Cache-Control", "no-store");
      response.set_header("X-Penumbra-Passes", std::to_string(passes));
      response.set_content(encode_preview_png(film.color, exposure), "image/png");
    });
  });
  server.Get("/api/workers", [this](const httplib::Request&, httplib::Response& response) {
    guarded(response, [&] {
      v1::ListWorkersResponse list;
      for (v1::WorkerInfo& worker : coordinator_.workers()) *list.add_workers() = std::move(worker);
      set_json(response, to_json(list));
    });
  });
}

}  // namespace penumbra::farm
