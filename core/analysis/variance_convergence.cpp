// Per-pixel variance against N, and its log-log slope (variance_convergence.h).

#include "core/analysis/variance_convergence.h"

#include <stdexcept>

#include "core/render/probe.h"

namespace penumbra {

ChartSeries VarianceConvergence::series(const std::string& name) const {
  ChartSeries s;
  s.name = name;
  s.lines = false;
  for (size_t i = 0; i < counts.size(); ++i) {
    s.x.push_back(counts[i]);
    s.y.push_back(mean_variance[i]);
  }
  int usable = 0;
  for (double v : mean_variance) usable += v > 0;
  if (usable >= 2) s.fit = fit_line(s, true, true);
  return s;
}

VarianceConvergence measure_variance_convergence(std::shared_ptr<const Scene> scene,
                                                 const std::vector<std::pair<int, int>>& pixels,
                                                 const std::string& method, Pattern sampler,
                                                 const std::vector<int>& counts, int trials,
                                                 uint64_t seed) {
  if (counts.size() < 2)
    throw std::invalid_argument("variance convergence: at least 2 sample counts are needed");
  if (pixels.empty()) throw std::invalid_argument("variance convergence: no pixels");
  ProbeSpec probe;
  probe.pixels = pixels;
  ProbeResult probed = run_probe(scene, probe, method, sampler, counts, trials, seed);

  VarianceConvergence result;
  result.method = method;
  result.sampler = sampler;
  result.trials = trials;
  result.counts = counts;
  result.mean_variance.assign(counts.size(), 0.0);
  for (const std::vector<ProbeRun>& runs : probed.points)
    for (size_t i = 0; i < runs.size(); ++i)
      result.mean_variance[i] += (runs[i].variance.x + runs[i].variance.y + runs[i].variance.z) /
                                 3.0 / double(probed.points.size());
  // Slope in log-log; counts whose variance is 0 (a pixel the method renders exactly) are left
  // out by the fit, and with fewer than 2 left the slope is reported as 0.
  int usable = 0;
  for (double v : result.mean_variance) usable += v > 0;
  if (usable >= 2) result.variance_slope = result.series("").fit->slope;
  return result;
}

}  // namespace penumbra
