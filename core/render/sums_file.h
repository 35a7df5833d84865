#pragma once
// A render's exact per-pixel sums in a file of their own ("penumbra/sums@1"), so that a render
// stopped part-way (Ctrl-C) and one of its remaining passes merge into the very image, bit for
// bit, that one uninterrupted render gives. An EXR cannot do that: it holds the mean as 32-bit
// floats, and the mean of two means is not the mean of the sums.
//
// The sums are the 128-bit fixed-point ones of core/render/tile.h, whose addition is exact and
// order-independent, gathered into one accumulator over the whole image (so renders with other
// tile sizes merge too), next to the pass range they hold and the image's metadata.
//
// File layout (little-endian):
//   8 bytes   "PNSUMS01"
//   4 bytes   n, the header's length, at most 1 MiB
//   n bytes   header, a JSON object: {"format": "penumbra/sums@1", "width", "height",
//             "first_pass", "passes", "compute_seconds", "metadata": {string: string}}
//   8 bytes   m, the body's length
//   m bytes   body: zlib stream of TileAccumulator::serialize() of the rect [0, width) x
//             [0, height), whose every pixel has `passes` samples
// Nothing may follow. The body must be within zlib's largest ratio of its inflated size, so a
// small file cannot make the reader allocate much.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/film.h"
#include "core/render/tile.h"

namespace penumbra {

inline constexpr const char* kSumsFormat = "penumbra/sums@1";

struct RenderSums {
  int width = 0, height = 0;
  uint32_t first_pass = 0;  // passes [first_pass, first_pass + passes)
  uint32_t passes = 0;
  double compute_seconds = 0;
  ImageMetadata metadata;  // the EXR's (method, sampler, seed, scene hash, ...)
  TileAccumulator sums;    // rect [0, width) x [0, height)
};

// The sums of a render's tiles (any tiling of the image, exact like TileAccumulator::merge)
// over one accumulator of the image. Throws std::invalid_argument when a tile lies outside it.
TileAccumulator whole_image_sums(int width, int height, std::span<const TileAccumulator> tiles);

std::string encode_sums(const RenderSums& sums);
// Throws std::invalid_argument "<name>: <what is wrong>" when the bytes are not such a file, or
// when a pixel's sample count is not `passes`.
RenderSums decode_sums(const std::string& bytes, const std::string& name);

void write_sums(const std::string& path, const RenderSums& sums);
RenderSums read_sums(const std::string& path);

// The sums of disjoint pass ranges of one render (same size, method, sampler, seed and scene)
// added: the sums of their union, which must be one range [first, first + total) with no gap.
// Compute seconds add up; the metadata is the first part's with penumbra:spp, penumbra:first_pass
// and penumbra:compute_seconds updated and penumbra:interrupted dropped. Throws
// std::invalid_argument naming the file (`names`, in the order of `parts`) and what differs.
RenderSums merge_sums(const std::vector<RenderSums>& parts, const std::vector<std::string>& names);

// The image of the sums: mean and variance of the mean per pixel (as a render's film).
inline Film sums_film(const RenderSums& sums) {
  return assemble_film(sums.width, sums.height, std::span<const TileAccumulator>(&sums.sums, 1));
}

}  // namespace penumbra
