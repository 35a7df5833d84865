// The coordinator's HTTP frontend as a process: /metrics scraped over HTTP and parsed by the
// Prometheus reference parser, with values that move when a job runs; /healthz; the JSON API
// (jobs, a job with its error curve, workers); the preview PNG; error statuses.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "server/http_frontend.h"
#include "tests/deploy/deploy_test_support.h"

namespace penumbra::farm::testing {
namespace {

// Width and height of a PNG from its IHDR chunk (the bytes after the 8-byte signature).
std::pair<uint32_t, uint32_t> png_size(const std::string& bytes) {
  auto be32 = [&](size_t at) {
    return uint32_t(uint8_t(bytes[at])) << 24 | uint32_t(uint8_t(bytes[at + 1])) << 16 |
           uint32_t(uint8_t(bytes[at + 2])) << 8 | uint32_t(uint8_t(bytes[at + 3]));
  };
  if (bytes.size() < 24 || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 ||
      bytes.compare(12, 4, "IHDR") != 0)
    return {0, 0};
  return {be32(16), be32(20)};
}

TEST(HttpMetrics, ParseHttpAddress) {
  EXPECT_EQ(parse_http_address("9100").host, "127.0.0.1");
  EXPECT_EQ(parse_http_address("9100").port, 9100);
  EXPECT_EQ(parse_http_address(":9100").host, "127.0.0.1");
  EXPECT_EQ(parse_http_address("0.0.0.0:80").host, "0.0.0.0");
  EXPECT_EQ(parse_http_address("[::1]:8080").host, "::1");
  EXPECT_EQ(parse_http_address("[::1]:8080").port, 8080);
  EXPECT_THROW(parse_http_address("host:"), std::invalid_argument);
  EXPECT_THROW(parse_http_address("host:99999"), std::invalid_argument);
  EXPECT_THROW(parse_http_address("host:12a"), std::invalid_argument);
  EXPECT_THROW(parse_http_address("[::1]8080"), std::invalid_argument);
}

TEST(HttpMetrics, ScrapedMetricsMoveWhenAJobRuns) {
  auto dir = fresh_directory("http-metrics");
  HttpCoordinator coordinator(dir / "coordinator");
  FarmClient client(coordinator.process.address());
  std::string scene = write_scene(dir, 64, 48);

  // Before any job: every family present with its type, counters at zero.
  Scrape before = parse_prometheus(coordinator.get("/metrics").body, dir);
  std::map<std::string, std::string> expected_types = {
      {"penumbra_queue_depth", "gauge"},
      {"penumbra_leased_tasks", "gauge"},
      {"penumbra_tasks_leased", "counter"},
      {"penumbra_tasks_completed", "counter"},
      {"penumbra_tasks_failed", "counter"},
      {"penumbra_late_results", "counter"},
      {"penumbra_leases_expired", "counter"},
      {"penumbra_jobs_submitted", "counter"},
      {"penumbra_tasks_completed_per_second", "gauge"},
      {"penumbra_job_latency_seconds", "histogram"},
      {"penumbra_jobs", "gauge"},
      {"penumbra_workers_active", "gauge"},
      {"penumbra_workers_registered", "gauge"},
      {"penumbra_worker_threads_active", "gauge"}};
  for (const auto& [family, type] : expected_types) {
    ASSERT_TRUE(before.family_types.count(family)) << family << " missing";
    EXPECT_EQ(before.family_types.at(family), type) << family;
  }
  EXPECT_EQ(before.value("penumbra_tasks_completed_total"), 0);
  EXPECT_EQ(before.value("penumbra_job_latency_seconds_count"), 0);
  EXPECT_EQ(before.value("penumbra_workers_active"), 0);

  // A reference job and a job scored against it, queued before any worker exists.
  std::string reference = client.submit(job_spec(scene, "sa", 8, 5)).job_id();
  v1::JobSpec spec = job_spec(scene, "sa", 16, 7, 16, 4);
  spec.set_reference_job(reference);
  spec.set_name("metrics \"test\"");
  std::string job = client.submit(spec).job_id();
  v1::JobStatus queued = client.status(job);
  Scrape waiting = parse_prometheus(coordinator.get("/metrics").body, dir);
  EXPECT_EQ(waiting.value("penumbra_jobs_submitted_total"), 2);
  EXPECT_GE(waiting.value("penumbra_queue_depth"), double(queued.tasks_total()));
  EXPECT_EQ(waiting.value("penumbra_jobs", {{"state", "queued"}}), 2);

  auto worker = start_worker(coordinator.process.address(), dir, "metrics-worker", 2);
  v1::JobStatus done = client.wait(job, std::chrono::seconds(60));
  ASSERT_EQ(done.state(), v1::JOB_STATE_DONE) << done.error();
  v1::JobStatus reference_done = client.status(reference);
  // The monitor samples every 200 ms: wait until it has seen both jobs finish.
  Scrape after;
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    after = parse_prometheus(coordinator.get("/metrics").body, dir);
  } while (after.value("penumbra_job_latency_seconds_count") < 2 &&
           std::chrono::steady_clock::now() < deadline);

