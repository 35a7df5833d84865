// Corrected MRSE, intervals, reference shares, significant winners, pairwise comparisons and
// efficiencies of a batch table (see the header).

#include "core/report/batch_comparison.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/image/image.h"

namespace penumbra {

namespace {

// The row's runs' values by repeat (a method's repeats of one row are distinct).
std::map<int, double> by_repeat(const BatchTableRow& row, const BatchResult& result,
                                const RecomputedErrors& recomputed, const ReferenceNoise& noise,
                                const std::string& region) {
  std::map<int, double> values;
  for (size_t r : row.run_indices) {
    const BatchRun& run = result.methods[row.method_index].runs[r];
    values[run.repeat] =
        noise.corrected(region, recomputed.at(row.method_index).at(r).at(region).mrse);
  }
  return values;
}

// Paired values of two rows: the repeats both have.
void pair_up(const std::map<int, double>& a, const std::map<int, double>& b,
             std::vector<double>& va, std::vector<double>& vb) {
  va.clear();
  vb.clear();
  for (const auto& [repeat, value] : a) {
    auto other = b.find(repeat);
    if (other == b.end()) continue;
    va.push_back(value);
    vb.push_back(other->second);
  }
}

}  // namespace

double ReferenceNoise::term(const std::string& region) const {
  auto it = regions.find(region);
  return it == regions.end() ? 0.0 : it->second.reference_term;
}

double ReferenceNoise::deviation(const std::string& region) const {
  auto it = regions.find(region);
  return it == regions.end() ? 0.0 : it->second.reference_deviation;
}

double ReferenceNoise::corrected(const std::string& region, double plain) const {
  return plain - term(region);
}

ReferenceNoise read_reference_noise(const BatchResult& result,
                                    const std::filesystem::path& result_dir) {
  const std::filesystem::path path = result_dir / result.reference.exr;
  Image variance;
  Image reference = read_exr(path.string(), nullptr, &variance);
  if (reference.width != result.scene.width || reference.height != result.scene.height)
    throw std::runtime_error(path.string() + ": image is " + std::to_string(reference.width) + "x" +
                             std::to_string(reference.height) + ", the batch's scene is " +
                             std::to_string(result.scene.width) + "x" +
                             std::to_string(result.scene.height));
  ReferenceNoise noise;
  noise.has_variance = variance.width > 0;
  try {
    noise.regions = noise_corrected_summary(reference, reference, variance, result.region_map());
  } catch (const std::invalid_argument& error) {
    throw std::runtime_error(path.string() + ": " + error.what());
  }
  const std::vector<float> mask = read_exr_channel(path.string(), "exact.mask");
  if (!mask.empty()) {
    std::map<std::string, Region> regions = result.region_map();
    regions["image"] = Region{0, 0, reference.width, reference.height};
    for (const auto& [name, region] : regions) {
      const Region area = clip_region(region, reference);
      ReferenceNoise::MaskShare share;
      for (int y = area.y0; y < area.y1; ++y)
        for (int x = area.x0; x < area.x1; ++x) {
          const float m = mask[size_t(y) * reference.width + x];
          share.pixels += m > 0 ? 1 : 0;
          share.samples += m;
        }
      const double count = double(area.x1 - area.x0) * double(area.y1 - area.y0);
      share.pixels /= count;
      share.samples /= count;
      noise.fallback[name] = share;
    }
  }
  return noise;
}

std::string choose_baseline(const BatchResult& result) {
  nlohmann::json spec = nlohmann::json::parse(result.spec_json, nullptr, false);
  if (spec.is_object() && spec.contains("baseline") && spec["baseline"].is_string()) {
    const std::string wanted = spec["baseline"].get<std::string>();
    for (const BatchMethod& method : result.methods)
      if (method.label == wanted && !method.runs.empty()) return wanted;
  }
  for (const BatchMethod& method : result.methods)
    if (!method.runs.empty()) return method.label;
  return "";
}

BatchComparison compare_batch_rows(BatchTable& table, const BatchResult& result,
                                   const RecomputedErrors& recomputed,
                                   const ReferenceNoise& noise) {
  BatchComparison comparison;
  comparison.baseline = choose_baseline(result);

  // Cells: corrected and plain means with intervals, the reference's share.
  for (BatchTableRow& row : table.rows) {
    if (!row.refusal.empty()) continue;
    for (const std::string& region : table.regions) {
      std::vector<double> corrected, plain;
      double shares = 0;
      for (size_t r : row.run_indices) {
        const double value = recomputed.at(row.method_index).at(r).at(region).mrse;
        plain.push_back(value);
        corrected.push_back(noise.corrected(region, value));
        shares += value > 0 ? noise.term(region) / value : 0.0;
      }
      BatchCell cell;
      cell.corrected = mean_interval(corrected, noise.deviation(region));
      cell.plain = mean_interval(plain);
      cell.reference_share = row.run_indices.empty() ? 0 : shares / double(row.run_indices.size());
      cell.reference_flagged = cell.reference_share > kReferenceShareFlag;
      row.cells[region] = cell;
    }
  }

  // Groups: winners, pairwise comparisons, efficiency against the baseline's row.
  std::map<std::string, std::vector<size_t>> groups;
  for (size_t i = 0; i < table.rows.size(); ++i)
    if (table.rows[i].refusal.empty()) groups[table.rows[i].comparison_group].push_back(i);
  std::vector<double> va, vb;
  for (const auto& [group, members] : groups) {
    for (size_t i : members) table.rows[i].best.clear();
    if (members.size() < 2) continue;
    for (const std::string& region : table.regions) {
      std::vector<std::map<int, double>> values;
      for (size_t i : members)
        values.push_back(by_repeat(table.rows[i], result, recomputed, noise, region));
      // Every ordered pair.
      std::vector<std::vector<int>> sign(members.size(), std::vector<int>(members.size(), 0));
      for (size_t a = 0; a < members.size(); ++a)
        for (size_t b = 0; b < members.size(); ++b) {
          if (a == b) continue;
          pair_up(values[a], values[b], va, vb);
          PairwiseComparison pair;
          pair.group = group;
          pair.region = region;
          pair.row_a = members[a];
          pair.row_b = members[b];
          pair.difference = paired_difference(va, vb);
          const double mean_a = table.rows[members[a]].cells.at(region).corrected.mean;
          const double mean_b = table.rows[members[b]].cells.at(region).corrected.mean;
          pair.ratio = mean_b > 0 ? mean_a / mean_b : 0.0;
          sign[a][b] = pair.difference.sign;
          if (a < b) comparison.pairwise.push_back(pair);
        }
      // The winner: beats every other row of the group.
      for (size_t a = 0; a < members.size(); ++a) {
        bool beats_all = true;
        for (size_t b = 0; b < members.size(); ++b)
          if (a != b && sign[a][b] != -1) beats_all = false;
        if (beats_all) table.rows[members[a]].best.insert("mrse:" + region);
      }
    }
  }

  // Efficiency: per repeat (MRSE x seconds of the baseline) / (MRSE x seconds of the row).
  for (const auto& [group, members] : groups) {
    const BatchTableRow* baseline = nullptr;
    for (size_t i : members)
      if (table.rows[i].label == comparison.baseline) baseline = &table.rows[i];
    if (!baseline) continue;
    auto cost_by_repeat = [&](const BatchTableRow& row) {
      std::map<int, double> cost;
      for (size_t r : row.run_indices) {
        const BatchRun& run = result.methods[row.method_index].runs[r];
        const double error =
            noise.corrected("image", recomputed.at(row.method_index).at(r).at("image").mrse);
        if (error > 0 && run.compute_seconds > 0) cost[run.repeat] = error * run.compute_seconds;
      }
      return cost;
    };
    const std::map<int, double> base = cost_by_repeat(*baseline);
    for (size_t i : members) {
      BatchTableRow& row = table.rows[i];
      std::vector<double> ratios;
      for (const auto& [repeat, cost] : cost_by_repeat(row)) {
        auto other = base.find(repeat);
        if (other != base.end()) ratios.push_back(other->second / cost);
      }
      row.efficiency = mean_interval(ratios);
    }
  }
  return comparison;
}

BatchResult corrected_curves(const BatchResult& result, const ReferenceNoise& noise) {
  BatchResult copy = result;
  for (BatchMethod& method : copy.methods)
    for (BatchRun& run : method.runs)
      for (BatchCurvePoint& point : run.curve) {
        point.mrse = noise.corrected("image", point.mrse);
        for (auto& [region, value] : point.regions) value = noise.corrected(region, value);
      }
  return copy;
}

RecomputedErrors corrected_errors(const RecomputedErrors& recomputed, const ReferenceNoise& noise) {
  RecomputedErrors copy = recomputed;
  for (auto& runs : copy)
    for (auto& regions : runs)
      for (auto& [region, summary] : regions) summary.mrse = noise.corrected(region, summary.mrse);
  return copy;
}

}  // namespace penumbra

