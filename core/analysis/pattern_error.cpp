// Sampling patterns compared at penumbra pixels of a rendered scene (pattern_error.h).

#include "core/analysis/pattern_error.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "core/analysis/disk_square_rejection.h"
#include "core/method/method.h"
#include "core/render/camera.h"
#include "core/render/shading.h"

namespace penumbra {

namespace {

// The scene without its occluders, for the unshadowed estimate of the screening.
class NothingOccludes : public Visibility {
 public:
  bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
};

double channel_mean(const Rgb& c) {
  return (c.x + c.y + c.z) / 3.0;
}

// Runs body(i) for i in [0, count) on `threads` threads (0: all).
template <typename Body>
void parallel_over(int count, int threads, const Body& body) {
  int limit = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
  tbb::task_arena arena(limit);
  arena.execute([&] { tbb::parallel_for(0, count, [&](int i) { body(i); }); });
}

void check_options(const PatternErrorOptions& o) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("pattern error study: ") + what);
  };
  require(o.samples >= 1 && o.samples <= 1 << 16, "samples must be in 1..65536");
  require(o.trials >= 2, "at least 2 trials are needed");
  require(o.pixel_stride >= 1, "pixel_stride must be at least 1");
  require(o.max_pixels >= 2, "at least 2 pixels are needed for a comparison");
  require(o.screening_samples >= 1 && o.reference_samples >= 1 && o.reference_trials >= 1,
          "screening and reference sample counts must be positive");
  require(o.min_visible_fraction >= 0 && o.min_visible_fraction < o.max_visible_fraction &&
              o.max_visible_fraction <= 1,
          "need 0 <= min_visible_fraction < max_visible_fraction <= 1");
}

}  // namespace

const PatternErrorResult& PatternErrorStudy::result(Pattern pattern) const {
  for (const PatternErrorResult& r : patterns)
    if (r.pattern == pattern) return r;
  throw std::out_of_range("pattern error study: pattern " + std::string(pattern_name(pattern)) +
                          " was not measured");
}

namespace {

struct ScreenedPixels {
  PenumbraPixels pixels;
  std::vector<ShadingPoint> points;
};

ScreenedPixels screen_penumbra_pixels(const Scene& scene, const SceneShading& shading,
                                      const PatternErrorOptions& options) {
  const DirectLighting& estimator = shading.direct_lighting();
  CameraRays camera(scene.camera);
  NothingOccludes unoccluded;

  Region region{0, 0, scene.camera.width, scene.camera.height};
  if (!options.region.empty()) {
    auto it = scene.regions.find(options.region);
    if (it == scene.regions.end())
      throw FormatError("regions",
                        "scene \"" + scene.name + "\" has no region \"" + options.region + "\"");
    region = it->second;
  }

  // Screen the candidates: the visible fraction of each pixel's shading point.
  std::vector<std::pair<int, int>> candidates;
  for (int y = region.y0 + options.pixel_stride / 2; y < region.y1; y += options.pixel_stride)
    for (int x = region.x0 + options.pixel_stride / 2; x < region.x1; x += options.pixel_stride)
      if (x >= 0 && y >= 0 && x < scene.camera.width && y < scene.camera.height)
        candidates.emplace_back(x, y);
  std::vector<std::optional<ShadingPoint>> points(candidates.size());
  std::vector<double> fraction(candidates.size(), -1.0);
  const uint64_t screening_seed = options.seed ^ 0x5C12EE4ull;
  parallel_over(int(candidates.size()), options.threads, [&](int i) {
    auto [x, y] = candidates[i];
    SceneShading::FirstHit hit =
        shading.first_hit(camera.origin(), camera.direction(x + 0.5, y + 0.5));
    if (!hit.shading_point) return;
    StreamKey key{screening_seed, uint64_t(i), 0, 0};
    double lit = channel_mean(estimator.estimate(
        *hit.shading_point, unoccluded, Pattern::Stratified, key, options.screening_samples));
    if (!(lit > 0)) return;
    double shadowed = channel_mean(estimator.estimate(
        *hit.shading_point, shading, Pattern::Stratified, key, options.screening_samples));
    points[i] = hit.shading_point;
    fraction[i] = shadowed / lit;
  });

  ScreenedPixels out;
  out.pixels.candidates = int(candidates.size());
  std::vector<size_t> penumbra;
  for (size_t i = 0; i < candidates.size(); ++i)
    if (points[i] && fraction[i] >= options.min_visible_fraction &&
        fraction[i] <= options.max_visible_fraction)
      penumbra.push_back(i);
  if (penumbra.size() < 2)
    throw std::invalid_argument(
        "pattern error study: fewer than 2 penumbra pixels in " +
        (options.region.empty() ? std::string("the image") : "region " + options.region) +
        " of scene " + scene.name);
  // At most max_pixels of them, evenly spread over the candidates' (row-major) order.
  size_t count = std::min(penumbra.size(), size_t(options.max_pixels));
  for (size_t j = 0; j < count; ++j) {
    size_t i = penumbra[j * penumbra.size() / count];
    out.pixels.pixels.push_back(candidates[i]);
    out.pixels.visible_fraction.push_back(fraction[i]);
    out.points.push_back(*points[i]);
  }
  return out;
}

}  // namespace