  double tasks = double(done.tasks_total() + reference_done.tasks_total());
  EXPECT_EQ(after.value("penumbra_tasks_completed_total"), tasks);
  EXPECT_GE(after.value("penumbra_tasks_leased_total"), tasks);
  EXPECT_EQ(after.value("penumbra_queue_depth"), 0);
  EXPECT_EQ(after.value("penumbra_leased_tasks"), 0);
  EXPECT_EQ(after.value("penumbra_jobs", {{"state", "done"}}), 2);
  EXPECT_EQ(after.value("penumbra_workers_active"), 1);
  EXPECT_EQ(after.value("penumbra_worker_threads_active"), 2);
  // Per-worker families have samples once a worker registered.
  EXPECT_EQ(after.family_types["penumbra_worker_tasks_completed"], "counter");
  EXPECT_EQ(after.family_types["penumbra_worker_tasks_leased"], "gauge");
  EXPECT_EQ(after.value("penumbra_worker_tasks_completed_total", {{"name", "metrics-worker"}}),
            tasks);
  EXPECT_GT(after.value("penumbra_tasks_completed_per_second"), 0);
  // Latency histogram: both jobs observed, cumulative buckets, +Inf equals the count.
  EXPECT_EQ(after.value("penumbra_job_latency_seconds_count"), 2);
  EXPECT_EQ(after.value("penumbra_job_latency_seconds_bucket", {{"le", "+Inf"}}), 2);
  EXPECT_GT(after.value("penumbra_job_latency_seconds_sum"), 0);
  EXPECT_LE(after.value("penumbra_job_latency_seconds_bucket", {{"le", "0.5"}}),
            after.value("penumbra_job_latency_seconds_bucket", {{"le", "60"}}));
  EXPECT_EQ(after.value("penumbra_leases_expired_total"), 0);
  EXPECT_EQ(after.value("penumbra_late_results_total"), 0);

  // JSON API.
  auto jobs = nlohmann::json::parse(coordinator.get("/api/jobs").body);
  ASSERT_EQ(jobs["jobs"].size(), 2u);
  EXPECT_EQ(jobs["jobs"][1]["job_id"], job);
  EXPECT_EQ(jobs["jobs"][1]["name"], "metrics \"test\"");
  EXPECT_EQ(jobs["jobs"][1]["state"], "JOB_STATE_DONE");
  auto detail = nlohmann::json::parse(coordinator.get("/api/jobs/" + job).body);
  EXPECT_EQ(detail["passes_complete"], 16);
  ASSERT_EQ(detail["curve"].size(), size_t(client.status(job).curve_size()));
  ASSERT_GE(detail["curve"].size(), 2u);  // one point per sealed block of 4 passes
  EXPECT_GT(detail["curve"][0]["mrse"].get<double>(), 0);
  auto workers = nlohmann::json::parse(coordinator.get("/api/workers").body);
  ASSERT_EQ(workers["workers"].size(), 1u);
  EXPECT_EQ(workers["workers"][0]["name"], "metrics-worker");
  auto summary = nlohmann::json::parse(coordinator.get("/api/summary").body);
  EXPECT_EQ(summary["tasks_completed"].get<double>(), tasks);

