// The coordinator's job and batch pages: the HTML built from status messages (state, progress,
// errors escaped, preview, tasks by state, workers with their throughput, the report's
// convergence charts, runs linked to their jobs, refusals, self-refresh only while running and
// never over the viewer), and the routes served by a real coordinator's HTTP side (a job's
// page with its tasks, this job's workers and their counts, its comparison viewer with and
// without a reference, 404 pages).
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/status_pages.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <nlohmann/json.hpp>

#include "core/image/metrics.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "core/report/comparison_viewer.h"
#include "fake_worker.h"
#include "farm_test_support.h"
#include "proto/support/scene_packing.h"
#include "server/coordinator.h"
#include "server/http_frontend.h"

namespace penumbra::farm {
namespace {

// The comparison viewer's data in a page (the JSON of its <script id="viewer-data">), or null.
nlohmann::json viewer_data(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"viewer-data\">";
  const size_t begin = html.find(open);
  if (begin == std::string::npos) return nullptr;
  const size_t end = html.find("</script>", begin);
  if (end == std::string::npos) return nullptr;
  return nlohmann::json::parse(html.substr(begin + open.size(), end - begin - open.size()));
}

v1::JobStatus running_job() {
  v1::JobStatus status;
  status.set_job_id("job-7");
  status.set_name("a <b> job");
  status.set_state(v1::JOB_STATE_RUNNING);
  status.set_scene_name("box");
  status.set_width(40);
  status.set_height(24);
  status.set_method("sa");
  status.set_sampler("stratified");
  status.set_spp_budget(16);
  status.set_passes_complete(8);
  status.set_passes_planned(16);
  status.set_tasks_total(4);
  status.set_tasks_complete(1);
  status.set_tasks_leased(2);
  status.set_wall_seconds(2);
  status.set_compute_seconds(3.5);
  for (uint32_t passes : {2u, 4u, 8u}) {
    v1::ErrorSample* sample = status.add_curve();
    sample->set_passes(passes);
    sample->set_compute_seconds(0.5 * passes);
    sample->set_mrse(1.0 / passes);
  }
  return status;
}

TEST(StatusPages, JobPageShowsProgressPreviewChartAndRefreshesWhileRunning) {
  std::vector<JobWorkerActivity> workers(3);
  workers[0].worker_id = "w-1";
  workers[0].name = "box <1>";
  workers[0].registered = true;
  workers[0].alive = true;
  workers[0].threads = 8;
  workers[0].tasks_completed = 120;
  workers[0].tasks_leased = 2;
  workers[0].compute_seconds = 61.25;
  workers[0].recent_tasks_per_second = 1.5;
  workers[1].worker_id = "w-2";
  workers[1].registered = true;
  workers[2].worker_id = "w-3";
  std::string html = job_page_html(running_job(), "", workers);
  EXPECT_NE(html.find("<title>Job job-7: a &lt;b&gt; job</title>"), std::string::npos);
  EXPECT_NE(html.find("<meta http-equiv=\"refresh\" content=\"2\">"), std::string::npos);
  EXPECT_NE(html.find("data-state=\"running\" data-passes=\"8\""), std::string::npos);
  EXPECT_NE(html.find("width:25.0%"), std::string::npos);  // 1 of 4 tasks
  EXPECT_NE(html.find("8 complete of 16 planned"), std::string::npos);
  EXPECT_NE(html.find("4 spp/s"), std::string::npos);  // 8 passes in 2 wall s
  EXPECT_NE(html.find("ETA 6 s"), std::string::npos);  // 2 s x (1 - 1/4) / (1/4)
  EXPECT_NE(html.find("src=\"/api/jobs/job-7/preview.png\""), std::string::npos);
  // Tasks by state: 1 complete, 2 leased, 1 waiting of the 4 opened.
  EXPECT_NE(html.find("data-complete=\"1\" data-leased=\"2\" data-waiting=\"1\""),
            std::string::npos);
  // Workers: escaped names, this job's tasks they hold, the recent rate, this job's tasks done
  // and their compute seconds; a lost one and a forgotten one say so.
  EXPECT_NE(html.find("<tr data-worker=\"w-1\"><td class=\"text\">box &lt;1&gt;</td><td "
                      "class=\"text\">alive</td><td>8</td><td>2</td><td>1.5</td><td>120</td>"
                      "<td>61.2</td></tr>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<tr data-worker=\"w-2\"><td class=\"text\">w-2</td><td "
                      "class=\"text\">lost</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<tr data-worker=\"w-3\"><td class=\"text\">w-3</td><td "
                      "class=\"text\">forgotten</td>"),
            std::string::npos);
  // Both convergence charts, as SVG data URIs.
  size_t charts = 0;
  for (size_t at = html.find("<img class=\"chart\""); at != std::string::npos;
       at = html.find("<img class=\"chart\"", at + 1))
    ++charts;
  EXPECT_EQ(charts, 2u);
  EXPECT_NE(html.find("alt=\"MRSE against spp, full image\" src=\"data:image/svg+xml;base64,"),
            std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);

  // Running, with passes: the viewer is offered on the same page with ?viewer=1 (after the
  // token), since this page refreshes itself.
  JobPageViewer offered;
  offered.offer = true;
  html = job_page_html(running_job(), "?token=a%2Bb", {}, offered);
  EXPECT_NE(html.find("<meta http-equiv=\"refresh\""), std::string::npos);
  EXPECT_NE(html.find("<a id=\"open-viewer\" href=\"/jobs/job-7?token=a%2Bb&amp;viewer=1\">"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("No worker has leased a task of this job."), std::string::npos);
  // With the viewer: no refresh (it would reset the viewer), a link to reload instead.
  JobPageViewer shown;
  shown.html = "<section id=\"viewer\"></section>";
  html = job_page_html(running_job(), "", {}, shown);
  EXPECT_EQ(html.find("http-equiv=\"refresh\""), std::string::npos);
  EXPECT_NE(html.find("this page shows the image at 8 spp; <a href=\"/jobs/job-7?viewer=1\">"
                      "reload</a>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<section id=\"viewer\"></section>"), std::string::npos);
  JobPageViewer none;
  none.note = "No viewer yet: <none>";
  html = job_page_html(running_job(), "", {}, none);
  EXPECT_NE(html.find("<p class=\"note\">No viewer yet: &lt;none&gt;</p>"), std::string::npos);

  v1::JobStatus failed = running_job();
  failed.set_state(v1::JOB_STATE_FAILED);
  failed.set_error("worker said <no>");
  html = job_page_html(failed);
  EXPECT_EQ(html.find("http-equiv=\"refresh\""), std::string::npos);
  EXPECT_NE(html.find("<span class=\"error\">worker said &lt;no&gt;</span>"), std::string::npos);
}

TEST(StatusPages, ConvergenceChartsAreTheReportsOfTheJobsCurve) {
  v1::JobStatus status = running_job();
  std::vector<ChartSpec> charts = job_convergence_charts(status);
  ASSERT_EQ(charts.size(), 2u);
  // Against compute seconds: the curve's points (0.5 s per pass), log-log.
  EXPECT_TRUE(charts[0].log_x && charts[0].log_y);
  EXPECT_EQ(charts[0].x_label, "compute seconds");
  ASSERT_EQ(charts[0].series.size(), 1u);
  EXPECT_EQ(charts[0].series[0].x, (std::vector<double>{1, 2, 4}));
  EXPECT_EQ(charts[0].series[0].y, (std::vector<double>{0.5, 0.25, 0.125}));
  // Against spp, with the fitted convergence rate: MRSE = 1 / spp has slope -1.
  EXPECT_EQ(charts[1].x_label, "samples per pixel");
  ASSERT_EQ(charts[1].series.size(), 1u);
  EXPECT_EQ(charts[1].series[0].x, (std::vector<double>{2, 4, 8}));
  ASSERT_TRUE(charts[1].series[0].fit.has_value());
  EXPECT_NEAR(charts[1].series[0].fit->slope, -1.0, 1e-12);
  EXPECT_NE(chart_svg(charts[1]).find("<svg"), std::string::npos);
  // No curve yet: no chart.
  status.clear_curve();
  EXPECT_TRUE(job_convergence_charts(status).empty());
}

TEST(StatusPages, BatchPageListsRunsRefusalsAndTheViewer) {
  v1::BatchStatus status;
  status.set_batch_id("batch-3");
  status.set_state(v1::BATCH_STATE_RUNNING);
  status.set_jobs_total(4);
  status.set_jobs_done(2);
  status.set_wall_seconds(10);
  v1::BatchMethodStatus* method = status.add_methods();
  method->set_label("sa");
  method->set_method("sa");
  v1::BatchRun* run = method->add_runs();
  run->set_job_id("job-9");
  run->mutable_job()->set_state(v1::JOB_STATE_DONE);
  run->mutable_job()->set_passes_complete(12);
  v1::BatchMethodStatus* refused = status.add_methods();
  refused->set_label("line-bd16");
  refused->set_error("material 'x' is ggx");
  std::string html = batch_page_html(status, "", "No viewer yet: the reference is not ready.");
  EXPECT_NE(html.find("<meta http-equiv=\"refresh\""), std::string::npos);
  EXPECT_NE(html.find("data-state=\"running\" data-jobs-done=\"2\""), std::string::npos);
  EXPECT_NE(html.find("(2 / 4 jobs)"), std::string::npos);
  EXPECT_NE(html.find("ETA 10 s"), std::string::npos);
  EXPECT_NE(html.find("<a href=\"/jobs/job-9\">job-9</a>"), std::string::npos);
  EXPECT_NE(html.find("refused: material &#39;x&#39; is ggx"), std::string::npos);
  EXPECT_NE(html.find("No viewer yet: the reference is not ready."), std::string::npos);
  // Running with the viewer: no refresh (it would reset the viewer), a link to reload instead.
  html = batch_page_html(status, "<section id=\"viewer\"></section>", "");
  EXPECT_EQ(html.find("http-equiv=\"refresh\""), std::string::npos);
  EXPECT_NE(html.find("this page shows the images at 10.0 wall s; <a href=\"/batches/batch-3\">"
                      "reload</a>"),
            std::string::npos)
      << html;
  status.set_state(v1::BATCH_STATE_DONE);
  html = batch_page_html(status, "<section id=\"viewer\"></section>", "");
  EXPECT_EQ(html.find("http-equiv=\"refresh\""), std::string::npos);
  EXPECT_EQ(html.find("reload"), std::string::npos);
  EXPECT_NE(html.find("<section id=\"viewer\"></section>"), std::string::npos);
}

TEST(StatusPages, CoordinatorServesJobPagesAndErrorPages) {
  auto dir = testing::fresh_directory("status-pages");
  CoordinatorOptions options;
  options.data_dir = (dir / "data").string();
  // Workers that only call when they lease or complete stay alive however slow the machine.
  options.lease_time = std::chrono::minutes(10);
  options.heartbeat_interval = std::chrono::minutes(1);
  Coordinator coordinator(options, parse_wire_package);
  std::string scene = testing::write_scene(dir, 40, 24);
  std::string job = coordinator.submit(testing::job_spec(scene, "sa", 8, 1, 16, 4)).job_id();
  HttpFrontend http(coordinator, HttpFrontendOptions{});
  httplib::Client client(http.host(), http.port());
  auto page = client.Get("/jobs/" + job);
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(page->body.find("data-state=\"queued\""), std::string::npos) << page->body;
  EXPECT_NE(page->body.find("0 complete of 8 planned"), std::string::npos) << page->body;
  EXPECT_NE(page->body.find("<table id=\"tasks\""), std::string::npos) << page->body;

  EXPECT_NE(page->body.find("No worker has leased a task of this job."), std::string::npos);

  // Worker 1 holds two of the job's tasks and completes one; worker 2 works on another job only.
  const std::string worker = testing::register_fake_worker(coordinator, "page-worker");
  const auto before_lease = std::chrono::steady_clock::now();
  std::vector<v1::Task> tasks = testing::lease_tasks(coordinator, worker, 2);
  ASSERT_EQ(tasks.size(), 2u);
  ASSERT_EQ(tasks[0].job_id(), job);
  ASSERT_TRUE(testing::complete_fake_task(coordinator, worker, tasks[0], 0.5));
  v1::JobSpec other_spec = testing::job_spec(scene, "sa", 4, 2, 16, 4);
  other_spec.set_priority(1);  // leased before the first job's remaining tasks
  const std::string other = coordinator.submit(other_spec).job_id();
  const std::string other_worker = testing::register_fake_worker(coordinator, "other-worker");
  std::vector<v1::Task> other_tasks = testing::lease_tasks(coordinator, other_worker, 6);
  ASSERT_EQ(other_tasks.size(), 6u);  // the other job's every task: 6 tiles, one block
  for (const v1::Task& task : other_tasks) {
    ASSERT_EQ(task.job_id(), other);
    ASSERT_TRUE(testing::complete_fake_task(coordinator, other_worker, task, 0.25));
  }
  std::vector<JobWorkerActivity> activity = coordinator.job_workers(job);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - before_lease).count();
  ASSERT_EQ(activity.size(), 1u);
  EXPECT_EQ(activity[0].worker_id, worker);
  EXPECT_EQ(activity[0].name, "page-worker");
  EXPECT_TRUE(activity[0].registered && activity[0].alive);
  EXPECT_EQ(activity[0].tasks_leased, 1u);
  EXPECT_EQ(activity[0].tasks_completed, 1u);
  EXPECT_DOUBLE_EQ(activity[0].compute_seconds, 0.5);
  // One completion over the worker's time on the job (at least a second).
  EXPECT_LE(activity[0].recent_tasks_per_second, 1.0);
  EXPECT_GE(activity[0].recent_tasks_per_second, 1.0 / std::max(1.0, elapsed));
  activity = coordinator.job_workers(other);
  ASSERT_EQ(activity.size(), 1u);
  EXPECT_EQ(activity[0].worker_id, other_worker);
  EXPECT_EQ(activity[0].tasks_leased, 0u);
  EXPECT_EQ(activity[0].tasks_completed, 6u);
  EXPECT_DOUBLE_EQ(activity[0].compute_seconds, 1.5);

  page = client.Get("/jobs/" + job);
  ASSERT_TRUE(page);
  EXPECT_NE(page->body.find("<tr data-worker=\"" + worker +
                            "\"><td class=\"text\">page-worker</td><td class=\"text\">alive</td>"
                            "<td>1</td><td>1</td>"),
            std::string::npos)
      << page->body;
  EXPECT_EQ(page->body.find("data-worker=\"" + other_worker + "\""), std::string::npos);
  EXPECT_NE(page->body.find("data-complete=\"1\" data-leased=\"1\""), std::string::npos);
  // Running without a complete pass: no viewer yet.
  EXPECT_NE(page->body.find("No viewer yet: no pass is complete."), std::string::npos);
  EXPECT_EQ(page->body.find("id=\"viewer-data\""), std::string::npos);

  // The other job is done: its page has the comparison viewer of its result, without a
  // reference, and lists only its own worker.
  page = client.Get("/jobs/" + other);
  ASSERT_TRUE(page);
  EXPECT_NE(page->body.find("data-state=\"done\""), std::string::npos);
  EXPECT_NE(page->body.find("data-worker=\"" + other_worker + "\""), std::string::npos);
  EXPECT_EQ(page->body.find("data-worker=\"" + worker + "\""), std::string::npos);
  nlohmann::json data = viewer_data(page->body);
  ASSERT_TRUE(data.is_object()) << page->body;
  EXPECT_TRUE(data["reference"].is_null());
  ASSERT_EQ(data["methods"].size(), 1u);
  EXPECT_EQ(data["methods"][0]["spp"], 4);
  EXPECT_EQ(data["methods"][0]["data"],
            base64_encode(encode_viewer_image(coordinator.result_film(other).color)));

  // A job measured against the other one: its viewer shows its image, that reference and the
  // scene's region, with the image's MRSE per region, as the report computes it.
  v1::JobSpec measured_spec = testing::job_spec(scene, "sa", 4, 3, 16, 4);
  measured_spec.set_reference_job(other);
  measured_spec.set_priority(2);
  const std::string measured = coordinator.submit(measured_spec).job_id();
  for (const v1::Task& task : testing::lease_tasks(coordinator, other_worker, 6)) {
    ASSERT_EQ(task.job_id(), measured);
    ASSERT_TRUE(testing::complete_fake_task(coordinator, other_worker, task, 0.25));
  }
  page = client.Get("/jobs/" + measured);
  ASSERT_TRUE(page);
  data = viewer_data(page->body);
  ASSERT_TRUE(data.is_object()) << page->body;
  const Film reference = coordinator.result_film(other);
  const Film image = coordinator.result_film(measured);
  EXPECT_EQ(data["reference"]["label"], "reference");
  EXPECT_EQ(data["reference"]["spp"], 4);
  EXPECT_EQ(data["reference"]["data"], base64_encode(encode_viewer_image(reference.color)));
  EXPECT_EQ(data["methods"][0]["data"], base64_encode(encode_viewer_image(image.color)));
  ASSERT_EQ(data["regions"].size(), 1u);
  EXPECT_EQ(data["regions"][0]["name"], "shadow");
  for (const auto& [region, summary] :
       error_summary(image.color, reference.color, {{"shadow", Region{8, 8, 24, 24}}}))
    EXPECT_DOUBLE_EQ(data["methods"][0]["mrse"][region].get<double>(), summary.mrse) << region;
  EXPECT_EQ(data["exposure"].get<double>(), choose_exposure(reference.color));

  auto missing = client.Get("/jobs/no-such-job");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_NE(missing->body.find("<h1>Error 404</h1>"), std::string::npos);
  auto batches = client.Get("/batches/batch-1");  // no batch manager given
  ASSERT_TRUE(batches);
  EXPECT_EQ(batches->status, 404);
  EXPECT_NE(batches->body.find("this server has no batches"), std::string::npos);
  http.stop();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(StatusPages, NeedsTheFarm) {
  GTEST_SKIP() << "built without the farm";
}
#endif
