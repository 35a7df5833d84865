#pragma once
// Per-pixel variance against the number of samples N (the convergence plots of Billen & Dutré
// Fig. 9 and Salesin & Jarosz Figs. 5, 7): the probe (core/render/probe.h) runs K independent
// estimates with N samples at each pixel; the variance of a pixel is the channel mean of the
// probe's unbiased sample variances, averaged over the pixels; the convergence rate is the
// least-squares slope of log(variance) against log(N) (METHODS.md).

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/image/chart.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"

namespace penumbra {

struct VarianceConvergence {
  std::string method;
  Pattern sampler = Pattern::Stratified;
  int trials = 0;
  std::vector<int> counts;                                       // N
  std::vector<double> mean_variance;                             // per N, averaged over the pixels
  double variance_slope = 0;                                     // d log(variance) / d log(N)
  double deviation_slope() const { return variance_slope / 2; }  // of the standard deviation

  // The measured series (variance against N) with its fitted line, for a log-log chart.
  ChartSeries series(const std::string& name) const;
};

// Throws FormatError when the method cannot run on the scene (e.g. a strategy that is not
// available yet) or a pixel is outside the image; std::invalid_argument for fewer than 2
// counts or no pixels.
VarianceConvergence measure_variance_convergence(std::shared_ptr<const Scene> scene,
                                                 const std::vector<std::pair<int, int>>& pixels,
                                                 const std::string& method, Pattern sampler,
                                                 const std::vector<int>& counts, int trials,
                                                 uint64_t seed);

}  // namespace penumbra
