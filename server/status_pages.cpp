// The job and batch pages: HTML built from the status messages alone.

#include "server/status_pages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

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

std::string mrse_chart_svg(const v1::JobStatus& status, int width, int height) {
  std::vector<std::pair<double, double>> points;
  for (const v1::ErrorSample& sample : status.curve())
    if (sample.compute_seconds() > 0 && sample.mrse() > 0 && std::isfinite(sample.mrse()))
      points.emplace_back(std::log10(sample.compute_seconds()), std::log10(sample.mrse()));
  if (points.size() < 2) return "";
  double x0 = points[0].first, x1 = x0, y0 = points[0].second, y1 = y0;
  for (const auto& [x, y] : points) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  if (x1 - x0 < 1e-9) x1 = x0 + 1;
  if (y1 - y0 < 1e-9) y1 = y0 + 1;
  const int left = 60, right = 12, top = 12, bottom = 36;
  auto sx = [&](double x) { return left + (x - x0) / (x1 - x0) * (width - left - right); };
  auto sy = [&](double y) { return top + (y1 - y) / (y1 - y0) * (height - top - bottom); };
  std::ostringstream out;
  out << "<svg class=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width
      << "\" height=\"" << height << "\" viewBox=\"0 0 " << width << " " << height << "\">\n"
      << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << width - left - right
      << "\" height=\"" << height - top - bottom << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
  out << "<path class=\"curve\" data-points=\"" << points.size()
      << "\" fill=\"none\" stroke=\"#2c5d8f\" stroke-width=\"2\" d=\"";
  for (size_t i = 0; i < points.size(); ++i)
    out << (i ? " L" : "M") << number(sx(points[i].first), "%.1f") << ","
        << number(sy(points[i].second), "%.1f");
  out << "\"/>\n";
  auto label = [&](double x, double y, const std::string& text, const char* anchor) {
    out << "<text x=\"" << number(x, "%.1f") << "\" y=\"" << number(y, "%.1f")
        << "\" font-size=\"11\" text-anchor=\"" << anchor << "\">" << html_escape(text)
        << "</text>\n";
  };
  label(left, height - 20, number(std::pow(10, x0)) + " s", "start");
  label(width - right, height - 20, number(std::pow(10, x1)) + " s", "end");
  label(width / 2.0, height - 4, "compute seconds (log)", "middle");
  label(left - 4, top + 10, number(std::pow(10, y1)), "end");
  label(left - 4, height - bottom, number(std::pow(10, y0)), "end");
  label(14, height / 2.0, "MRSE", "middle");
  out << "</svg>\n";
  return out.str();
}

std::string job_page_html(const v1::JobStatus& status, const std::string& link_query) {
  const std::string q = html_escape(link_query);
  std::ostringstream out;
  const std::string title =
      "Job " + status.job_id() + (status.name().empty() ? "" : ": " + status.name());
  out << head(title, !finished(status.state())) << "<h1>" << html_escape(title) << "</h1>\n"
      << "<p class=\"note\"><a href=\"/" << q << "\">dashboard</a> · <a href=\"/api/jobs/"
      << html_escape(status.job_id()) << q << "\">JSON</a></p>\n";
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
  std::string chart = mrse_chart_svg(status);
  if (!chart.empty())
    out << "<h2>Convergence</h2>\n<p class=\"note\">MRSE against the reference at each pass "
           "boundary, against compute seconds (log-log).</p>\n"
        << chart;
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
  out << "</body>\n</html>\n";
  return out.str();
}

std::string batch_page_html(const v1::BatchStatus& status, const std::string& viewer_html,
                            const std::string& viewer_note, const std::string& link_query) {
  const std::string q = html_escape(link_query);
  std::ostringstream out;
  const std::string title =
      "Batch " + status.batch_id() + (status.name().empty() ? "" : ": " + status.name());
  out << head(title, !finished(status.state())) << "<h1>" << html_escape(title) << "</h1>\n"
      << "<p class=\"note\"><a href=\"/" << q << "\">dashboard</a></p>\n";
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
