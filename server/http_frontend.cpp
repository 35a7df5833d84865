#include "server/http_frontend.h"

#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "core/image/metrics.h"
#include "core/report/batch_figure.h"
#include "core/report/comparison_viewer.h"
#include "server/batch_manager.h"
#include "server/dashboard_page.h"
#include "server/status_pages.h"

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

// The canonical proto3 JSON mapping prints 64-bit integers as strings (JavaScript numbers lose
// precision past 2^53); our counts, ids, seeds and milliseconds are read by scripts and
// dashboards as numbers, so they are turned back into JSON numbers (exact: nlohmann keeps 64-bit
// integers).
void int64_as_numbers(const google::protobuf::Descriptor& descriptor, nlohmann::json& json) {
  using google::protobuf::FieldDescriptor;
  for (int i = 0; i < descriptor.field_count(); ++i) {
    const FieldDescriptor& field = *descriptor.field(i);
    auto found = json.find(field.name());
    if (found == json.end()) continue;
    auto convert = [&](nlohmann::json& value) {
      if (field.cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) {
        if (value.is_object() && !field.is_map()) int64_as_numbers(*field.message_type(), value);
        return;
      }
      if (!value.is_string()) return;
      const std::string text = value.get<std::string>();
      try {
        if (field.cpp_type() == FieldDescriptor::CPPTYPE_INT64)
          value = int64_t(std::stoll(text));
        else if (field.cpp_type() == FieldDescriptor::CPPTYPE_UINT64)
          value = uint64_t(std::stoull(text));
      } catch (const std::exception&) {
        // Not a number after all: left as printed.
      }
    };
    if (field.is_repeated() && found->is_array())
      for (nlohmann::json& element : *found) convert(element);
    else
      convert(*found);
  }
}

std::string to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string json;
  auto status = google::protobuf::util::MessageToJsonString(message, &json, options);
  if (!status.ok()) throw std::runtime_error("JSON encoding failed: " + status.ToString());
  nlohmann::json document = nlohmann::json::parse(json);
  int64_as_numbers(*message.GetDescriptor(), document);
  return document.dump();
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
    case FarmErrorCode::AlreadyExists:
      return 409;
    case FarmErrorCode::Internal:
      return 500;
  }
  return 500;
}

// Runs a handler body; an exception becomes fail(HTTP status, message): a domain error's own
// status, 500 for anything else.
template <typename Body, typename Fail>
void run_guarded(Body&& body, Fail&& fail) {
  try {
    body();
  } catch (const FarmError& error) {
    fail(http_status(error.code()), error.what());
  } catch (const std::exception& error) {
    fail(500, error.what());
  }
}

// Runs a handler body; domain errors become their HTTP status with a JSON error body.
template <typename Body>
void guarded(httplib::Response& response, Body&& body) {
  run_guarded(body, [&](int status, const std::string& message) {
    response.status = status;
    response.set_content(nlohmann::json{{"error", message}}.dump() + "\n", "application/json");
  });
}

void set_json(httplib::Response& response, const std::string& json) {
  response.set_header("Cache-Control", "no-store");
  response.set_content(json + "\n", "application/json");
}

// A page for a domain error: the error's HTTP status and message.
template <typename Body>
void guarded_page(httplib::Response& response, Body&& body, const std::string& link_query = "") {
  run_guarded(body, [&](int status, const std::string& message) {
    response.status = status;
    response.set_content(error_page_html(status, message, link_query), "text/html; charset=utf-8");
  });
}

// A query parameter's value percent-encoded (RFC 3986 unreserved characters kept).
std::string percent_encode(const std::string& text) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

bool is_page(const std::string& path) {
  return path == "/" || path.rfind("/jobs/", 0) == 0 || path.rfind("/batches/", 0) == 0;
}

// What a page appends to its links: the token when the request brought it in the address.
std::string link_query(const HttpAuthorization& authorization, const httplib::Request& request) {
  if (!authorization.token_from_query) return "";
  return "?token=" + percent_encode(request.get_param_value("token"));
}

