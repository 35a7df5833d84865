// The batch table: errors recomputed from the EXRs, checked against the recorded ones, grouped
// into rows (method and spp level, or method on a time budget), best per column marked.

#include "core/report/batch_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace penumbra {

namespace {

Image read_checked_exr(const std::filesystem::path& path, const BatchSceneInfo& scene) {
  Image image = read_exr(path.string());
  if (image.width != scene.width || image.height != scene.height)
    throw std::runtime_error(path.string() + ": image is " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + ", the batch's scene is " +
                             std::to_string(scene.width) + "x" + std::to_string(scene.height));
  return image;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

// Full precision for machine-readable output (round-trips a double).
std::string exact_number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

}  // namespace

RecomputedErrors recompute_batch_errors(const BatchResult& result,
                                        const std::filesystem::path& result_dir) {
  Image reference = read_checked_exr(result_dir / result.reference.exr, result.scene);
  std::map<std::string, Region> regions = result.region_map();
  RecomputedErrors recomputed(result.methods.size());
  for (size_t m = 0; m < result.methods.size(); ++m) {
    for (const BatchRun& run : result.methods[m].runs) {
      Image image = read_checked_exr(result_dir / run.exr, result.scene);
      recomputed[m].push_back(error_summary(image, reference, regions));
    }
  }
  return recomputed;
}

std::vector<std::string> compare_recorded_errors(const BatchResult& result,
                                                 const RecomputedErrors& recomputed,
                                                 double relative_tolerance) {
  std::vector<std::string> mismatches;
  auto check = [&](const std::string& where, const std::string& region, const char* metric,
                   double recorded, double actual) {
    double scale = std::max(std::abs(recorded), std::abs(actual));
    double difference = std::abs(recorded - actual);
    if (!(difference <= relative_tolerance * scale)) {
      char buffer[160];
      std::snprintf(buffer, sizeof(buffer),
                    ": region \"%s\": %s recorded %.17g, recomputed from the EXR %.17g "
                    "(relative difference %.3g)",
                    region.c_str(), metric, recorded, actual, scale > 0 ? difference / scale : 0.0);
      mismatches.push_back(where + buffer);
    }
  };
  for (size_t m = 0; m < result.methods.size(); ++m) {
    const BatchMethod& method = result.methods[m];
    for (size_t r = 0; r < method.runs.size(); ++r) {
      const BatchRun& run = method.runs[r];
      std::string where = "methods[" + std::to_string(m) + "].runs[" + std::to_string(r) + "] (" +
                          method.label + ", repeat " + std::to_string(run.repeat) + ", " +
                          std::to_string(run.spp) + " spp, " + run.exr + ")";
      for (const auto& [region, actual] : recomputed.at(m).at(r)) {
        auto recorded = run.errors.find(region);
        if (recorded == run.errors.end()) {
          mismatches.push_back(where + ": no recorded errors for region \"" + region + "\"");
          continue;
        }
        check(where, region, "mrse", recorded->second.mrse, actual.mrse);
        check(where, region, "mse", recorded->second.mse, actual.mse);
        check(where, region, "rmse", recorded->second.rmse, actual.rmse);
      }
    }
  }
  return mismatches;
}

MeanStd mean_std(const std::vector<double>& values) {
  MeanStd result;
  result.count = int(values.size());
  if (values.empty()) return result;
  double sum = 0;
  for (double v : values) sum += v;
  result.mean = sum / double(values.size());
  if (values.size() > 1) {
    double squares = 0;
    for (double v : values) squares += (v - result.mean) * (v - result.mean);
    result.std = std::sqrt(squares / double(values.size() - 1));
  }
  return result;
}

BatchTable make_batch_table(const BatchResult& result, const RecomputedErrors& recomputed) {
  BatchTable table;
  table.regions.push_back("image");
  for (const BatchRegion& region : result.regions) table.regions.push_back(region.name);

  for (size_t m = 0; m < result.methods.size(); ++m) {
    const BatchMethod& method = result.methods[m];
    BatchTableRow base;
    base.label = method.label;
    base.method = method.method;
    base.sampler = method.sampler;
    base.budget_seconds = method.budget_seconds;
    base.method_index = m;
    if (method.runs.empty()) {
      base.refusal = method.error.empty() ? "no runs" : method.error;
      table.rows.push_back(base);
      continue;
    }
    // Group the runs: a budgeted method's equal-time runs together (key 0), and one group per
    // spp level.
    std::map<uint32_t, std::vector<size_t>> groups;
    for (size_t r = 0; r < method.runs.size(); ++r)
      groups[method.runs[r].equal_time ? 0u : method.runs[r].spp].push_back(r);
    for (const auto& [spp_key, run_indices] : groups) {
      BatchTableRow row = base;
      if (spp_key != 0) row.budget_seconds.reset();  // an spp level of a budgeted method
      row.run_indices = run_indices;
      row.repeats = int(run_indices.size());
      row.spp_min = UINT32_MAX;
      std::vector<double> seconds;
      std::map<std::string, std::vector<double>> errors;
      for (size_t r : run_indices) {
        const BatchRun& run = method.runs[r];
        row.spp_min = std::min(row.spp_min, run.spp);
        row.spp_max = std::max(row.spp_max, run.spp);
        seconds.push_back(run.compute_seconds);
        for (const std::string& region : table.regions)
          errors[region].push_back(recomputed.at(m).at(r).at(region).mrse);
      }
      row.compute_seconds = mean_std(seconds);
      for (const std::string& region : table.regions) row.mrse[region] = mean_std(errors[region]);
      row.comparison_group = row.budget_seconds
                                 ? "budget " + format_number(*row.budget_seconds) + " s"
                                 : std::to_string(spp_key) + " spp";
      table.rows.push_back(std::move(row));
    }
  }

  // Best per column within each comparison group of two or more rows (lowest is best).
  std::map<std::string, std::vector<BatchTableRow*>> groups;
  for (BatchTableRow& row : table.rows)
    if (row.refusal.empty()) groups[row.comparison_group].push_back(&row);
  for (auto& group : groups) {
    std::vector<BatchTableRow*>& rows = group.second;
    if (rows.size() < 2) continue;
    auto mark = [&](const std::string& column, auto value_of) {
      double best = INFINITY;
      for (BatchTableRow* row : rows) best = std::min(best, value_of(*row));
      for (BatchTableRow* row : rows)
        if (value_of(*row) == best) row->best.insert(column);
    };
    for (const std::string& region : table.regions)
      mark("mrse:" + region, [&](const BatchTableRow& row) { return row.mrse.at(region).mean; });
  }
  return table;
}

std::string batch_table_csv(const BatchTable& table) {
  std::ostringstream out;
  out << "label,method,sampler,budget_seconds,comparison_group,spp_min,spp_max,repeats,"
         "compute_seconds_mean,compute_seconds_std";
  for (const std::string& region : table.regions)
    out << "," << csv_field("mrse_" + region + "_mean") << ","
        << csv_field("mrse_" + region + "_std");
  // The comparison's columns (core/report/batch_comparison.h): corrected MRSE with its 95%
  // interval and the reference's share, per region; the efficiency against the baseline.
  for (const std::string& region : table.regions)
    for (const char* part :
         {"_corrected_mean", "_corrected_lower", "_corrected_upper", "_reference_share"})
      out << "," << csv_field("mrse_" + region + part);
  out << ",efficiency_mean,efficiency_lower,efficiency_upper";
  out << ",best,refusal\n";
  for (const BatchTableRow& row : table.rows) {
    out << csv_field(row.label) << "," << csv_field(row.method) << "," << csv_field(row.sampler)
        << "," << (row.budget_seconds ? exact_number(*row.budget_seconds) : "") << ","
        << csv_field(row.comparison_group) << ",";
    if (row.refusal.empty()) {
      out << row.spp_min << "," << row.spp_max << "," << row.repeats << ","
          << exact_number(row.compute_seconds.mean) << "," << exact_number(row.compute_seconds.std);
      for (const std::string& region : table.regions)
        out << "," << exact_number(row.mrse.at(region).mean) << ","
            << exact_number(row.mrse.at(region).std);
      auto interval = [&](const MeanInterval& value) {
        out << "," << exact_number(value.mean) << ","
            << (value.has_interval ? exact_number(value.lower()) : "") << ","
            << (value.has_interval ? exact_number(value.upper()) : "");
      };
      for (const std::string& region : table.regions) {
        auto cell = row.cells.find(region);
        if (cell == row.cells.end()) {
          out << ",,,,";
          continue;
        }
        interval(cell->second.corrected);
        out << "," << exact_number(cell->second.reference_share);
      }
      if (row.efficiency.count > 0)
        interval(row.efficiency);
      else
        out << ",,,";
    } else {
      out << ",,,,";
      for (size_t i = 0; i < table.regions.size(); ++i) out << ",,,,,,";
      out << ",,,";
    }
    std::string best;
    for (const std::string& column : row.best) best += (best.empty() ? "" : ";") + column;
    out << "," << csv_field(best) << "," << csv_field(row.refusal) << "\n";
  }
  return out.str();
}

nlohmann::json batch_table_json(const BatchTable& table) {
  nlohmann::json rows = nlohmann::json::array();
  for (const BatchTableRow& row : table.rows) {
    nlohmann::json entry = {{"label", row.label},
                            {"method", row.method},
                            {"sampler", row.sampler},
                            {"budget_seconds", nullptr},
                            {"comparison_group", row.comparison_group}};
    if (row.budget_seconds) entry["budget_seconds"] = *row.budget_seconds;
    if (!row.refusal.empty()) {
      entry["refusal"] = row.refusal;
    } else {
      entry["spp_min"] = row.spp_min;
      entry["spp_max"] = row.spp_max;
      entry["repeats"] = row.repeats;
      entry["compute_seconds"] = {{"mean", row.compute_seconds.mean},
                                  {"std", row.compute_seconds.std}};
      nlohmann::json mrse = nlohmann::json::object();
      for (const auto& [region, value] : row.mrse)
        mrse[region] = {{"mean", value.mean}, {"std", value.std}, {"count", value.count}};
      entry["mrse"] = mrse;
    }
    entry["best"] = std::vector<std::string>(row.best.begin(), row.best.end());
    rows.push_back(entry);
  }
  return {{"regions", table.regions}, {"rows", rows}};
}

std::string format_number(double value) {
  char buffer[40];
  double magnitude = std::abs(value);
  if (value != 0 && (magnitude < 1e-3 || magnitude >= 1e6))
    std::snprintf(buffer, sizeof(buffer), "%.3e", value);
  else
    std::snprintf(buffer, sizeof(buffer), "%.4g", value);
  return buffer;
}

}  // namespace penumbra
