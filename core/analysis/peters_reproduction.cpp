// Peters 2021 targets on random configurations (peters_reproduction.h).

#include "core/analysis/peters_reproduction.h"

#include <algorithm>
#include <cmath>

#include "core/math/projected_solid_angle.h"
#include "core/method/direct_lighting.h"
#include "core/method/method.h"
#include "core/sampling/pattern.h"
#include "core/scene/light_setup.h"

namespace penumbra {

namespace {

class NothingOccludes : public Visibility {
 public:
  bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
};

// A uniform direction on the unit sphere from two uniform numbers.
Vec3 sphere_direction(double u, double v) {
  double z = 1.0 - 2.0 * u;
  double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  double phi = 2.0 * kPi * v;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

double log_uniform(double u, double low, double high) {
  return std::exp(std::log(low) + u * (std::log(high) - std::log(low)));
}

}  // namespace

std::vector<Vec3> random_polygon_configuration(uint64_t seed, uint64_t index) {
  StreamKey key{seed, index, 0, 0};
  uint32_t dimension = 0;
  auto next = [&] { return random_uniform(key, 0, dimension++); };

  int vertex_count = 3 + std::min(5, int(next() * 6));
  // Direction of the polygon's centre: the upper hemisphere, every third near the zenith.
  Vec3 direction = sphere_direction(next(), next());
  direction.z = std::abs(direction.z);
  if (index % 3 == 0) direction = normalize(Vec3{direction.x, direction.y, 3.0});
  double distance = log_uniform(next(), 0.01, 100.0);
  double radius = distance * log_uniform(next(), 0.01, 3.0);
  double aspect = 0.1 + 0.9 * next();
  Vec3 centre = direction * distance;

  // The polygon's plane: a random orientation, facing the origin.
  Vec3 normal = sphere_direction(next(), next());
  if (dot(normal, centre) > 0) normal = -normal;  // emits towards the origin
  if (std::abs(dot(normal, normalize(centre))) < 1e-3) normal = -normalize(centre);
  Frame frame = Frame::from_normal(normal);

  // Vertices on an ellipse at sorted random angles (convex), counter-clockwise about `normal`.
  std::vector<double> angles(vertex_count);
  for (double& a : angles) a = 2.0 * kPi * next();
  std::sort(angles.begin(), angles.end());
  std::vector<Vec3> vertices;
  for (double a : angles)
    vertices.push_back(centre + radius * (std::cos(a) * frame.s + aspect * std::sin(a) * frame.t));
  // Frame::from_normal is right-handed (s x t = n), so increasing angle winds counter-clockwise
  // about the normal; make sure anyway.
  Vec3 winding = cross(vertices[1] - vertices[0], vertices[2] - vertices[0]);
  if (dot(winding, normal) < 0) std::reverse(vertices.begin(), vertices.end());
  return vertices;
}

PsaVarianceResult measure_psa_relative_deviation(int configurations, int samples, uint64_t seed) {
  PsaVarianceResult result;
  result.samples_per_configuration = samples;
  Material lambert;
  lambert.name = "lambert";
  lambert.albedo = {0.8, 0.8, 0.8};
  const MethodSpec psa = parse_method("psa");
  NothingOccludes nothing;
  std::vector<double> deviations;

  for (uint64_t index = 0; int(deviations.size()) < configurations; ++index) {
    Scene scene;
    scene.materials = {lambert};
    try {
      scene.lights = {make_polygon_light(random_polygon_configuration(seed, index), {1, 1, 1})};
    } catch (const std::invalid_argument&) {
      continue;  // a degenerate polygon (collinear angles): not a light
    }
    ShadingPoint sp;
    sp.position = {0, 0, 0};
    sp.normal = {0, 0, 1};
    sp.wo = normalize(Vec3{0.3, -0.2, 1.0});
    sp.material = &scene.materials[0];
    DirectLighting estimator(scene, psa);

    double mean = 0, sum_squares = 0;
    bool has_light = true;
    for (int s = 0; s < samples; ++s) {
      StreamKey key{seed ^ 0x9E7E85ull, index, uint32_t(s), 0};
      Rgb e = estimator.estimate(sp, nothing, Pattern::Random, key, 1);
      double value = e.x;
      if (!std::isfinite(value)) {
        ++result.nonfinite_estimates;
        value = 0;
      }
      if (s == 0 && !(value > 0)) {
        has_light = false;  // nothing above the horizon: the estimate is exactly 0
        break;
      }
      // Welford's update: the estimates agree to ~1e-15, so naive sums would cancel.
      double delta = value - mean;
      mean += delta / (s + 1);
      sum_squares += delta * (value - mean);
    }
    if (!has_light) continue;
    double deviation = std::sqrt(sum_squares / std::max(1, samples - 1)) / mean;
    deviations.push_back(std::isfinite(deviation) ? deviation : 1.0);
  }
  result.configurations = int(deviations.size());
  std::sort(deviations.begin(), deviations.end());
  if (!deviations.empty()) {
    result.max_relative_deviation = deviations.back();
    result.median_relative_deviation = deviations[deviations.size() / 2];
  }
  return result;
}

BackwardErrorResult measure_psa_backward_error(int configurations, int iterations, uint64_t seed) {
  BackwardErrorResult result;
  result.iterations = iterations;
  std::vector<double> errors;
  errors.reserve(configurations);
  for (uint64_t index = 0; int(errors.size()) < configurations; ++index) {
    std::vector<Vec3> polygon = random_polygon_configuration(seed, index);
    ProjectedSolidAngleSampler sampler(polygon, iterations);
    if (!(sampler.projected_solid_angle() > 0)) continue;
    StreamKey key{seed ^ 0xBAC4E440ull, index, 0, 0};
    Vec2 u{random_uniform(key, 0, 0), random_uniform(key, 0, 1)};
    std::optional<Vec3> direction = sampler.sample(u);
    if (!direction) {
      ++result.failed_samples;
      errors.push_back(1.0);
      continue;
    }
    if (sampler.area_cancellation(u.x) > 1e10) {
      ++result.rounding_limited;
      continue;
    }
    double error = sampler.backward_error(u, *direction);
    errors.push_back(std::isfinite(error) ? error : 1.0);
  }
  result.configurations = int(errors.size());
  std::sort(errors.begin(), errors.end());
  if (!errors.empty()) {
    result.max_error = errors.back();
    result.p99_error = errors[size_t(0.99 * double(errors.size() - 1))];
  }
  return result;
}

}  // namespace penumbra
