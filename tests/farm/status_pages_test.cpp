// The coordinator's job and batch pages: the HTML built from status messages (state, progress,
// errors escaped, preview, tasks by state, workers with their throughput, the report's
// convergence charts, runs linked to their jobs, refusals, self-refresh only while running and
// never over the viewer), and the routes served by a real coordinator's HTTP side (a job's
// page with its tasks and workers, 404 pages).
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/status_pages.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include "fake_worker.h"
#include "farm_test_support.h"
#include "proto/support/scene_packing.h"
#include "server/coordinator.h"
#include "server/http_frontend.h"

namespace penumbra::farm {
namespace {

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
  std::vector<JobPageWorker> workers(2);
  workers[0].info.set_worker_id("w-1");
  workers[0].info.set_name("box <1>");
  workers[0].info.set_alive(true);
  workers[0].info.set_threads(8);
  workers[0].info.set_tasks_completed(120);
  workers[0].info.set_tasks_leased(2);
  workers[0].recent_tasks_per_second = 1.5;
  workers[1].info.set_worker_id("w-2");
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
  // Workers: escaped names, the tasks they hold and the recent rate; a lost one says so.
  EXPECT_NE(html.find("<tr data-worker=\"w-1\"><td class=\"text\">box &lt;1&gt;</td><td "
                      "class=\"text\">alive</td><td>8</td><td>2</td><td>1.5</td><td>120</td>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<tr data-worker=\"w-2\"><td class=\"text\">w-2</td><td "
                      "class=\"text\">lost</td>"),
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
  EXPECT_NE(page->body.find("No worker has registered."), std::string::npos) << page->body;

  // A worker that completes one of its two tasks: its row on the page, and its rate over the
  // monitor's samples (one completion between two samples).
  FarmMonitor monitor(coordinator);
  const std::string worker = testing::register_fake_worker(coordinator, "page-worker");
  monitor.sample();
  std::vector<v1::Task> tasks = testing::lease_tasks(coordinator, worker, 2);
  ASSERT_EQ(tasks.size(), 2u);
  ASSERT_TRUE(testing::complete_fake_task(coordinator, worker, tasks[0], 0.5));
  const auto before = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  monitor.sample();
  const double rate = monitor.worker_rates().at(worker);
  EXPECT_GT(rate, 0.0);
  EXPECT_LE(rate,
            1.0 / std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count());
  page = client.Get("/jobs/" + job);
  ASSERT_TRUE(page);
  EXPECT_NE(page->body.find("<tr data-worker=\"" + worker +
                            "\"><td class=\"text\">page-worker</td><td class=\"text\">alive</td>"
                            "<td>1</td><td>1</td>"),
            std::string::npos)
      << page->body;
  EXPECT_NE(page->body.find("data-complete=\"1\" data-leased=\"1\""), std::string::npos);
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
