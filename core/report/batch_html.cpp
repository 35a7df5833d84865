// The HTML page of a batch report. Everything it shows is inlined, so the file can be mailed or
// opened offline; the SVG charts are <img> data: URIs (inline <svg> elements would share the
// cairo glyph ids between charts).

#include "core/report/batch_html.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace penumbra {

namespace {

std::string read_file_bytes(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path.string() + ": cannot read for the report");
  std::ostringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

std::string relative_link(const std::filesystem::path& path, const std::filesystem::path& base) {
  std::error_code error;
  std::filesystem::path relative = std::filesystem::relative(path, base, error);
  return html_escape((error || relative.empty() ? path : relative).generic_string());
}

std::string mean_std_text(const MeanStd& value) {
  if (value.count > 1) return format_number(value.mean) + " ± " + format_number(value.std);
  return format_number(value.mean);
}

const char* kStyle = R"(
body { font-family: "DejaVu Sans", sans-serif; margin: 24px; color: #111; max-width: 1400px; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 28px; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 13px; }
th, td { border: 1px solid #bbb; padding: 4px 8px; text-align: right; }
th { background: #eee; } td.text { text-align: left; }
td.best { background: #d8f5d0; font-weight: bold; }
td.refused { text-align: left; color: #a00; }
.charts img { max-width: 680px; margin: 6px; border: 1px solid #ddd; }
.figure img { max-width: 100%; border: 1px solid #ddd; }
pre { background: #f6f6f6; padding: 8px; font-size: 12px; overflow-x: auto; }
.problems { color: #a00; }
.note { font-size: 12px; color: #444; }
)";

void write_table(std::ostringstream& out, const BatchTable& table) {
  out << "<table id=\"batch-table\">\n<tr><th>label</th><th>method</th><th>sampler</th>"
         "<th>group</th><th>spp</th><th>repeats</th><th>compute s</th>";
  for (const std::string& region : table.regions)
    out << "<th>MRSE " << html_escape(region == "image" ? "full image" : region) << "</th>";
  out << "</tr>\n";
  for (const BatchTableRow& row : table.rows) {
    out << "<tr><td class=\"text\">" << html_escape(row.label) << "</td><td class=\"text\">"
        << html_escape(row.method) << "</td><td class=\"text\">" << html_escape(row.sampler)
        << "</td>";
    if (!row.refusal.empty()) {
      out << "<td class=\"refused\" colspan=\"" << 4 + table.regions.size()
          << "\">refused: " << html_escape(row.refusal) << "</td></tr>\n";
      continue;
    }
    out << "<td class=\"text\">" << html_escape(row.comparison_group) << "</td><td>" << row.spp_min;
    if (row.spp_max != row.spp_min) out << "–" << row.spp_max;
    out << "</td><td>" << row.repeats << "</td>";
    auto cell = [&](const std::string& column, const std::string& text) {
      bool best = row.best.count(column) > 0;
      out << "<td" << (best ? " class=\"best\" title=\"best of its group\"" : "") << ">"
          << html_escape(text) << (best ? " ★" : "") << "</td>";
    };
    cell("compute_seconds", mean_std_text(row.compute_seconds));
    for (const std::string& region : table.regions)
      cell("mrse:" + region, mean_std_text(row.mrse.at(region)));
    out << "</tr>\n";
  }
  out << "</table>\n";
}

}  // namespace

std::string html_escape(std::string_view text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        escaped += "&amp;";
        break;
      case '<':
        escaped += "&lt;";
        break;
      case '>':
        escaped += "&gt;";
        break;
      case '"':
        escaped += "&quot;";
        break;
      case '\'':
        escaped += "&#39;";
        break;
      default:
        escaped += c;
    }
  }
  return escaped;
}

std::string base64_encode(std::string_view bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string encoded;
  encoded.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    uint32_t triple = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8 |
                      uint32_t(uint8_t(bytes[i + 2]));
    for (int shift = 18; shift >= 0; shift -= 6) encoded += kAlphabet[(triple >> shift) & 63];
  }
  size_t rest = bytes.size() - i;
  if (rest > 0) {
    uint32_t triple = uint32_t(uint8_t(bytes[i])) << 16;
    if (rest == 2) triple |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    encoded += kAlphabet[(triple >> 18) & 63];
    encoded += kAlphabet[(triple >> 12) & 63];
    encoded += rest == 2 ? kAlphabet[(triple >> 6) & 63] : '=';
    encoded += '=';
  }
  return encoded;
}

std::string batch_report_html(const BatchReportContent& content) {
  const BatchResult& result = *content.result;
  std::ostringstream out;
  std::string title =
      "Penumbra batch report: " + (result.name.empty() ? result.batch_id : result.name);
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
      << html_escape(title) << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  out << "<h1>" << html_escape(title) << "</h1>\n<p>Batch <code>" << html_escape(result.batch_id)
      << "</code>; scene <b>" << html_escape(result.scene.name) << "</b> (" << result.scene.width
      << "x" << result.scene.height << ", sha256 <code>" << html_escape(result.scene.hash)
      << "</code>).</p>\n";

  if (!content.problems.empty()) {
    out << "<h2>Problems</h2>\n<ul class=\"problems\">\n";
    for (const std::string& problem : content.problems)
      out << "<li>" << html_escape(problem) << "</li>\n";
    out << "</ul>\n";
  }

  out << "<h2>Table</h2>\n<p class=\"note\">MRSE (Salesin &amp; Jarosz; mean over pixels and "
         "channels of (p - r)² / (r² + 1e-6)) recomputed from the EXRs against the reference; mean "
         "± "
         "sample standard deviation over repeats. ★ marks the lowest value of each column among "
         "the rows of one group (the same time budget, or the same spp). Also as "
      << "<a href=\"table.csv\">table.csv</a> and <a href=\"table.json\">table.json</a>.</p>\n";
  write_table(out, *content.table);

  std::vector<const BatchMethod*> refused;
  for (const BatchMethod& method : result.methods)
    if (method.runs.empty()) refused.push_back(&method);
  if (!refused.empty()) {
    out << "<h2>Refusals</h2>\n<ul>\n";
    for (const BatchMethod* method : refused)
      out << "<li><b>" << html_escape(method->label) << "</b> (" << html_escape(method->method)
          << "): " << html_escape(method->error.empty() ? "no runs" : method->error) << "</li>\n";
    out << "</ul>\n";
  }

  out << "<h2>Charts</h2>\n<div class=\"charts\">\n";
  for (const BatchChartFiles& chart : content.charts) {
    out << "<figure><img alt=\"" << html_escape(chart.title)
        << "\" src=\"data:image/svg+xml;base64," << base64_encode(read_file_bytes(chart.svg))
        << "\"><figcaption class=\"note\">" << html_escape(chart.title) << " (<a href=\""
        << relative_link(chart.svg, content.out_dir) << "\">SVG</a>, <a href=\""
        << relative_link(chart.png, content.out_dir) << "\">PNG</a>)</figcaption></figure>\n";
  }
  out << "</div>\n";

  out << "<h2>Figure</h2>\n<p class=\"note\">One column per method (the reference first): the "
         "full image tonemapped at exposure "
      << format_number(content.figure.exposure)
      << " for all, the regions enlarged (nearest neighbour) with their MRSE, and the relative "
         "error |x - ref| / (ref + 0.01) in false colour on one scale (0 to "
      << format_number(content.figure.error_scale)
      << "). Each column shows the run with the highest spp, lowest repeat.</p>\n"
      << "<div class=\"figure\"><img alt=\"figure\" src=\"data:image/png;base64,"
      << base64_encode(read_file_bytes(content.figure_png)) << "\"></div>\n";

  out << "<h2>Reference</h2>\n<table>\n";
  auto detail = [&](const std::string& key, const std::string& value) {
    out << "<tr><th>" << html_escape(key) << "</th><td class=\"text\">" << html_escape(value)
        << "</td></tr>\n";
  };
  detail("EXR", result.reference.exr);
  detail("method", result.reference.method);
  detail("sampler", result.reference.sampler);
  detail("spp", std::to_string(result.reference.spp));
  detail("job", result.reference.job_id);
  detail("cached", result.reference.cached ? "yes (rendered by an earlier batch)" : "no");
  out << "</table>\n";

  out << "<h2>Runs</h2>\n<table>\n<tr><th>label</th><th>budget s</th><th>repeat</th><th>seed</th>"
         "<th>job</th><th>spp</th><th>compute s</th><th>wall s</th><th>curve points</th>"
         "<th>EXR</th></tr>\n";
  for (const BatchMethod& method : result.methods)
    for (const BatchRun& run : method.runs)
      out << "<tr><td class=\"text\">" << html_escape(method.label) << "</td><td>"
          << (method.budget_seconds ? format_number(*method.budget_seconds) : "–") << "</td><td>"
          << run.repeat << "</td><td>" << run.seed << "</td><td class=\"text\">"
          << html_escape(run.job_id) << "</td><td>" << run.spp << "</td><td>"
          << format_number(run.compute_seconds) << "</td><td>" << format_number(run.wall_seconds)
          << "</td><td>" << run.curve.size() << "</td><td class=\"text\">" << html_escape(run.exr)
          << "</td></tr>\n";
  out << "</table>\n";

  out << "<h2>Spec</h2>\n<pre>"
      << html_escape(result.spec_json.empty() ? "(not recorded)" : result.spec_json) << "</pre>\n";
  out << "<h2>Regions</h2>\n<ul>\n<li>image: the whole " << result.scene.width << "x"
      << result.scene.height << " image</li>\n";
  for (const BatchRegion& region : result.regions)
    out << "<li>" << html_escape(region.name) << ": [" << region.rect.x0 << ", " << region.rect.y0
        << ") to [" << region.rect.x1 << ", " << region.rect.y1 << ")</li>\n";
  out << "</ul>\n</body>\n</html>\n";
  return out.str();
}

}  // namespace penumbra
