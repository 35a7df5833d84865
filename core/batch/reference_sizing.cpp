// Sizing an auto reference (the derivation is in the header).

#include "core/batch/reference_sizing.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace penumbra {

namespace {

void check_value(double value, const std::string& what) {
  if (!std::isfinite(value) || value < 0)
    throw std::invalid_argument("reference sizing: " + what + " is " + std::to_string(value) +
                                " (must be finite and non-negative)");
}

}  // namespace

double quarter_octave_ceil(double x) {
  if (!(x > 1)) return 1;
  // The first grid point at or above x: k = ceil(4 log2 x), corrected for rounding both ways.
  double k = std::ceil(4.0 * std::log2(x));
  while (k > 0 && std::ceil(std::exp2((k - 1) / 4.0) - 1e-9) >= x) k -= 1;
  while (std::ceil(std::exp2(k / 4.0) - 1e-9) < x) k += 1;
  return std::ceil(std::exp2(k / 4.0) - 1e-9);
}

ReferenceSizing size_reference(const ReferenceSizingRequest& request) {
  if (!(request.target_share > 0) || !(request.target_share < 1))
    throw std::invalid_argument("reference sizing: the target share must lie in (0, 1), got " +
                                std::to_string(request.target_share));
  check_value(request.seconds_per_pass, "the reference's seconds per pass");
  check_value(request.max_seconds, "the reference's compute budget");
  ReferenceSizing sizing;
  // Per region: the best method's error and the spp that brings the reference to the target.
  struct Need {
    double best = 0;
    int best_method = -1;
    double noise = 0;
  };
  std::vector<Need> needs(request.regions.size());
  for (size_t r = 0; r < request.regions.size(); ++r) {
    const ReferenceSizingRegion& region = request.regions[r];
    if (region.expected.empty())
      throw std::invalid_argument("reference sizing: region '" + region.name +
                                  "' has no method's error");
    check_value(region.reference_noise, "the reference noise of region '" + region.name + "'");
    Need& need = needs[r];
    need.noise = region.reference_noise;
    need.best = std::numeric_limits<double>::infinity();
    for (size_t m = 0; m < region.expected.size(); ++m) {
      check_value(region.expected[m],
                  "method " + std::to_string(m) + "'s expected error in '" + region.name + "'");
      if (region.expected[m] < need.best) {
        need.best = region.expected[m];
        need.best_method = int(m);
      }
    }
    if (!(need.best > 0)) continue;  // nothing to be a share of
    const double required = need.noise / (request.target_share * need.best);
    if (required > sizing.required_spp) sizing.required_spp = required;
  }
  const double wanted = quarter_octave_ceil(std::max(1.0, sizing.required_spp));
  double cap = double(std::max<uint32_t>(request.max_spp, 1));
  if (request.seconds_per_pass > 0)
    cap = std::min(cap, std::max(1.0, std::floor(request.max_seconds / request.seconds_per_pass)));
  sizing.capped = sizing.required_spp > cap;
  sizing.spp = uint32_t(std::clamp(wanted, 1.0, cap));
  sizing.predicted_seconds = double(sizing.spp) * request.seconds_per_pass;
  // The prediction at the chosen spp, in the region where the reference weighs most.
  for (size_t r = 0; r < needs.size(); ++r) {
    if (!(needs[r].best > 0)) continue;
    const double ratio = needs[r].noise / double(sizing.spp) / needs[r].best;
    if (sizing.deciding_region.empty() || ratio > sizing.predicted_ratio) {
      sizing.predicted_ratio = ratio;
      sizing.deciding_region = request.regions[r].name;
      sizing.best_method = needs[r].best_method;
    }
  }
  sizing.predicted_share = sizing.predicted_ratio / (1 + sizing.predicted_ratio);
  return sizing;
}

}  // namespace penumbra