// The comparison viewer of a batch's images as the coordinator holds them: the reference EXR and,
// per method that ran, the image of its run with the most passes (lowest repeat first): the result
// when that job is done, else its image so far.
// Empty with a note when there is nothing to show yet.
std::string batch_viewer_html(Coordinator& coordinator, BatchManager& batches,
                              const v1::BatchStatus& status, std::string& note) {
  std::string exr;
  try {
    exr = batches.reference_exr(status.batch_id());
  } catch (const std::exception& error) {
    note = std::string("No viewer yet: the reference is not ready (") + error.what() + ").";
    return "";
  }
  Image reference_variance;
  Image reference = decode_exr(exr, nullptr, &reference_variance);
  std::map<std::string, Region> regions;
  ComparisonViewerContent content;
  content.width = reference.width;
  content.height = reference.height;
  for (const v1::BatchRegion& region : status.regions()) {
    Region rect{region.rect().x0(), region.rect().y0(), region.rect().x1(), region.rect().y1()};
    regions[region.name()] = rect;
    content.regions.push_back({region.name(), rect});
  }
  content.reference = {"reference",
                       status.reference().method(),
                       status.reference().sampler(),
                       status.reference().spp(),
                       0,
                       0,
                       &reference,
                       {},
                       {},
                       0,
                       reference_variance.width ? &reference_variance : nullptr};
  std::vector<Image> images, variances;
  images.reserve(size_t(status.methods_size()));
  variances.reserve(size_t(status.methods_size()));
  for (const v1::BatchMethodStatus& method : status.methods()) {
    const v1::BatchRun* shown = nullptr;
    for (const v1::BatchRun& run : method.runs())
      if (!run.job_id().empty() && run.job().passes_complete() > 0 &&
          (!shown || run.job().passes_complete() > shown->job().passes_complete()))
        shown = &run;
    if (!shown) continue;
    // A finished job's image is its result; a running one's the sealed passes so far.
    Film film = shown->job().state() == v1::JOB_STATE_DONE
                    ? coordinator.result_film(shown->job_id())
                    : coordinator.preview_film(shown->job_id());
    if (film.color.width != reference.width || film.color.height != reference.height) continue;
    images.push_back(std::move(film.color));
    variances.push_back(std::move(film.variance));
    ViewerImage image;
    image.label = method.label();
    image.method = method.method();
    image.sampler = method.sampler();
    image.spp = shown->job().passes_complete();
    image.repeat = int(shown->repeat());
    image.compute_seconds = shown->job().compute_seconds();
    image.image = &images.back();
    image.variance = variances.back().width == reference.width ? &variances.back() : nullptr;
    for (const auto& [region, summary] : error_summary(images.back(), reference, regions))
      image.mrse[region] = summary.mrse;
    content.methods.push_back(std::move(image));
  }
  if (content.methods.empty()) {
    note = "No viewer yet: no run has a complete pass.";
    return "";
  }
  // The scales as the static report chooses them (core/report/comparison_viewer.h).
  choose_viewer_scales(content);
  note.clear();
  return comparison_viewer_html(content);
}

