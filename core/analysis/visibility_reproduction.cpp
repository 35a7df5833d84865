// The tables and charts of Ramamoorthi et al. 2012, Sec. 4, from visibility_theory.h.

#include "core/analysis/visibility_reproduction.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace penumbra {

namespace {

using enum VisibilityPattern;
using enum DiscontinuityPlacement;

VisibilityErrorResult run(const VisibilityReproductionOptions& options, VisibilityPattern pattern,
                          int discontinuities, DiscontinuityPlacement placement, int samples = -1,
                          uint64_t seed_offset = 0) {
  VisibilityExperiment experiment;
  experiment.pattern = pattern;
  experiment.discontinuities = discontinuities;
  experiment.placement = placement;
  experiment.samples = samples > 0 ? samples : options.samples;
  experiment.trials = options.trials;
  experiment.seed = options.seed + seed_offset;
  experiment.threads = options.threads;
  return run_visibility_experiment(experiment);
}

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), pattern, value);
  return buffer;
}

std::string pad(std::string text, size_t width) {
  if (text.size() < width) text.append(width - text.size(), ' ');
  return text;
}

// The label of a (pattern, placement) series in a chart.
std::string series_label(const VisibilityExperiment& experiment, bool show_placement) {
  std::string label(visibility_pattern_name(experiment.pattern));
  if (show_placement) label += " (" + std::string(placement_name(experiment.placement)) + ")";
  return label;
}

// Rows grouped by (pattern, placement), in order of first appearance.
std::vector<std::vector<const VisibilityErrorResult*>> group_rows(const VisibilityTable& table) {
  std::vector<std::pair<std::pair<VisibilityPattern, DiscontinuityPlacement>,
                        std::vector<const VisibilityErrorResult*>>>
      groups;
  for (const VisibilityErrorResult& row : table.rows) {
    auto key = std::make_pair(row.experiment.pattern, row.experiment.placement);
    auto it = std::find_if(groups.begin(), groups.end(),
                           [&](const auto& group) { return group.first == key; });
    if (it == groups.end()) {
      groups.push_back({key, {}});
      it = groups.end() - 1;
    }
    it->second.push_back(&row);
  }
  std::vector<std::vector<const VisibilityErrorResult*>> out;
  for (auto& group : groups) out.push_back(std::move(group.second));
  return out;
}

bool mixed_placements(const VisibilityTable& table) {
  for (const auto& row : table.rows)
    if (row.experiment.placement != table.rows.front().experiment.placement) return true;
  return false;
}

}  // namespace

VisibilityTable reproduce_one_discontinuity(const VisibilityReproductionOptions& options) {
  VisibilityTable table{"Fig. 4: one discontinuity (N = " + std::to_string(options.samples) + ")",
                        {}};
  for (VisibilityPattern pattern :
       {StratumEnds, Uniform, UniformJitter, Stratified, Halton, CanonicalHalton, Random})
    table.rows.push_back(run(options, pattern, 1, DistinctStrata));
  return table;
}

VisibilityTable reproduce_two_discontinuities(const VisibilityReproductionOptions& options) {
  VisibilityTable table{"Fig. 6: two discontinuities in different strata (N = " +
                            std::to_string(options.samples) + ")",
                        {}};
  for (VisibilityPattern pattern : {Uniform, UniformJitter, Stratified, Halton, CanonicalHalton})
    table.rows.push_back(run(options, pattern, 2, DistinctStrata));
  // Random sampling does not see strata; its closed form is for independent positions.
  table.rows.push_back(run(options, Random, 2, Independent));
  return table;
}

VisibilityTable reproduce_discontinuity_count(const VisibilityReproductionOptions& options,
                                              int max_discontinuities) {
  VisibilityTable table{"Fig. 7a: error against the number of discontinuities (N = " +
                            std::to_string(options.samples) + ")",
                        {}};
  int k_max = std::min(max_discontinuities, options.samples);
  for (VisibilityPattern pattern : {Uniform, UniformJitter, Stratified, CanonicalHalton, Halton})
    for (int k = 1; k <= k_max; ++k) table.rows.push_back(run(options, pattern, k, DistinctStrata));
  return table;
}

VisibilityTable reproduce_extreme_case(const VisibilityReproductionOptions& options) {
  VisibilityTable table{"Fig. 7b: the extreme case (N = " + std::to_string(options.samples) + ")",
                        {}};
  const int n = options.samples;
  for (VisibilityPattern pattern : {Uniform, UniformJitter, Stratified, CanonicalHalton}) {
    for (int k : {10, 20, 50, 100})
      if (k <= n) table.rows.push_back(run(options, pattern, k, DistinctStrata));
    for (int per_stratum : {1, 4, 16})
      table.rows.push_back(run(options, pattern, per_stratum * n, Independent));
  }
  return table;
}

