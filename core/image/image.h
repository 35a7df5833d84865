#pragma once
// Images (float RGB, row-major, origin top-left), EXR and PNG I/O through OpenImageIO.

#include <map>
#include <string>
#include <vector>

#include "core/math/vec.h"

namespace penumbra {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgb;  // 3 floats per pixel

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(size_t(w) * h * 3, 0.0f) {}
  Rgb at(int x, int y) const {
    size_t i = (size_t(y) * width + x) * 3;
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
  void set(int x, int y, const Rgb& c) {
    size_t i = (size_t(y) * width + x) * 3;
    rgb[i] = float(c.x);
    rgb[i + 1] = float(c.y);
    rgb[i + 2] = float(c.z);
  }
};

// Metadata stored as EXR string attributes ("penumbra:method", ...).
using ImageMetadata = std::map<std::string, std::string>;

// Channel type of a written EXR: float round-trips bit-exactly; half is half the size.
enum class ExrPixelType { Float, Half };

// A further layer of an EXR with one channel: one float per pixel, row-major (e.g. an exact
// reference's "exact.mask", core/exact/exact_reference.h).
struct ExrChannel {
  std::string name;
  std::vector<float> values;
};

// Writes an EXR with channels R,G,B and, when `variance` is given, variance.R/G/B (per-pixel
// variance of the mean), then the `extra` channels. Metadata keys are written as string attributes
// named with the "penumbra:" prefix (added when a key lacks it). Throws std::runtime_error naming
// the path and what failed.
void write_exr(const std::string& path, const Image& color, const Image* variance,
               const ImageMetadata& metadata, ExrPixelType pixel_type = ExrPixelType::Float);
void write_exr(const std::string& path, const Image& color, const Image* variance,
               const ImageMetadata& metadata, const std::vector<ExrChannel>& extra,
               ExrPixelType pixel_type = ExrPixelType::Float);
// The same EXR as bytes (for the farm's result stream), encoded in memory (no temporary file).
// write_exr writes exactly these bytes, atomically (a temporary file beside `path`, renamed).
std::string encode_exr(const Image& color, const Image* variance, const ImageMetadata& metadata,
                       ExrPixelType pixel_type = ExrPixelType::Float);
std::string encode_exr(const Image& color, const Image* variance, const ImageMetadata& metadata,
                       const std::vector<ExrChannel>& extra,
                       ExrPixelType pixel_type = ExrPixelType::Float);
// Reads R,G,B (and metadata when asked: every "penumbra:" string attribute, keys with the
// prefix). `variance`, when given, receives variance.R/G/B, or an empty (0x0) image when the file
// has none. Throws std::runtime_error naming the path and what failed.
Image read_exr(const std::string& path, ImageMetadata* metadata = nullptr,
               Image* variance = nullptr);
Image decode_exr(const std::string& bytes, ImageMetadata* metadata = nullptr,
                 Image* variance = nullptr);
// One single channel of an EXR by name (one float per pixel), empty when the file has none.
std::vector<float> read_exr_channel(const std::string& path, const std::string& name);
std::vector<float> decode_exr_channel(const std::string& bytes, const std::string& name);
// Tone-mapped 8-bit sRGB preview (exposure scale, then clamp and the sRGB curve; non-finite
// pixels black) as PNG bytes: the one preview encoder of the CLI and the coordinator's HTTP side.
std::string encode_png_preview(const Image& color, double exposure = 1.0);
// The same bytes written atomically to `path`.
void write_png_preview(const std::string& path, const Image& color, double exposure = 1.0);

}  // namespace penumbra
