// The runs and the reference of a bias check (see the header).

#include "core/analysis/verify.h"

#include <cmath>
#include <stdexcept>

namespace penumbra {

Scene scene_at_width(const Scene& scene, int width) {
  if (width < 1) throw std::invalid_argument("the width must be at least 1 pixel");
  Scene out = scene;
  Camera& camera = out.camera;
  const double factor = double(width) / camera.width;
  auto scaled = [factor](int pixels) { return int(std::lround(pixels * factor)); };
  camera.height = std::max(1, scaled(camera.height));
  camera.width = width;
  if (camera.full_width > 0) {
    camera.full_width = std::max(camera.width, scaled(camera.full_width));
    camera.full_height = std::max(camera.height, scaled(camera.full_height));
    camera.crop_x = scaled(camera.crop_x);
    camera.crop_y = scaled(camera.crop_y);
  }
  out.regions.clear();
  return out;
}

VerifyReference render_verify_reference(std::shared_ptr<const Scene> scene,
                                        const ExactReferenceOptions& options) {
  ExactReferenceImage image = render_exact_reference(scene, options);
  VerifyReference reference;
  reference.film = std::move(image.film);
  reference.exact_fraction = std::move(image.exact_fraction);
  const double total = double(image.exact_samples + image.fallback_samples);
  reference.exact_share = total > 0 ? double(image.exact_samples) / total : 0;
  reference.compute_seconds = image.compute_seconds;
  reference.seed = options.seed;
  char text[256];
  std::snprintf(text, sizeof text,
                "exact (closed form on %.1f%% of camera samples, %s with %d samples per term "
                "elsewhere), %u camera samples per pixel, seed %llu",
                100 * reference.exact_share, options.shading.fallback_method.c_str(),
                options.shading.fallback_samples, options.camera_samples,
                (unsigned long long)options.seed);
  reference.description = text;
  return reference;
}

VerifyReference render_deep_reference(std::shared_ptr<const Scene> scene, const std::string& method,
                                      Pattern sampler, uint32_t spp, uint64_t seed, int threads) {
  Renderer renderer(scene, RenderOptions{method, sampler, seed});
  RenderBudget budget;
  budget.spp = spp;
  LocalRenderResult render = render_local(renderer, budget, threads);
  VerifyReference reference;
  reference.film = std::move(render.film);
  reference.compute_seconds = render.compute_seconds;
  reference.seed = seed;
  reference.description = "deep render: " + method + ", " + std::string(pattern_name(sampler)) +
                          ", " + std::to_string(spp) + " spp, seed " + std::to_string(seed);
  return reference;
}

RunRenderer method_run_renderer(std::shared_ptr<const Scene> scene, const std::string& method,
                                Pattern sampler, const RenderBudget& budget, int threads) {
  // Checks the method against the scene once, before any run.
  { Renderer check(scene, RenderOptions{method, sampler, 0}); }
  return [scene, method, sampler, budget, threads](int, uint64_t seed) {
    Renderer renderer(scene, RenderOptions{method, sampler, seed});
    return render_local(renderer, budget, threads).film;
  };
}

VerifyResult verify_runs(const VerifyReference& reference, int runs, uint64_t seed,
                         const RunRenderer& render, const BiasCheckOptions& options) {
  if (runs < 2) throw std::invalid_argument("verify needs at least 2 runs");
  if (reference.seed >= seed && reference.seed - seed < uint64_t(runs))
    throw std::invalid_argument("the runs' seeds " + std::to_string(seed) + ".." +
                                std::to_string(seed + uint64_t(runs) - 1) +
                                " include the reference's (" + std::to_string(reference.seed) +
                                "): their noise would not be independent");
  std::vector<Film> films;
  VerifyResult result;
  for (int i = 0; i < runs; ++i) {
    films.push_back(render(i, seed + uint64_t(i)));
    if (films.back().nonfinite_samples > 0)
      throw std::runtime_error("run " + std::to_string(i) + " had " +
                               std::to_string(films.back().nonfinite_samples) +
                               " non-finite samples");
    result.spp.push_back(films.back().min_spp);
  }
  result.check = check_bias(reference.film, &reference.exact_fraction, films, options);
  return result;
}

}  // namespace penumbra