// The comparison viewer of one job: its image (the result when it has one, else the sealed passes
// so far) and its reference when it has one, with the regions of its scene. Empty with a note
// when there is nothing to show.
std::string job_viewer_html(Coordinator& coordinator, const v1::JobStatus& status,
                            std::string& note) {
  if (status.state() == v1::JOB_STATE_FAILED) {
    note = "No viewer: the job failed.";
    return "";
  }
  if (status.passes_complete() == 0) {
    note = "No viewer yet: no pass is complete.";
    return "";
  }
  uint32_t passes = 0;
  Film film = coordinator.preview_film(status.job_id(), &passes);
  ComparisonViewerContent content;
  content.width = film.color.width;
  content.height = film.color.height;
  const std::map<std::string, Region> regions = coordinator.regions(status.job_id());
  for (const auto& [name, rect] : regions) content.regions.push_back({name, rect});
  Image reference, reference_variance;
  if (std::optional<std::string> exr = coordinator.reference_exr(status.job_id())) {
    ImageMetadata metadata;
    reference = decode_exr(*exr, &metadata, &reference_variance);
    if (reference.width == content.width && reference.height == content.height) {
      content.reference.label = "reference";
      content.reference.method = metadata["penumbra:method"];
      content.reference.sampler = metadata["penumbra:sampler"];
      try {
        content.reference.spp = uint32_t(std::stoul(metadata["penumbra:spp"]));
      } catch (const std::exception&) {
        content.reference.spp = 0;  // an uploaded EXR of another renderer
      }
      content.reference.image = &reference;
      if (reference_variance.width == content.width)
        content.reference.variance = &reference_variance;
    }
  }
  ViewerImage image;
  image.label = status.method();
  image.method = status.method();
  image.sampler = status.sampler();
  image.spp = passes;
  image.compute_seconds = status.compute_seconds();
  image.image = &film.color;
  image.variance = film.variance.width == content.width ? &film.variance : nullptr;
  if (content.reference.image)
    for (const auto& [region, summary] : error_summary(film.color, reference, regions))
      image.mrse[region] = summary.mrse;
  content.methods.push_back(std::move(image));
  // The scales as the static report chooses them (core/report/comparison_viewer.h).
  choose_viewer_scales(content);
  note.clear();
  return comparison_viewer_html(content);
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

namespace {

// Counts per second between the newest sample and the oldest inside `window` (or the oldest).
double rate_over(
    const std::deque<std::pair<std::chrono::steady_clock::time_point, uint64_t>>& samples,
    std::chrono::seconds window) {
  if (samples.size() < 2) return 0;
  const auto& newest = samples.back();
  auto oldest = samples.front();
  for (const auto& sample : samples)
    if (newest.first - sample.first <= window) {
      oldest = sample;
      break;
    }
  double seconds = std::chrono::duration<double>(newest.first - oldest.first).count();
  if (seconds <= 0 || newest.second < oldest.second) return 0;
  return double(newest.second - oldest.second) / seconds;
}

}  // namespace

double FarmMonitor::completion_rate(std::chrono::seconds window) {
  std::lock_guard lock(mutex_);
  return completion_rate_locked(window);
}

double FarmMonitor::completion_rate_locked(std::chrono::seconds window) const {
  return rate_over(completions_, window);
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

namespace {

std::unique_ptr<httplib::Server> make_server(const HttpFrontendOptions& options) {
  if (options.tls_cert.empty() != options.tls_key.empty())
    throw std::runtime_error("HTTP: TLS needs both a certificate and its key");
  if (options.tls_cert.empty()) return std::make_unique<httplib::Server>();
  auto server =
      std::make_unique<httplib::SSLServer>(options.tls_cert.c_str(), options.tls_key.c_str());
  if (!server->is_valid())
    throw std::runtime_error("HTTP: cannot use the TLS certificate " + options.tls_cert +
                             " with the key " + options.tls_key);
  return server;
}

}  // namespace

HttpFrontend::HttpFrontend(Coordinator& coordinator, const HttpFrontendOptions& options)
    : coordinator_(coordinator),
      batches_(options.batches),
      tokens_(options.tokens),
      open_metrics_(options.open_metrics),
      monitor_(coordinator),
      server_(make_server(options)) {
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

HttpAuthorization HttpFrontend::authorize(const httplib::Request& request) const {
  std::optional<std::string> header, parameter;
  if (request.has_header("Authorization")) header = request.get_header_value("Authorization");
  if (request.has_param("token")) parameter = request.get_param_value("token");
  return authorize_http(tokens_.get(),
                        header ? std::optional<std::string_view>(*header) : std::nullopt,
                        parameter ? std::optional<std::string_view>(*parameter) : std::nullopt);
}

void HttpFrontend::route() {
  httplib::Server& server = *server_;
  server.set_default_headers({{"Referrer-Policy", "no-referrer"},
                              {"X-Content-Type-Options", "nosniff"},
                              {"X-Frame-Options", "DENY"}});
  // Every request is checked before routing (an unknown path without a token is 401 too, so the
  // routes say nothing to a caller without one); the handlers then ask whose it is.
  server.set_pre_routing_handler([this](const httplib::Request& request,
                                        httplib::Response& response) {
    using Result = httplib::Server::HandlerResponse;
    if (request.path == "/healthz" || (request.path == "/metrics" && open_metrics_))
      return Result::Unhandled;
    HttpAuthorization authorization = authorize(request);
    int status = authorization.status;
    std::string message = authorization.message;
    if (status == 200 && request.path == "/metrics" && !authorization.sees_farm) {
      status = 403;
      message = "/metrics names every client's jobs: it needs a viewer or admin token";
    }
    if (status == 200) return Result::Unhandled;
    response.status = status;
    if (status == 401) response.set_header("WWW-Authenticate", "Bearer realm=\"penumbra\"");
    response.set_header("Cache-Control", "no-store");
    if (is_page(request.path))
      response.set_content(error_page_html(status, message), "text/html; charset=utf-8");
    else
      response.set_content(nlohmann::json{{"error", message}}.dump() + "\n", "application/json");
    return Result::Handled;
  });
  server.Get("/", [this](const httplib::Request& request, httplib::Response& response) {
    guarded(response, [&] {
      HttpAuthorization authorization = authorize(request);
      // The first state is rendered here: the page shows the farm without JavaScript too.
      DashboardSnapshot snapshot;
      snapshot.jobs = coordinator_.list(authorization.caller);
      if (authorization.token_from_query)
        snapshot.token_parameter = percent_encode(request.get_param_value("token"));
      snapshot.workers = coordinator_.workers();
      CoordinatorCounters counters = coordinator_.counters();
      snapshot.queue_depth = counters.queued_tasks;
      snapshot.leased_tasks = counters.leased_tasks;
      snapshot.tasks_completed = counters.tasks_completed;
      std::time_t now = std::time(nullptr);
      char text[32];
      std::strftime(text, sizeof text, "%H:%M:%S", std::localtime(&now));
      snapshot.updated = std::string(text) + " (server)";
      response.set_header("Cache-Control", "no-store");
      response.set_content(dashboard_page(snapshot), "text/html; charset=utf-8");
    });
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
  server.Get("/api/jobs", [this](const httplib::Request& request, httplib::Response& response) {
    guarded(response, [&] {
      v1::ListJobsResponse list;
      for (v1::JobStatus& job : coordinator_.list(authorize(request).caller))
        *list.add_jobs() = std::move(job);
      set_json(response, to_json(list));
    });
  });
  server.Get(R"(/api/jobs/([A-Za-z0-9_.-]+))", [this](const httplib::Request& request,
                                                      httplib::Response& response) {
    guarded(response, [&] {
      set_json(response,
               to_json(coordinator_.status(authorize(request).caller, request.matches[1], true)));
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
      coordinator_.status(authorize(request).caller, request.matches[1], false);  // NotFound
      uint32_t passes = 0;
      Film film = coordinator_.preview_film(request.matches[1], &passes);
      response.set_header("Cache-Control", "no-store");
      response.set_header("X-Penumbra-Passes", std::to_string(passes));
      response.set_content(encode_png_preview(film.color, exposure), "image/png");
    });
  });
  server.Get(R"(/jobs/([A-Za-z0-9_.-]+))", [this](const httplib::Request& request,
                                                  httplib::Response& response) {
    HttpAuthorization authorization = authorize(request);
    std::string query = link_query(authorization, request);
    guarded_page(
        response,
        [&] {
          v1::JobStatus status =
              coordinator_.status(authorization.caller, request.matches[1], true);
          // A running job's page refreshes itself, which would reset the viewer: it has the
          // viewer only when asked (?viewer=1), and offers it otherwise.
          JobPageViewer viewer;
          if (is_terminal(status.state()) || request.get_param_value("viewer") == "1")
            viewer.html = job_viewer_html(coordinator_, status, viewer.note);
          else if (status.passes_complete() > 0)
            viewer.offer = true;
          else
            viewer.note = "No viewer yet: no pass is complete.";
          response.set_header("Cache-Control", "no-store");
          response.set_content(
              job_page_html(status, query, coordinator_.job_workers(status.job_id()), viewer),
              "text/html; charset=utf-8");
        },
        query);
  });
  server.Get(R"(/batches/([A-Za-z0-9_.-]+))",
             [this](const httplib::Request& request, httplib::Response& response) {
               HttpAuthorization authorization = authorize(request);
               std::string query = link_query(authorization, request);
               guarded_page(
                   response,
                   [&] {
                     if (!batches_)
                       throw FarmError(FarmErrorCode::NotFound, "this server has no batches");
                     v1::BatchStatus status =
                         batches_->status(request.matches[1], false, authorization.caller);
                     std::string note;
                     std::string viewer = batch_viewer_html(coordinator_, *batches_, status, note);
                     response.set_header("Cache-Control", "no-store");
                     response.set_content(batch_page_html(status, viewer, note, query),
                                          "text/html; charset=utf-8");
                   },
                   query);
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
