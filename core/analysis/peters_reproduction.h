#pragma once
// Peters 2021 ("BRDF Importance Sampling for Polygonal Lights") targets of METHODS.md, measured on
// random configurations:
//   (1) projected solid angle sampling (`psa`, through the renderer's estimator) of an unoccluded
//       Lambertian polygon light on a Lambertian surface has near-zero variance: relative
//       standard deviation of one-sample estimates below 1e-4;
//   (2) the backward error of the sampler (Sec. 3.6) below 1e-5.
//
// Configurations: a convex polygon of 3-8 vertices around a random direction of the upper
// hemisphere (every third near the zenith, so central and decentral cases are both common), at
// a distance log-uniform in [0.01, 100], of a size log-uniform in [0.01, 3] times that distance,
// with a random orientation; polygons may cross the horizon. Deterministic per seed.

#include <cstdint>
#include <vector>

#include "core/math/vec.h"

namespace penumbra {

// A random convex polygon relative to a shading point at the origin with normal +z, wound
// counter-clockwise seen from the origin (so a polygon light made of it emits towards the
// point). `index` selects the configuration of the stream `seed`.
std::vector<Vec3> random_polygon_configuration(uint64_t seed, uint64_t index);

struct PsaVarianceResult {
  int configurations = 0;  // measured (those with light above the horizon)
  int samples_per_configuration = 0;
  double max_relative_deviation = 0;  // over the configurations
  double median_relative_deviation = 0;
  int nonfinite_estimates = 0;
};

// One-sample estimates of the `psa` method at a Lambertian point under a Lambertian-emitting
// polygon light, nothing occluding: their relative standard deviation per configuration.
PsaVarianceResult measure_psa_relative_deviation(int configurations, int samples, uint64_t seed);

struct BackwardErrorResult {
  int configurations = 0;
  int iterations = 0;
  double max_error = 0;
  double p99_error = 0;
  // Samples in sectors whose area cancels more than 10 digits (slivers of ~1e-15 sr at the
  // horizon): their area, hence any backward error, is rounding noise; they are counted and
  // left out of the statistics, as Peters leaves out areas below 1e-7 (Sec. 3.6).
  int rounding_limited = 0;
  int failed_samples = 0;  // sample() returned nothing although the polygon has area
};

BackwardErrorResult measure_psa_backward_error(int configurations, int iterations, uint64_t seed);

}  // namespace penumbra