  // Preview PNG of the job's image, at its resolution.
  HttpReply preview = coordinator.get("/api/jobs/" + job + "/preview.png");
  ASSERT_EQ(preview.status, 200);
  EXPECT_EQ(preview.content_type, "image/png");
  EXPECT_EQ(png_size(preview.body), std::make_pair(64u, 48u));
  EXPECT_EQ(preview.headers["X-Penumbra-Passes"], "16");
  // The finished job's image itself (not black): the very bytes `penumbra render` would write as
  // the preview of the job's EXR (one encoder).
  EXPECT_EQ(preview.body, encode_png_preview(decode_exr(client.fetch(job))));

  // Errors: unknown job 404, bad exposure 400, unknown path 404; the dashboard page is HTML.
  EXPECT_EQ(coordinator.get("/api/jobs/job-999").status, 404);
  EXPECT_EQ(coordinator.get("/api/jobs/job-999/preview.png").status, 404);
  EXPECT_EQ(coordinator.get("/api/jobs/" + job + "/preview.png?exposure=-1").status, 400);
  EXPECT_EQ(coordinator.get("/nothing-here").status, 404);
  HttpReply page = coordinator.get("/");
  EXPECT_EQ(page.status, 200);
  EXPECT_NE(page.body.find("<svg id=\"chart\""), std::string::npos);
  // Rendered on the server (no script has run): both jobs, the worker, the preview, the summary.
  EXPECT_NE(
      page.body.find("<tr class=\"job selected\" data-job-id=\"" + job + "\" data-state=\"done\""),
      std::string::npos)
      << page.body.substr(0, 6000);
  EXPECT_NE(page.body.find("data-job-id=\"" + reference + "\""), std::string::npos);
  EXPECT_NE(page.body.find("metrics &quot;test&quot;"), std::string::npos) << "escaped name";
  EXPECT_NE(page.body.find("<tr class=\"worker\" data-worker-id=\"metrics-worker\" "
                           "data-alive=\"true\">"),
            std::string::npos);
  EXPECT_NE(page.body.find("<img id=\"preview\" src=\"/api/jobs/" + job + "/preview.png"),
            std::string::npos);
  EXPECT_EQ(page.body.find("loading&hellip;"), std::string::npos);

  // 64-bit integers are JSON numbers, exactly.
  EXPECT_TRUE(jobs["jobs"][1]["submitted_unix_ms"].is_number_integer());
  EXPECT_EQ(jobs["jobs"][1]["submitted_unix_ms"].get<int64_t>(),
            client.status(job).submitted_unix_ms());
  EXPECT_TRUE(detail["tasks_total"].is_number_integer());
  EXPECT_EQ(detail["tasks_total"].get<uint64_t>(), client.status(job).tasks_total());
  EXPECT_TRUE(detail["seed"].is_number_integer());
  EXPECT_TRUE(workers["workers"][0]["tasks_completed"].is_number_integer());

  worker->signal(SIGTERM);
  worker->wait_exit(std::chrono::seconds(20));
  std::filesystem::remove_all(dir);
}

TEST(HttpMetrics, ParserRejectsMalformedText) {
  // The parser check can fail: a sample line with a broken value is rejected.
  auto dir = fresh_directory("http-metrics-bad");
  EXPECT_THROW(parse_prometheus("# TYPE x counter\nx_total one\n", dir), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm::testing
