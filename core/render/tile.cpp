#include "core/render/tile.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace penumbra {

namespace {
constexpr double kScale = 4294967296.0;              // 2^32
constexpr double kMaxValue = 1152921504606846976.0;  // 2^60
constexpr uint32_t kMagic = 0x31544e50;              // "PNT1"

template <typename T>
void put(std::string& out, const T& value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}
template <typename T>
T get(std::string_view& in) {
  if (in.size() < sizeof(T)) throw std::invalid_argument("tile bytes truncated");
  T value;
  std::memcpy(&value, in.data(), sizeof(T));
  in.remove_prefix(sizeof(T));
  return value;
}
}  // namespace

Fixed128 to_fixed(double value) {
  value = std::clamp(value, -kMaxValue, kMaxValue);
  // Split into a high and a low part so the product with 2^32 is exact in 128 bits.
  double scaled_high = std::floor(value);
  double fraction = value - scaled_high;  // exact, in [0,1)
  Fixed128 high = static_cast<Fixed128>(static_cast<int64_t>(scaled_high)) << 32;
  Fixed128 low = static_cast<Fixed128>(std::llround(fraction * kScale));
  return high + low;
}

double from_fixed(Fixed128 value) {
  bool negative = value < 0;
  unsigned __int128 magnitude = negative ? -static_cast<unsigned __int128>(value) : value;
  double high =
      static_cast<double>(static_cast<uint64_t>(magnitude >> 64)) * 18446744073709551616.0;
  double low = static_cast<double>(static_cast<uint64_t>(magnitude));
  double result = (high + low) / kScale;
  return negative ? -result : result;
}

TileAccumulator::TileAccumulator(const TileRect& rect)
    : rect_(rect),
      sums_(rect.pixel_count() * 3, 0),
      squares_(rect.pixel_count() * 3, 0),
      counts_(rect.pixel_count(), 0) {}

void TileAccumulator::add_sample(int64_t i, const Rgb& radiance) {
  for (int c = 0; c < 3; ++c) {
    double v = radiance[c];
    if (!std::isfinite(v)) {
      ++nonfinite_;
      v = 0;
    }
    sums_[i * 3 + c] += to_fixed(v);
    squares_[i * 3 + c] += to_fixed(v * v);
  }
  ++counts_[i];
}

void TileAccumulator::merge(const TileAccumulator& other) {
  if (!(other.rect_ == rect_)) throw std::invalid_argument("merging tiles of different rects");
  for (size_t i = 0; i < sums_.size(); ++i) {
    sums_[i] += other.sums_[i];
    squares_[i] += other.squares_[i];
  }
  for (size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  nonfinite_ += other.nonfinite_;
}

Rgb TileAccumulator::mean(int64_t i) const {
  uint32_t n = counts_[i];
  if (n == 0) return {};
  return {from_fixed(sums_[i * 3]) / n, from_fixed(sums_[i * 3 + 1]) / n,
          from_fixed(sums_[i * 3 + 2]) / n};
}

Rgb TileAccumulator::variance_of_mean(int64_t i) const {
  uint32_t n = counts_[i];
  if (n < 2) return {};
  Rgb result;
  for (int c = 0; c < 3; ++c) {
    double mean = from_fixed(sums_[i * 3 + c]) / n;
    double mean_square = from_fixed(squares_[i * 3 + c]) / n;
    double sample_variance = std::max(0.0, (mean_square - mean * mean) * n / (n - 1.0));
    result[c] = sample_variance / n;
  }
  return result;
}

std::string TileAccumulator::serialize() const {
  std::string out;
  out.reserve(32 + sums_.size() * 32 + counts_.size() * 4);
  put(out, kMagic);
  put(out, int32_t(rect_.x0));
  put(out, int32_t(rect_.y0));
  put(out, int32_t(rect_.x1));
  put(out, int32_t(rect_.y1));
  put(out, nonfinite_);
  for (size_t i = 0; i < sums_.size(); ++i) put(out, sums_[i]);
  for (size_t i = 0; i < squares_.size(); ++i) put(out, squares_[i]);
  for (uint32_t c : counts_) put(out, c);
  return out;
}

TileAccumulator TileAccumulator::deserialize(std::string_view in) {
  if (get<uint32_t>(in) != kMagic) throw std::invalid_argument("tile bytes: bad magic number");
  TileRect rect;
  rect.x0 = get<int32_t>(in);
  rect.y0 = get<int32_t>(in);
  rect.x1 = get<int32_t>(in);
  rect.y1 = get<int32_t>(in);
  if (rect.x1 <= rect.x0 || rect.y1 <= rect.y0 || rect.x0 < 0 || rect.y0 < 0 ||
      rect.pixel_count() > (int64_t(1) << 26))
    throw std::invalid_argument("tile bytes: invalid rect");
  uint64_t nonfinite = get<uint64_t>(in);
  size_t expected = size_t(rect.pixel_count()) * (3 * 16 * 2 + 4);
  if (in.size() != expected)
    throw std::invalid_argument("tile bytes: expected " + std::to_string(expected) +
                                " bytes of pixel data, got " + std::to_string(in.size()));
  TileAccumulator tile(rect);
  tile.nonfinite_ = nonfinite;
  for (auto& s : tile.sums_) s = get<Fixed128>(in);
  for (auto& s : tile.squares_) s = get<Fixed128>(in);
  for (auto& c : tile.counts_) c = get<uint32_t>(in);
  // add_sample clamps each value and its square to 2^60, so in 2^-32 fixed point a pixel's sums
  // stay within count * 2^92 (< 2^124): anything beyond came from no sample, and merging it could
  // overflow the 128-bit sums. Squares are never negative.
  for (size_t pixel = 0; pixel < tile.counts_.size(); ++pixel) {
    const unsigned __int128 bound = static_cast<unsigned __int128>(tile.counts_[pixel]) << 92;
    for (int channel = 0; channel < 3; ++channel) {
      Fixed128 sum = tile.sums_[3 * pixel + channel], square = tile.squares_[3 * pixel + channel];
      unsigned __int128 magnitude =
          sum < 0 ? -static_cast<unsigned __int128>(sum) : static_cast<unsigned __int128>(sum);
      if (magnitude > bound || square < 0 || static_cast<unsigned __int128>(square) > bound)
        throw std::invalid_argument("tile bytes: pixel " + std::to_string(pixel) +
                                    " has sums no sample could produce");
    }
  }
  return tile;
}

}  // namespace penumbra