VisibilityTable reproduce_convergence(const VisibilityReproductionOptions& options,
                                      int discontinuities) {
  VisibilityTable table{"Convergence: " + std::to_string(discontinuities) +
                            " discontinuities, N = 4.." + std::to_string(options.samples),
                        {}};
  for (VisibilityPattern pattern : {Uniform, UniformJitter, Stratified, Random})
    for (int n = 4; n <= options.samples; n *= 2) {
      if (discontinuities > n) continue;
      DiscontinuityPlacement placement = pattern == Random ? Independent : DistinctStrata;
      // Each N its own trials (seed + N): the same trials at every N would make the normalized
      // errors of the deterministic patterns identical and the fitted slope exact by design.
      table.rows.push_back(run(options, pattern, discontinuities, placement, n, uint64_t(n)));
    }
  return table;
}

std::vector<VisibilityTable> reproduce_visibility_theory(
    const VisibilityReproductionOptions& options) {
  return {reproduce_one_discontinuity(options), reproduce_two_discontinuities(options),
          reproduce_discontinuity_count(options), reproduce_extreme_case(options),
          reproduce_convergence(options)};
}

std::string format_visibility_table(const VisibilityTable& table) {
  std::string text = table.title + "\n";
  text += pad("pattern", 18) + pad("placement", 17) + pad("k", 7) + pad("N", 6) + pad("trials", 8) +
          pad("N^2 x measured", 24) + pad("N^2 x predicted", 17) + pad("ratio", 8) + "formula\n";
  for (const VisibilityErrorResult& row : table.rows) {
    const VisibilityExperiment& e = row.experiment;
    double n2 = double(e.samples) * double(e.samples);
    text += pad(std::string(visibility_pattern_name(e.pattern)), 18);
    text += pad(std::string(placement_name(e.placement)), 17);
    text += pad(std::to_string(e.discontinuities), 7);
    text += pad(std::to_string(e.samples), 6);
    text += pad(std::to_string(e.trials), 8);
    text += pad(
        format("%.5g", row.normalized_error()) + " +- " + format("%.2g", row.standard_error * n2),
        24);
    text += pad(row.predicted ? format("%.5g", row.predicted->value * n2) : "-", 17);
    text += pad(row.ratio ? format("%.4f", *row.ratio) : "-", 8);
    text += row.predicted ? row.predicted->formula + "  [" + row.predicted->source + "]" : "";
    text += "\n";
  }
  return text;
}

ChartSpec discontinuity_count_chart(const VisibilityTable& table) {
  ChartSpec chart;
  chart.width = 1100;
  chart.height = 650;
  chart.title = table.title;
  chart.x_label = "discontinuities k";
  chart.y_label = "N^2 x expected squared error";
  bool show_placement = mixed_placements(table);
  int k_min = 0, k_max = 0;
  for (const auto& row : table.rows) {
    int k = row.experiment.discontinuities;
    k_min = k_min == 0 ? k : std::min(k_min, k);
    k_max = std::max(k_max, k);
  }
  chart.log_x = chart.log_y = k_min > 0 && k_max >= 20 * k_min;

  int color = 0;
  for (const auto& group : group_rows(table)) {
    ChartSeries measured, predicted;
    measured.name = series_label(group.front()->experiment, show_placement);
    measured.color = color;
    predicted.name = measured.name + " predicted";
    predicted.color = color;
    predicted.markers = false;
    predicted.dashed = true;
    for (const VisibilityErrorResult* row : group) {
      double n2 = double(row->experiment.samples) * double(row->experiment.samples);
      measured.x.push_back(row->experiment.discontinuities);
      measured.y.push_back(row->normalized_error());
      measured.y_error.push_back(2 * row->standard_error * n2);
      if (row->predicted) {
        predicted.x.push_back(row->experiment.discontinuities);
        predicted.y.push_back(row->predicted->value * n2);
      }
    }
    chart.series.push_back(measured);
    if (!predicted.x.empty()) chart.series.push_back(predicted);
    ++color;
  }
  return chart;
}

ChartSpec convergence_chart(const VisibilityTable& table) {
  ChartSpec chart;
  chart.width = 1100;
  chart.height = 650;
  chart.title = table.title;
  chart.x_label = "samples N";
  chart.y_label = "expected squared error";
  chart.log_x = chart.log_y = true;
  bool show_placement = mixed_placements(table);
  int color = 0;
  for (const auto& group : group_rows(table)) {
    ChartSeries measured;
    measured.name = series_label(group.front()->experiment, show_placement);
    measured.color = color++;
    measured.lines = false;
    for (const VisibilityErrorResult* row : group) {
      measured.x.push_back(row->experiment.samples);
      measured.y.push_back(row->mean_squared_error);
      measured.y_error.push_back(2 * row->standard_error);
    }
    if (measured.x.size() >= 2) measured.fit = fit_line(measured, true, true);
    chart.series.push_back(measured);
  }
  return chart;
}

}  // namespace penumbra
