#pragma once
// Binning of unit directions for the BSDF sampling tests (chi-square against a density).

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math/vec.h"

namespace penumbra::test {

// Directions binned around an axis: y = (1 - cos(angle to axis)) / 2 in [0, 1] (linear or
// logarithmic from y_min, for narrow lobes) times the azimuth. Solid angle: dw = 2 dy dphi.
struct DirectionBinning {
  Frame frame;
  bool log_scale = false;
  double y_min = 1e-8;
  int y_bins = 32;
  int phi_bins = 16;

  double s_of_y(double y) const {
    if (!log_scale) return y;
    if (y <= y_min) return 0;
    return 1.0 - std::log(y) / std::log(y_min);
  }
  double y_of_s(double s) const { return log_scale ? std::exp(std::log(y_min) * (1.0 - s)) : s; }
  double dy_ds(double s) const { return log_scale ? y_of_s(s) * -std::log(y_min) : 1.0; }
  Vec3 direction(double y, double phi) const {
    double cos_a = 1.0 - 2.0 * y;
    double sin_a = 2.0 * std::sqrt(std::max(0.0, y * (1.0 - y)));
    return frame.to_world({sin_a * std::cos(phi), sin_a * std::sin(phi), cos_a});
  }
  int bin(const Vec3& w) const {
    Vec3 local = frame.to_local(w);
    double y = std::clamp(0.5 * (1.0 - local.z), 0.0, 1.0);
    double phi = std::atan2(local.y, local.x);
    if (phi < 0) phi += 2.0 * kPi;
    int i = std::clamp(static_cast<int>(s_of_y(y) * y_bins), 0, y_bins - 1);
    int j = std::clamp(static_cast<int>(phi / (2.0 * kPi) * phi_bins), 0, phi_bins - 1);
    return i * phi_bins + j;
  }
  // Integral of the density over every bin (midpoint rule on a sub-grid of each bin).
  template <class Pdf>
  std::vector<double> integrate(const Pdf& pdf, int sub = 16) const {
    std::vector<double> mass(y_bins * phi_bins, 0.0);
    double ds = 1.0 / (y_bins * sub), dphi = 2.0 * kPi / (phi_bins * sub);
    for (int i = 0; i < y_bins * sub; ++i) {
      double s = (i + 0.5) * ds;
      double y = y_of_s(s);
      double weight = 2.0 * dy_ds(s) * ds * dphi;
      for (int j = 0; j < phi_bins * sub; ++j) {
        double phi = (j + 0.5) * dphi;
        mass[(i / sub) * phi_bins + j / sub] += pdf(direction(y, phi)) * weight;
      }
    }
    if (log_scale) {
      // The cap y in [0, y_min] belongs to the first ring.
      int cap_steps = 8;
      double dy = y_min / cap_steps;
      for (int i = 0; i < cap_steps; ++i) {
        double y = (i + 0.5) * dy;
        for (int j = 0; j < phi_bins * sub; ++j) {
          double phi = (j + 0.5) * dphi;
          mass[j / sub] += pdf(direction(y, phi)) * 2.0 * dy * dphi;
        }
      }
    }
    return mass;
  }
};

}  // namespace penumbra::test
