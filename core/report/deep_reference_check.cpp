// The check of a batch's table against a deeper reference (see the header).

#include "core/report/deep_reference_check.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "core/image/image.h"
#include "core/image/noise_corrected_mrse.h"
#include "core/report/batch_table.h"

namespace penumbra {

bool DeepCheck::passed() const {
  for (const DeepCheckCell& cell : cells)
    if (!cell.within) return false;
  return !cells.empty();
}

double DeepCheck::worst_deviation() const {
  double worst = 0;
  for (const DeepCheckCell& cell : cells) worst = std::max(worst, std::abs(cell.ratio - 1));
  return worst;
}

DeepCheck check_against_deep_reference(const std::filesystem::path& result_dir,
                                       const std::filesystem::path& deep_reference,
                                       double tolerance) {
  const BatchResult result = read_batch_result(result_dir);
  DeepCheck check;
  check.deep_reference = deep_reference;
  check.tolerance = tolerance;
  check.reference_spp = result.reference.spp;
  Image reference_variance, deep_variance;
  const Image reference =
      read_exr((result_dir / result.reference.exr).string(), nullptr, &reference_variance);
  ImageMetadata deep_metadata;
  const Image deep = read_exr(deep_reference.string(), &deep_metadata, &deep_variance);
  if (deep.width != reference.width || deep.height != reference.height)
    throw std::runtime_error(deep_reference.string() + " is " + std::to_string(deep.width) + "x" +
                             std::to_string(deep.height) + ", the batch's reference is " +
                             std::to_string(reference.width) + "x" +
                             std::to_string(reference.height));
  check.deep_spp = uint32_t(std::atoll(deep_metadata["penumbra:spp"].c_str()));

  const BatchTable table = make_batch_table(result, recompute_batch_errors(result, result_dir));
  std::map<std::string, Region> regions = result.region_map();
  regions["image"] = Region{0, 0, reference.width, reference.height};
  for (const BatchTableRow& row : table.rows) {
    if (!row.refusal.empty() || row.run_indices.empty()) continue;
    const BatchMethod& method = result.methods[row.method_index];
    std::vector<Image> runs;
    for (size_t index : row.run_indices)
      runs.push_back(read_exr((result_dir / method.runs[index].exr).string()));
    for (const std::string& region_name : table.regions) {
      const Region& region = regions.at(region_name);
      DeepCheckCell cell;
      cell.label = row.label;
      cell.budget =
          row.budget_seconds ? std::string("equal time") : std::to_string(row.spp_max) + " spp";
      cell.region = region_name;
      cell.repeats = int(runs.size());
      for (const Image& run : runs) {
        const NoiseCorrectedError against_batch =
            noise_corrected_mrse(run, reference, reference_variance, region);
        const NoiseCorrectedError against_deep =
            noise_corrected_mrse(run, deep, deep_variance, region);
        cell.reported += against_batch.corrected / double(runs.size());
        cell.reported_plain += against_batch.plain / double(runs.size());
        cell.deep += against_deep.corrected / double(runs.size());
        cell.deep_plain += against_deep.plain / double(runs.size());
      }
      cell.ratio = cell.deep > 0 ? cell.reported / cell.deep : 0;
      cell.within = cell.deep > 0 && std::abs(cell.ratio - 1) <= tolerance;
      check.cells.push_back(cell);
    }
  }
  return check;
}

std::string deep_check_text(const DeepCheck& check) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "%-34s %-11s %-18s %12s %12s %8s %12s %12s\n", "method",
                "budget", "region", "reported", "deep", "ratio", "plain", "plain deep");
  out += line;
  for (const DeepCheckCell& cell : check.cells) {
    std::snprintf(line, sizeof line, "%-34s %-11s %-18s %12.5g %12.5g %8.4f %12.5g %12.5g%s\n",
                  cell.label.c_str(), cell.budget.c_str(), cell.region.c_str(), cell.reported,
                  cell.deep, cell.ratio, cell.reported_plain, cell.deep_plain,
                  cell.within ? "" : "  FAIL");
    out += line;
  }
  int failing = 0;
  for (const DeepCheckCell& cell : check.cells) failing += cell.within ? 0 : 1;
  std::snprintf(line, sizeof line,
                "%s: %zu cells, %d outside %.0f%%; worst |ratio - 1| = %.4f (reference %u spp, "
                "deep reference %s, %u spp)\n",
                check.passed() ? "PASS" : "FAIL", check.cells.size(), failing,
                100 * check.tolerance, check.worst_deviation(), check.reference_spp,
                check.deep_reference.string().c_str(), check.deep_spp);
  out += line;
  return out;
}

nlohmann::json deep_check_json(const DeepCheck& check) {
  nlohmann::json cells = nlohmann::json::array();
  for (const DeepCheckCell& cell : check.cells)
    cells.push_back({{"label", cell.label},
                     {"budget", cell.budget},
                     {"region", cell.region},
                     {"repeats", cell.repeats},
                     {"reported", cell.reported},
                     {"deep", cell.deep},
                     {"reported_plain", cell.reported_plain},
                     {"deep_plain", cell.deep_plain},
                     {"ratio", cell.ratio},
                     {"within", cell.within}});
  return {{"format", "penumbra/depth-check@1"},
          {"deep_reference", check.deep_reference.string()},
          {"reference_spp", check.reference_spp},
          {"deep_spp", check.deep_spp},
          {"tolerance", check.tolerance},
          {"passed", check.passed()},
          {"worst_deviation", check.worst_deviation()},
          {"cells", cells}};
}

}  // namespace penumbra
