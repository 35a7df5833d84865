#pragma once
// Helpers of the comparison viewer's tests: decoding the page's base64 payloads, images whose
// pixels span many decades, and the decoded error relative to each pixel's brightest channel.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "core/image/image.h"

namespace penumbra::testing {

inline std::string base64_decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string bytes;
  uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    int v = value(c);
    if (v < 0) continue;  // '=' padding
    bits = bits << 6 | uint32_t(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      bytes += char((bits >> count) & 0xff);
    }
  }
  return bytes;
}

// Pixels over 12 decades, in every colour, with a few black ones.
inline Image wide_range_image(int width, int height, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> exponent(-6, 6), unit(0, 1);
  Image image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double scale = std::pow(10.0, exponent(random));
      Rgb value{scale * unit(random), scale * unit(random), scale * unit(random)};
      if ((x + y) % 17 == 0) value = {0, 0, 0};
      image.set(x, y, value);
    }
  return image;
}

// The largest decoded error of any channel over its pixel's brightest channel.
inline double worst_error(const Image& original, const Image& decoded) {
  double worst = 0;
  for (size_t i = 0; i < original.rgb.size(); i += 3) {
    double largest = std::max({original.rgb[i], original.rgb[i + 1], original.rgb[i + 2]});
    for (size_t c = 0; c < 3; ++c) {
      double error = std::abs(double(decoded.rgb[i + c]) - original.rgb[i + c]);
      if (largest == 0) {
        EXPECT_EQ(decoded.rgb[i + c], 0.0f) << "pixel " << i / 3;
        continue;
      }
      worst = std::max(worst, error / largest);
    }
  }
  return worst;
}

}  // namespace penumbra::testing
