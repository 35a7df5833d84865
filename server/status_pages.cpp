// The job and batch pages: HTML built from the status messages alone.

#include "server/status_pages.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/report/batch_charts.h"
#include "core/report/batch_html.h"
#include "proto/support/state_names.h"

namespace penumbra::farm {

namespace {

const char* kStyle = R"(
body { font-family: "DejaVu Sans", sans-serif; margin: 24px; color: #111; max-width: 1400px; }
h1 { font-size: 22px; } h2 { font-size: 17px; margin-top: 24px; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 13px; }
th, td { border: 1px solid #bbb; padding: 3px 8px; text-align: right; }
th { background: #eee; } td.text, th.text { text-align: left; }
.bar { width: 420px; height: 14px; border: 1px solid #888; background: #eee; display: inline-block;
  vertical-align: middle; } .bar span { display: block; height: 100%; background: #2c5d8f; }
.error { color: #a00; } .note { font-size: 12px; color: #444; }
.charts { display: flex; flex-wrap: wrap; gap: 12px; } figure { margin: 0; }
img.preview { border: 1px solid #888; image-rendering: pixelated; max-width: 100%; }
)";

bool finished(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}
bool finished(v1::BatchState state) {
  return state == v1::BATCH_STATE_DONE || state == v1::BATCH_STATE_FAILED ||
         state == v1::BATCH_STATE_CANCELLED;
}

std::string number(double value, const char* format = "%.4g") {
  char text[48];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

// Fraction done: tasks for an spp budget, compute seconds for a seconds budget.
double job_fraction(const v1::JobStatus& status) {
  if (status.state() == v1::JOB_STATE_DONE) return 1.0;
  if (status.spp_budget() && status.tasks_total())
    return double(status.tasks_complete()) / double(status.tasks_total());
  if (status.seconds_budget() > 0)
    return std::min(1.0, status.compute_seconds() / status.seconds_budget());
  return 0.0;
}

std::string bar(double fraction) {
  return "<span class=\"bar\"><span style=\"width:" + number(100 * fraction, "%.1f") +
         "%\"></span></span> " + number(100 * fraction, "%.0f") + "%";
}

std::string head(const std::string& title, bool refresh) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n" +
         std::string(refresh ? "<meta http-equiv=\"refresh\" content=\"2\">\n" : "") + "<title>" +
         html_escape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
}

void row(std::ostringstream& out, const std::string& key, const std::string& value_html) {
  out << "<tr><th class=\"text\">" << html_escape(key) << "</th><td class=\"text\">" << value_html
      << "</td></tr>\n";
}

}  // namespace

std::string chart_svg(const ChartSpec& spec) {
  // A name no other request (thread or process) uses at the same time.
  static std::atomic<uint64_t> counter{0};
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("penumbra-chart-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".svg");
  struct Remove {
    const std::filesystem::path& path;
    ~Remove() {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  } remove{path};
  write_line_chart(path.string(), spec);
  std::ifstream file(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (text.empty()) throw std::runtime_error("chart " + path.string() + ": cannot read it back");
  return text;
}

std::vector<ChartSpec> job_convergence_charts(const v1::JobStatus& status) {
  // A batch of this one run, so that the charts are the report's own.
  BatchResult result;
  BatchMethod method;
  method.label = status.method();
  method.method = status.method();
  method.sampler = status.sampler();
  BatchRun run;
  run.job_id = status.job_id();
  run.spp = status.passes_complete();
  run.compute_seconds = status.compute_seconds();
  run.wall_seconds = status.wall_seconds();
  for (const v1::ErrorSample& sample : status.curve())
    if (sample.mrse() > 0 && std::isfinite(sample.mrse()))
      run.curve.push_back(
          {sample.passes(), sample.compute_seconds(), sample.wall_seconds(), sample.mrse(), {}});
  if (run.curve.empty()) return {};
  ErrorSummary last;
  last.mrse = run.curve.back().mrse;
  run.errors["image"] = last;
  method.runs.push_back(run);
  result.methods.push_back(method);
  const RecomputedErrors recomputed = {{run.errors}};
  std::vector<ChartSpec> charts = {mrse_time_chart(result, recomputed),
                                   mrse_spp_chart(result, recomputed, "image")};
  for (ChartSpec& chart : charts) {
    chart.width = 480;
    chart.height = 340;
  }
  return charts;
}

std::string job_page_html(const v1::JobStatus& status, const std::string& link_query,
                          const std::vector<JobWorkerActivity>& workers,
                          const JobPageViewer& viewer) {
  const std::string q = html_escape(link_query);
  // This page with the viewer (?viewer=1 after the token, if any).
  const std::string with_viewer =
      "/jobs/" + html_escape(status.job_id()) + (q.empty() ? "?" : q + "&amp;") + "viewer=1";
  std::ostringstream out;
  const std::string title =
      "Job " + status.job_id() + (status.name().empty() ? "" : ": " + status.name());
  // A refresh would reset the viewer (its zoom and exposure): a running job's page with the
  // viewer links to its newer state instead.
  const bool running = !finished(status.state());
  out << head(title, running && viewer.html.empty()) << "<h1>" << html_escape(title) << "</h1>\n"
      << "<p class=\"note\"><a href=\"/" << q << "\">dashboard</a> · <a href=\"/api/jobs/"
      << html_escape(status.job_id()) << q << "\">JSON</a>";
  if (running && !viewer.html.empty())
    out << " · <span id=\"stale\">running: this page shows the image at "
        << status.passes_complete() << " spp; <a href=\"" << with_viewer
        << "\">reload</a> for the newer passes</span>";
  out << "</p>\n";
  out << "<table id=\"job\" data-state=\"" << farm::state_name(status.state())
      << "\" data-passes=\"" << status.passes_complete() << "\">\n";
  row(out, "state", "<b>" + farm::state_name(status.state()) + "</b>");
  if (!status.error().empty())
    row(out, "error", "<span class=\"error\">" + html_escape(status.error()) + "</span>");
  const double fraction = job_fraction(status);
  row(out, "progress", bar(fraction));
  row(out, "scene",
      html_escape(status.scene_name()) + " (" + std::to_string(status.width()) + "x" +
          std::to_string(status.height()) + ", <code>" + html_escape(status.scene_hash()) +
          "</code>)");
  row(out, "method",
      "<code>" + html_escape(status.method()) + "</code>, sampler " +
          html_escape(status.sampler()) + ", seed " + std::to_string(status.seed()) +
          ", priority " + std::to_string(status.priority()));
  row(out, "budget",
      status.spp_budget() ? std::to_string(status.spp_budget()) + " spp"
                          : number(status.seconds_budget()) + " compute s");
  row(out, "spp",
      std::to_string(status.passes_complete()) + " complete of " +
          std::to_string(status.passes_planned()) + " planned");
  row(out, "tiles",
      std::to_string(status.tiles_complete()) + " / " + std::to_string(status.tiles_total()));
  row(out, "tasks",
      std::to_string(status.tasks_complete()) + " / " + std::to_string(status.tasks_total()) +
          " complete");
  std::string time = number(status.compute_seconds(), "%.2f") + " compute s, " +
                     number(status.wall_seconds(), "%.2f") + " wall s";
  if (status.wall_seconds() > 0)
    time += ", " + number(status.passes_complete() / status.wall_seconds(), "%.3g") + " spp/s";
  if (fraction > 0.01 && fraction < 1 && status.wall_seconds() > 0)
    time += ", ETA " + number(status.wall_seconds() * (1 - fraction) / fraction, "%.0f") + " s";
  row(out, "time", time);
  if (status.has_mrse()) row(out, "MRSE", number(status.mrse()) + " (at the last pass boundary)");
  out << "</table>\n";

  out << "<h2>Preview</h2>\n<p class=\"note\">The image so far (every tile's complete passes), "
         "tonemapped at exposure 1.</p>\n<img class=\"preview\" id=\"preview\" alt=\"preview\" "
         "src=\"/api/jobs/"
      << html_escape(status.job_id()) << "/preview.png" << q << "\" width=\"" << status.width()
      << "\" height=\"" << status.height() << "\">\n";
  // Tasks by state: complete, held by a worker (rendering), waiting for one.
  const uint64_t leased = status.tasks_leased();
  const uint64_t waiting = status.tasks_total() > status.tasks_complete() + leased
                               ? status.tasks_total() - status.tasks_complete() - leased
                               : 0;
  out << "<h2>Tasks</h2>\n<table id=\"tasks\" data-complete=\"" << status.tasks_complete()
      << "\" data-leased=\"" << leased << "\" data-waiting=\"" << waiting
      << "\">\n<tr><th class=\"text\">state</th><th>tasks</th></tr>\n"
      << "<tr><td class=\"text\">complete</td><td>" << status.tasks_complete() << "</td></tr>\n"
      << "<tr><td class=\"text\">rendering (leased to a worker)</td><td>" << leased
      << "</td></tr>\n"
      << "<tr><td class=\"text\">waiting for a worker</td><td>" << waiting << "</td></tr>\n"
      << "<tr><th class=\"text\">opened so far</th><th>" << status.tasks_total()
      << "</th></tr>\n</table>\n";

  out << "<h2>Workers</h2>\n";
  if (workers.empty()) {
    out << "<p class=\"note\">No worker has leased a task of this job.</p>\n";
  } else {
    out << "<p class=\"note\">The workers that rendered or hold this job's tasks, since the "
           "coordinator started: this job's tasks each holds now and completed, their compute "
           "seconds, and its rate on this job over the last "
        << kJobWorkerRateWindowSeconds << " s.</p>\n"
        << "<table id=\"workers\">\n<tr><th class=\"text\">worker</th><th "
           "class=\"text\">state</th><th>threads</th><th>tasks now</th><th>recent "
           "tasks/s</th><th>tasks done</th><th>compute s</th></tr>\n";
    for (const JobWorkerActivity& worker : workers) {
      const char* state = !worker.registered ? "forgotten" : worker.alive ? "alive" : "lost";
      out << "<tr data-worker=\"" << html_escape(worker.worker_id) << "\"><td class=\"text\">"
          << html_escape(worker.name.empty() ? worker.worker_id : worker.name)
          << "</td><td class=\"text\">" << state << "</td><td>" << worker.threads << "</td><td>"
          << worker.tasks_leased << "</td><td>" << number(worker.recent_tasks_per_second, "%.3g")
          << "</td><td>" << worker.tasks_completed << "</td><td>"
          << number(worker.compute_seconds, "%.1f") << "</td></tr>\n";
    }
    out << "</table>\n";
  }

  // The convergence charts, as the batch report draws them (SVG as data: URIs, as there).
  std::vector<ChartSpec> charts = job_convergence_charts(status);
  if (!charts.empty()) {
    out << "<h2>Convergence</h2>\n<p class=\"note\">MRSE against the reference at each pass "
           "boundary, against compute seconds and against spp (log-log).</p>\n<div "
           "class=\"charts\">\n";
    for (const ChartSpec& chart : charts) {
      std::string svg;
      try {
        svg = chart_svg(chart);
      } catch (const std::exception& error) {
        out << "<p class=\"note\">" << html_escape(chart.title) << ": " << html_escape(error.what())
            << "</p>\n";
        continue;
      }
      out << "<figure><img class=\"chart\" alt=\"" << html_escape(chart.title)
          << "\" src=\"data:image/svg+xml;base64," << base64_encode(svg) << "\"><figcaption "
          << "class=\"note\">" << html_escape(chart.title) << "</figcaption></figure>\n";
    }
    out << "</div>\n";
  }
  if (status.curve_size() > 0) {
    out << "<table id=\"curve\">\n<tr><th>passes</th><th>compute s</th><th>wall s</th>"
           "<th>MRSE</th></tr>\n";
    for (const v1::ErrorSample& sample : status.curve())
      out << "<tr><td>" << sample.passes() << "</td><td>" << number(sample.compute_seconds())
          << "</td><td>" << number(sample.wall_seconds()) << "</td><td>" << number(sample.mrse())
          << "</td></tr>\n";
    out << "</table>\n";
  }
  if (status.errors_size() > 0) {
    out << "<h2>Errors against the reference</h2>\n<table id=\"errors\">\n<tr><th "
           "class=\"text\">region</th><th>MRSE</th><th>MSE</th><th>RMSE</th></tr>\n";
    for (const v1::RegionError& error : status.errors())
      out << "<tr><td class=\"text\">" << html_escape(error.region()) << "</td><td>"
          << number(error.mrse()) << "</td><td>" << number(error.mse()) << "</td><td>"
          << number(error.rmse()) << "</td></tr>\n";
    out << "</table>\n";
  }
  if (!viewer.html.empty())
    out << viewer.html;
  else if (viewer.offer)
    out << "<h2>Viewer</h2>\n<p class=\"note\"><a id=\"open-viewer\" href=\"" << with_viewer
        << "\">Open the comparison viewer</a> of the image so far (" << status.passes_complete()
        << " spp); that page does not refresh itself.</p>\n";
  else if (!viewer.note.empty())
    out << "<h2>Viewer</h2>\n<p class=\"note\">" << html_escape(viewer.note) << "</p>\n";
  out << "</body>\n</html>\n";
  return out.str();
}

std::string batch_page_html(const v1::BatchStatus& status, const std::string& viewer_html,
                            const std::string& viewer_note, const std::string& link_query) {
  const std::string q = html_escape(link_query);
  std::ostringstream out;
  const std::string title =
      "Batch " + status.batch_id() + (status.name().empty() ? "" : ": " + status.name());
  // A refresh would reset the viewer (its method, zoom and exposure): a running batch's page
  // with the viewer links to its newer state instead.
  const bool running = !finished(status.state());
  out << head(title, running && viewer_html.empty()) << "<h1>" << html_escape(title) << "</h1>\n"
      << "<p class=\"note\"><a href=\"/" << q << "\">dashboard</a>";
  if (running && !viewer_html.empty())
    out << " · <span id=\"stale\">running: this page shows the images at " +
               number(status.wall_seconds(), "%.1f") + " wall s; <a href=\"/batches/" +
               html_escape(status.batch_id()) + q + "\">reload</a> for the newer passes</span>";
  out << "</p>\n";
  out << "<table id=\"batch\" data-state=\"" << farm::state_name(status.state())
      << "\" data-jobs-done=\"" << status.jobs_done() << "\">\n";
  row(out, "state", "<b>" + farm::state_name(status.state()) + "</b>");
  if (!status.error().empty())
    row(out, "error", "<span class=\"error\">" + html_escape(status.error()) + "</span>");
  const double fraction = status.state() == v1::BATCH_STATE_DONE ? 1.0
                          : status.jobs_total() ? double(status.jobs_done()) / status.jobs_total()
                                                : 0.0;
  row(out, "progress",
      bar(fraction) + " (" + std::to_string(status.jobs_done()) + " / " +
          std::to_string(status.jobs_total()) + " jobs)");
  row(out, "scene",
      html_escape(status.scene_name()) + " (" + std::to_string(status.width()) + "x" +
          std::to_string(status.height()) + ")");
  std::string time = number(status.compute_seconds(), "%.2f") + " compute s, " +
                     number(status.wall_seconds(), "%.2f") + " wall s";
  if (fraction > 0.01 && fraction < 1 && status.wall_seconds() > 0)
    time += ", ETA " + number(status.wall_seconds() * (1 - fraction) / fraction, "%.0f") + " s";
  row(out, "time", time);
  const v1::BatchReferenceStatus& reference = status.reference();
  std::string reference_text =
      html_escape(reference.kind()) + " " + html_escape(reference.method()) + " " +
      html_escape(reference.sampler()) + " at " + std::to_string(reference.spp()) + " spp, " +
      farm::state_name(reference.state()) + (reference.cached() ? ", cached" : "");
  if (!reference.job_id().empty())
    reference_text += ", job <a href=\"/jobs/" + html_escape(reference.job_id()) + q + "\">" +
                      html_escape(reference.job_id()) + "</a>";
  row(out, "reference", reference_text);
  out << "</table>\n";

  out << "<h2>Methods</h2>\n<table id=\"runs\">\n<tr><th class=\"text\">label</th><th "
         "class=\"text\">method</th><th>repeat</th><th class=\"text\">job</th><th "
         "class=\"text\">state</th><th>spp</th><th>compute s</th><th>MRSE</th></tr>\n";
  for (const v1::BatchMethodStatus& method : status.methods()) {
    if (!method.error().empty()) {
      out << "<tr><td class=\"text\">" << html_escape(method.label()) << "</td><td class=\"text\">"
          << html_escape(method.method())
          << "</td><td class=\"text error\" colspan=\"6\">refused: " << html_escape(method.error())
          << "</td></tr>\n";
      continue;
    }
    for (const v1::BatchRun& run : method.runs()) {
      const v1::JobStatus& job = run.job();
      out << "<tr><td class=\"text\">" << html_escape(method.label()) << "</td><td class=\"text\">"
          << html_escape(method.method()) << "</td><td>" << run.repeat()
          << "</td><td class=\"text\"><a href=\"/jobs/" << html_escape(run.job_id()) << q << "\">"
          << html_escape(run.job_id()) << "</a></td><td class=\"text\">"
          << farm::state_name(job.state())
          << (job.error().empty()
                  ? ""
                  : ": <span class=\"error\">" + html_escape(job.error()) + "</span>")
          << "</td><td>" << job.passes_complete() << "</td><td>"
          << number(job.compute_seconds(), "%.2f") << "</td><td>"
          << (job.has_mrse() ? number(job.mrse()) : "–") << "</td></tr>\n";
    }
  }
  out << "</table>\n";
  if (!viewer_html.empty())
    out << viewer_html;
  else if (!viewer_note.empty())
    out << "<h2>Viewer</h2>\n<p class=\"note\">" << html_escape(viewer_note) << "</p>\n";
  out << "</body>\n</html>\n";
  return out.str();
}

std::string error_page_html(int http_status, const std::string& message,
                            const std::string& link_query) {
  return head("Error " + std::to_string(http_status), false) + "<h1>Error " +
         std::to_string(http_status) + "</h1>\n<p class=\"error\">" + html_escape(message) +
         "</p>\n<p><a href=\"/" + html_escape(link_query) +
         "\">dashboard</a></p>\n</body>\n</html>\n";
}

}  // namespace penumbra::farm
