#pragma once
// Assembles tile accumulations into the image of a job: the mean per pixel and the per-pixel
// variance of the mean, and the EXR metadata every render carries.

#include <span>
#include <string>

#include "core/image/image.h"
#include "core/render/renderer.h"
#include "core/render/tile.h"

namespace penumbra {

struct Film {
  Image color;
  Image variance;  // variance of the mean, per channel
  uint64_t nonfinite_samples = 0;
  uint32_t min_spp = 0, max_spp = 0;
};

// Tiles may cover any part of the image; pixels no tile covers stay black with count 0.
Film assemble_film(int width, int height, std::span<const TileAccumulator> tiles);

// Metadata for the EXR: method, sampler, spp, seconds, scene name and hash, seed, version.
ImageMetadata render_metadata(const Scene& scene, const RenderOptions& options, uint32_t spp,
                              double compute_seconds);

}  // namespace penumbra
