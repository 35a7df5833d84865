#pragma once
// Per-pixel accumulation of a tile over a range of passes, and its exact merge.
//
// Sums are kept in 128-bit fixed point (2^-32 units): addition of integers is associative, so
// the sum of a pixel does not depend on how its passes were split into tasks or in which order
// a coordinator merged them. A local render and a farm render of the same job are therefore
// bit-identical, whatever the tiles, pass ranges, worker count or completion order.
// The quantum 2^-32 (2.3e-10) is far below Monte Carlo noise; values are clamped to +-2^60.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/math/vec.h"

namespace penumbra {

using Fixed128 = __int128;

Fixed128 to_fixed(double value);
double from_fixed(Fixed128 value);

struct TileRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0,x1) x [y0,y1), origin top-left
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  int64_t pixel_count() const { return int64_t(width()) * height(); }
  bool operator==(const TileRect&) const = default;
};

class TileAccumulator {
 public:
  TileAccumulator() = default;
  explicit TileAccumulator(const TileRect& rect);

  const TileRect& rect() const { return rect_; }
  // Adds one sample's radiance to the pixel at local index i (row-major within the tile).
  void add_sample(int64_t local_index, const Rgb& radiance);
  // Adds another accumulation of the same rect (any pass range): exact and order-independent.
  void merge(const TileAccumulator& other);

  uint32_t count(int64_t local_index) const { return counts_[local_index]; }
  Rgb mean(int64_t local_index) const;
  // Unbiased estimate of the variance of the mean, per channel (0 when count < 2).
  Rgb variance_of_mean(int64_t local_index) const;
  // Samples that were not finite and were counted as zero (must stay 0; reported as an error).
  uint64_t nonfinite_samples() const { return nonfinite_; }

  // Little-endian binary form for the wire and the coordinator's store.
  std::string serialize() const;
  // Throws std::invalid_argument naming what is wrong when the bytes are not a valid tile.
  static TileAccumulator deserialize(std::string_view bytes);

  bool operator==(const TileAccumulator&) const = default;

 private:
  TileRect rect_;
  std::vector<Fixed128> sums_;     // 3 per pixel
  std::vector<Fixed128> squares_;  // 3 per pixel
  std::vector<uint32_t> counts_;
  uint64_t nonfinite_ = 0;
};

}  // namespace penumbra
