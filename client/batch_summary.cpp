#include "client/batch_summary.h"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace penumbra {

namespace {

std::string padded(const std::string& text, size_t width, bool left) {
  if (text.size() >= width) return text;
  const std::string fill(width - text.size(), ' ');
  return left ? text + fill : fill + text;
}

std::string formatted(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

}  // namespace

std::string batch_summary_table(const nlohmann::json& index) {
  std::vector<std::string> regions = {"image"};
  if (index.contains("regions"))
    for (const auto& region : index["regions"]) regions.push_back(region["name"]);

  // The cells first, then every column as wide as its widest cell or header.
  struct Line {
    std::string label, refusal;
    std::vector<std::string> cells;  // spp, compute s, one MRSE per region, the repeat
  };
  std::vector<Line> lines;
  for (const auto& method : index["methods"]) {
    const std::string label = method["label"];
    if (method.contains("error")) {
      lines.push_back({label, method["error"].get<std::string>(), {}});
      continue;
    }
    for (const auto& run : method["runs"]) {
      if (method.contains("budget_seconds") && method["budget_seconds"].is_number() &&
          !run.value("equal_time", true))
        continue;
      Line line{label, "", {}};
      line.cells.push_back(std::to_string(run["spp"].get<unsigned>()));
      line.cells.push_back(formatted("%.2f", run["compute_seconds"].get<double>()));
      for (const std::string& region : regions) {
        std::string value = "-";
        for (const auto& error : run["errors"])
          if (error["region"] == region) value = formatted("%.4g", error["mrse"].get<double>());
        line.cells.push_back(value);
      }
      line.cells.push_back("(r" + std::to_string(run["repeat"].get<unsigned>()) + ")");
      lines.push_back(std::move(line));
    }
  }
  std::vector<std::string> headers = {"spp", "compute s"};
  for (const std::string& region : regions) headers.push_back("MRSE " + region);
  size_t label_width = std::string("method").size();
  std::vector<size_t> widths;
  for (const std::string& header : headers) widths.push_back(header.size());
  for (const Line& line : lines) {
    label_width = std::max(label_width, line.label.size());
    for (size_t c = 0; c < headers.size() && c < line.cells.size(); ++c)
      widths[c] = std::max(widths[c], line.cells[c].size());
  }

  std::string table = padded("method", label_width, true);
  for (size_t c = 0; c < headers.size(); ++c) table += "  " + padded(headers[c], widths[c], false);
  table += "\n";
  for (const Line& line : lines) {
    table += padded(line.label, label_width, true);
    if (!line.refusal.empty()) {
      table += "  refused: " + line.refusal + "\n";
      continue;
    }
    for (size_t c = 0; c < headers.size(); ++c)
      table += "  " + padded(line.cells[c], widths[c], false);
    table += "  " + line.cells.back() + "\n";
  }
  return table;
}

}  // namespace penumbra
