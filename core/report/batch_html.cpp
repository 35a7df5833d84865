// The HTML page of a batch report. Everything it shows is inlined, so the file can be mailed or
// opened offline; the SVG charts are <img> data: URIs (inline <svg> elements would share the
// cairo glyph ids between charts).

#include "core/report/batch_html.h"

#include <cstdio>
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
td.flagged { background: #fde7c8; } td.best.flagged { background: #e6efc0; }
.small { font-size: 11px; color: #555; font-weight: normal; }
td.refused { text-align: left; color: #a00; }
.charts img { max-width: 680px; margin: 6px; border: 1px solid #ddd; }
.figure img { max-width: 100%; border: 1px solid #ddd; }
pre { background: #f6f6f6; padding: 8px; font-size: 12px; overflow-x: auto; }
.problems { color: #a00; }
.note { font-size: 12px; color: #444; }
)";

std::string interval_text(const MeanInterval& value) {
  std::string text = format_number(value.mean);
  if (value.has_interval)
    text += " [" + format_number(value.lower()) + ", " + format_number(value.upper()) + "]";
  return text;
}

std::string percent(double share) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f%%", 100 * share);
  return text;
}

void write_table(std::ostringstream& out, const BatchTable& table, const std::string& baseline) {
  out << "<table id=\"batch-table\">\n<tr><th>label</th><th>method</th><th>sampler</th>"
         "<th>group</th><th>spp</th><th>repeats</th><th>compute s</th>";
  for (const std::string& region : table.regions)
    out << "<th>MRSE " << html_escape(region == "image" ? "full image" : region) << "</th>";
  out << "<th>efficiency vs " << html_escape(baseline) << "</th></tr>\n";
  for (const BatchTableRow& row : table.rows) {
    out << "<tr><td class=\"text\">" << html_escape(row.label) << "</td><td class=\"text\">"
        << html_escape(row.method) << "</td><td class=\"text\">" << html_escape(row.sampler)
        << "</td>";
    if (!row.refusal.empty()) {
      out << "<td class=\"refused\" colspan=\"" << 5 + table.regions.size()
          << "\">refused: " << html_escape(row.refusal) << "</td></tr>\n";
      continue;
    }
    out << "<td class=\"text\">" << html_escape(row.comparison_group) << "</td><td>" << row.spp_min;
    if (row.spp_max != row.spp_min) out << "–" << row.spp_max;
    out << "</td><td>" << row.repeats << "</td><td>"
        << html_escape(mean_std_text(row.compute_seconds)) << "</td>";
    for (const std::string& region : table.regions) {
      const bool best = row.best.count("mrse:" + region) > 0;
      auto cell = row.cells.find(region);
      if (cell == row.cells.end()) {
        out << "<td>" << html_escape(mean_std_text(row.mrse.at(region))) << "</td>";
        continue;
      }
      const BatchCell& value = cell->second;
      std::string classes = std::string(best ? "best" : "") +
                            (value.reference_flagged ? (best ? " flagged" : "flagged") : "");
      // data-viewer-*: a click shows this method and region in the viewer.
      out << "<td data-viewer-label=\"" << html_escape(row.label) << "\" data-viewer-region=\""
          << html_escape(region) << "\"" << (classes.empty() ? "" : " class=\"" + classes + "\"")
          << (best ? " title=\"beats every other row of its group at 95%\"" : "") << ">"
          << html_escape(interval_text(value.corrected)) << (best ? " ★" : "")
          << "<br><span class=\"small\">plain " << html_escape(format_number(value.plain.mean))
          << " · ref " << percent(value.reference_share) << (value.reference_flagged ? " ⚠" : "")
          << "</span></td>";
    }
    out << "<td>"
        << (row.efficiency.count > 0 ? "×" + html_escape(interval_text(row.efficiency)) : "–")
        << "</td></tr>\n";
  }
  out << "</table>\n";
}

void write_pairwise(std::ostringstream& out, const BatchTable& table,
                    const BatchComparison& comparison) {
  if (comparison.pairwise.empty()) return;
  out << "<h2>Pairwise comparisons</h2>\n<p class=\"note\">For each group and region, every "
         "pair of rows: the ratio of their mean corrected MRSE and whether the paired "
         "difference over the repeats (same seed offsets, so repeat r of A and B share their "
         "camera jitter) is significant at 95% (two-sided t test, k - 1 degrees of freedom); "
         "the reference's noise is common to both and cancels.</p>\n"
         "<table id=\"pairwise-table\">\n<tr><th>group</th><th>region</th><th>A</th><th>B</th>"
         "<th>MRSE A / B</th><th>difference A - B [95%]</th><th>p</th><th>verdict</th></tr>\n";
  for (const PairwiseComparison& pair : comparison.pairwise) {
    const std::string& a = table.rows[pair.row_a].label;
    const std::string& b = table.rows[pair.row_b].label;
    std::string verdict = pair.difference.pairs < 2  ? "one repeat: not tested"
                          : pair.difference.sign < 0 ? a + " beats " + b
                          : pair.difference.sign > 0 ? b + " beats " + a
                                                     : "not significant";
    out << "<tr><td class=\"text\">" << html_escape(pair.group) << "</td><td class=\"text\">"
        << html_escape(pair.region) << "</td><td class=\"text\">" << html_escape(a)
        << "</td><td class=\"text\">" << html_escape(b) << "</td><td>"
        << html_escape(format_number(pair.ratio)) << "</td><td>"
        << html_escape(format_number(pair.difference.difference)) << " ± "
        << html_escape(format_number(pair.difference.half_width)) << "</td><td>"
        << html_escape(format_number(pair.difference.p_value)) << "</td><td class=\"text\">"
        << html_escape(verdict) << "</td></tr>\n";
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

  const std::string baseline = content.comparison ? content.comparison->baseline : "";
  out << "<h2>Table</h2>\n<p class=\"note\">How to read it. Each MRSE cell (Salesin &amp; "
         "Jarosz: mean over pixels and channels of (p - r)² / (r² + 1e-6), recomputed from the "
         "EXRs) is the <b>corrected</b> MRSE: the reference's own expected contribution, the mean "
         "of s² / (r² + 1e-6) with s² the reference's per-pixel variance of the mean (its EXR's "
         "variance layer), removed. It is the mean over the repeats with its 95% interval in "
         "brackets (the repeats' spread and the reference's own noise, which every run shares). "
         "Below it: the <b>plain</b> MRSE as measured, and the reference's <b>share</b> of it; a "
         "share above "
      << percent(kReferenceShareFlag)
      << " is flagged ⚠ (orange): there the reference is not clean enough for the plain number "
         "to mean much, and the corrected one leans on the correction. ★ marks a row that beats "
         "every other row of its group (the same time budget, or the same spp) in that column at "
         "95%, paired by repeat; no star means no significant winner. Efficiency is 1 / (MRSE × "
         "compute seconds) relative to <b>"
      << html_escape(baseline)
      << "</b> (paired by repeat, image MRSE corrected): above 1 is better. Also as <a "
         "href=\"table.csv\">table.csv</a> and <a href=\"table.json\">table.json</a>.</p>\n";
  write_table(out, *content.table, baseline);
  out << content.viewer_html;
  if (content.comparison) write_pairwise(out, *content.table, *content.comparison);

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
  if (result.reference.sizing) detail("sized", reference_sizing_text(result.reference));
  detail("job", result.reference.job_id);
  detail("cached", result.reference.cached ? "yes (rendered by an earlier batch)" : "no");
  if (content.reference_noise) {
    const ReferenceNoise& noise = *content.reference_noise;
    if (!noise.has_variance) {
      detail("own noise", "unknown: the reference EXR has no variance layer (nothing corrected)");
    } else {
      for (const auto& [region, error] : noise.regions)
        detail("own MRSE, " + region, format_number(error.reference_term) + " (± " +
                                          format_number(error.reference_deviation) +
                                          " shared by every run)");
    }
    for (const auto& [region, share] : noise.fallback) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "%.1f%% of the pixels have a camera sample without a closed form (%.1f%% of "
                    "the camera samples), shaded by the fallback estimate (the EXR's exact.mask)",
                    100 * share.pixels, 100 * share.samples);
      detail("not exact, " + region, text);
    }
  }
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