PenumbraPixels find_penumbra_pixels(std::shared_ptr<const Scene> scene,
                                    const PatternErrorOptions& options) {
  check_options(options);
  SceneShading shading(scene, parse_method(options.method));
  return screen_penumbra_pixels(*scene, shading, options).pixels;
}

std::vector<PatternErrorStudy> measure_pattern_error_sweep(std::shared_ptr<const Scene> scene,
                                                           const std::vector<Pattern>& patterns,
                                                           const std::vector<int>& sample_counts,
                                                           const PatternErrorOptions& options) {
  check_options(options);
  for (int n : sample_counts)
    if (n < 1 || n > 1 << 16)
      throw std::invalid_argument("pattern error study: sample counts must be in 1..65536");
  if (options.disk_sampling == DiskSampling::SquareRejection)
    for (const Light& light : scene->lights)
      if (light.type != LightType::Disk)
        throw std::invalid_argument(
            "pattern error study: square rejection sampling needs disk "
            "lights only; scene " +
            scene->name + " has another light");
  SceneShading shading(scene, parse_method(options.method));
  const DirectLighting& estimator = shading.direct_lighting();
  ScreenedPixels screened = screen_penumbra_pixels(*scene, shading, options);
  const std::vector<ShadingPoint>& measured = screened.points;

  PatternErrorStudy base;
  base.scene = scene->name;
  base.options = options;
  base.candidate_pixels = screened.pixels.candidates;
  base.pixels = screened.pixels.pixels;
  base.visible_fraction = screened.pixels.visible_fraction;

  // References: the mean of a few long stratified estimates.
  base.reference.assign(measured.size(), 0.0);
  const uint64_t reference_seed = options.seed ^ 0x8EFE8E4CEull;
  parallel_over(int(measured.size()), options.threads, [&](int p) {
    double sum = 0;
    for (int t = 0; t < options.reference_trials; ++t) {
      StreamKey key{reference_seed, uint64_t(p), uint32_t(t), 0};
      sum += channel_mean(estimator.estimate(measured[p], shading, Pattern::Stratified, key,
                                             options.reference_samples));
    }
    base.reference[p] = sum / options.reference_trials;
  });
  double reference_squares = 0;
  for (double r : base.reference) reference_squares += r * r;

  std::vector<PatternErrorStudy> studies;
  for (int n : sample_counts) {
    PatternErrorStudy study = base;
    study.options.samples = n;
    // Each pattern's squared error at each pixel; independent streams per (N, pattern).
    for (size_t index = 0; index < patterns.size(); ++index) {
      Pattern pattern = patterns[index];
      PatternErrorResult result;
      result.pattern = pattern;
      result.pixel_squared_error.assign(measured.size(), 0.0);
      // The uniform pattern has no randomness: every trial gives the same estimate.
      const int trials = pattern == Pattern::Uniform ? 1 : options.trials;
      const uint64_t seed = options.seed + 0x9E3779B97F4A7C15ull * uint64_t(n) + index + 1;
      auto start = std::chrono::steady_clock::now();
      parallel_over(int(measured.size()), options.threads, [&](int p) {
        double sum = 0;
        for (int t = 0; t < trials; ++t) {
          StreamKey key{seed, uint64_t(p), uint32_t(t), 0};
          double e = channel_mean(options.disk_sampling == DiskSampling::SquareRejection
                                      ? estimate_disk_lights_by_square_rejection(
                                            *scene, measured[p], shading, pattern, key, n)
                                      : estimator.estimate(measured[p], shading, pattern, key, n));
          double d = e - study.reference[p];
          sum += d * d;
        }
        result.pixel_squared_error[p] = sum / trials;
      });
      result.seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      double total = 0;
      for (double e : result.pixel_squared_error) total += e;
      result.mean_squared_error = total / double(measured.size());
      result.relative_rms_error = reference_squares > 0 ? std::sqrt(total / reference_squares) : 0;
      study.patterns.push_back(std::move(result));
    }
    studies.push_back(std::move(study));
  }
  return studies;
}

PatternErrorStudy measure_pattern_errors(std::shared_ptr<const Scene> scene,
                                         const std::vector<Pattern>& patterns,
                                         const PatternErrorOptions& options) {
  return measure_pattern_error_sweep(scene, patterns, {options.samples}, options).front();
}

}  // namespace penumbra
