#include "core/render/film.h"

#include <algorithm>
#include <limits>
#include <sstream>

#include "penumbra/version.h"

namespace penumbra {

Film assemble_film(int width, int height, std::span<const TileAccumulator> tiles) {
  Film film;
  film.color = Image(width, height);
  film.variance = Image(width, height);
  uint32_t min_spp = std::numeric_limits<uint32_t>::max(), max_spp = 0;
  bool any = false;
  for (const TileAccumulator& tile : tiles) {
    const TileRect& r = tile.rect();
    film.nonfinite_samples += tile.nonfinite_samples();
    for (int y = std::max(r.y0, 0); y < std::min(r.y1, height); ++y) {
      for (int x = std::max(r.x0, 0); x < std::min(r.x1, width); ++x) {
        int64_t i = int64_t(y - r.y0) * r.width() + (x - r.x0);
        film.color.set(x, y, tile.mean(i));
        film.variance.set(x, y, tile.variance_of_mean(i));
        min_spp = std::min(min_spp, tile.count(i));
        max_spp = std::max(max_spp, tile.count(i));
        any = true;
      }
    }
  }
  film.min_spp = any ? min_spp : 0;
  film.max_spp = max_spp;
  return film;
}

ImageMetadata render_metadata(const Scene& scene, const RenderOptions& options, uint32_t spp,
                              double compute_seconds) {
  std::ostringstream seconds;
  seconds.precision(6);
  seconds << compute_seconds;
  ImageMetadata metadata = {{"penumbra:method", options.method},
                            {"penumbra:sampler", std::string(pattern_name(options.sampler))},
                            {"penumbra:spp", std::to_string(spp)},
                            {"penumbra:seed", std::to_string(options.seed)},
                            {"penumbra:compute_seconds", seconds.str()},
                            {"penumbra:scene", scene.name},
                            {"penumbra:scene_hash", scene.content_hash},
                            {"penumbra:version", kVersion}};
  // What the scene reader ignored or approximated travels with the image.
  if (!scene.warnings.empty()) {
    std::string warnings;
    for (const std::string& warning : scene.warnings) warnings += warning + "\n";
    metadata["penumbra:warnings"] = warnings;
  }
  return metadata;
}

}  // namespace penumbra