namespace penumbra {

namespace {

nlohmann::json interval_json(const MeanInterval& interval) {
  nlohmann::json entry = {{"mean", interval.mean}, {"count", interval.count}};
  if (interval.has_interval) {
    entry["lower"] = interval.lower();
    entry["upper"] = interval.upper();
  }
  return entry;
}

}  // namespace

void add_comparison_json(nlohmann::json& table_json, const BatchTable& table,
                         const BatchComparison& comparison, const ReferenceNoise& noise) {
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const BatchTableRow& row = table.rows[i];
    nlohmann::json& entry = table_json["rows"][i];
    if (!row.refusal.empty()) continue;
    nlohmann::json cells = nlohmann::json::object();
    for (const auto& [region, cell] : row.cells) {
      nlohmann::json value = interval_json(cell.corrected);
      value["plain"] = interval_json(cell.plain);
      value["reference_share"] = cell.reference_share;
      value["reference_flagged"] = cell.reference_flagged;
      cells[region] = value;
    }
    entry["mrse_corrected"] = cells;
    if (row.efficiency.count > 0) entry["efficiency"] = interval_json(row.efficiency);
  }
  table_json["baseline"] = comparison.baseline;
  table_json["reference_share_flag"] = kReferenceShareFlag;
  nlohmann::json reference = {{"has_variance", noise.has_variance}};
  for (const auto& [region, error] : noise.regions)
    reference["regions"][region] = {{"term", error.reference_term},
                                    {"deviation", error.reference_deviation}};
  for (const auto& [region, share] : noise.fallback)
    reference["fallback"][region] = {{"pixel_share", share.pixels},
                                     {"sample_share", share.samples}};
  table_json["reference_noise"] = reference;
  nlohmann::json pairwise = nlohmann::json::array();
  for (const PairwiseComparison& pair : comparison.pairwise)
    pairwise.push_back({{"group", pair.group},
                        {"region", pair.region},
                        {"a", table.rows[pair.row_a].label},
                        {"b", table.rows[pair.row_b].label},
                        {"ratio", pair.ratio},
                        {"difference", pair.difference.difference},
                        {"half_width", pair.difference.half_width},
                        {"p_value", pair.difference.p_value},
                        {"pairs", pair.difference.pairs},
                        {"significant", pair.difference.sign != 0},
                        {"better", pair.difference.sign < 0   ? table.rows[pair.row_a].label
                                   : pair.difference.sign > 0 ? table.rows[pair.row_b].label
                                                              : ""}});
  table_json["pairwise"] = pairwise;
}

}  // namespace penumbra

namespace penumbra {

ChartAnnotations chart_annotations(const BatchTable& table, const ReferenceNoise& noise) {
  ChartAnnotations annotations;
  if (noise.has_variance) annotations.y_label_note = ", corrected for the reference's noise";
  for (const BatchTableRow& row : table.rows)
    for (const auto& [region, cell] : row.cells)
      if (cell.reference_flagged)
        annotations.legend_suffix[{row.label, region}] =
            " [ref > " + std::to_string(int(std::lround(100 * kReferenceShareFlag))) + "%]";
  return annotations;
}

}  // namespace penumbra
