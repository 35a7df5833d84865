// EXR and PNG I/O through OpenImageIO 2.4, in the module of core/image/oiio_services.h.
//
// Precision: pixels are float in memory. EXR channels are written as float (bit-exact round
// trip) or half (half the bytes, ~3 decimal digits) as the caller asks; every channel of one file
// has the same type. Encoding and decoding happen in memory; write_exr encodes in memory too, then
// writes the file atomically (temporary file + rename).

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/image/image.h"
#include "core/image/oiio_services.h"

namespace penumbra {

namespace {

constexpr std::string_view kMetadataPrefix = "penumbra:";
// Largest image read: the scene format's resolution limit per side, and far more channels than
// the six we write.
constexpr int kMaxImageSide = 16384;
constexpr int kMaxChannels = 64;
constexpr const char* kColorChannels[3] = {"R", "G", "B"};
constexpr const char* kVarianceChannels[3] = {"variance.R", "variance.G", "variance.B"};

// The attribute name of one metadata key: keys already carry the prefix ("penumbra:method", as
// render_metadata writes them); a bare key ("method") gets it.
std::string metadata_attribute_name(const std::string& key) {
  if (key.compare(0, kMetadataPrefix.size(), kMetadataPrefix) == 0) return key;
  return std::string(kMetadataPrefix) + key;
}

void check_image_shape(const Image& image, const std::string& what, const std::string& where) {
  if (image.width <= 0 || image.height <= 0)
    throw std::runtime_error(where + ": " + what + " image is empty (" +
                             std::to_string(image.width) + "x" + std::to_string(image.height) +
                             ")");
  if (image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
    throw std::runtime_error(where + ": " + what + " image holds " +
                             std::to_string(image.rgb.size()) + " floats, expected " +
                             std::to_string(size_t(image.width) * image.height * 3));
}

// The interleaved float pixels of an EXR with R,G,B and optionally variance.R/G/B, and its
// metadata as string attributes.
oiio::Pixels exr_contents(const Image& color, const Image* variance, const ImageMetadata& metadata,
                          const std::vector<ExrChannel>& extra, const std::string& where) {
  // Check the images.
  check_image_shape(color, "color", where);
  if (variance) {
    check_image_shape(*variance, "variance", where);
    if (variance->width != color.width || variance->height != color.height)
      throw std::runtime_error(where + ": variance image is " + std::to_string(variance->width) +
                               "x" + std::to_string(variance->height) + " but color is " +
                               std::to_string(color.width) + "x" + std::to_string(color.height));
  }

  const size_t pixel_count = size_t(color.width) * size_t(color.height);
  for (const ExrChannel& channel : extra) {
    if (channel.values.size() != pixel_count)
      throw std::runtime_error(where + ": channel " + channel.name + " holds " +
                               std::to_string(channel.values.size()) + " values, expected " +
                               std::to_string(pixel_count));
    if (channel.name.empty() || channel.name == "R" || channel.name == "G" || channel.name == "B" ||
        channel.name.rfind("variance.", 0) == 0)
      throw std::runtime_error(where + ": channel name '" + channel.name + "' is taken");
  }

  // Describe the channels and the metadata.
  const int base_channels = variance ? 6 : 3;
  const int channel_count = base_channels + int(extra.size());
  oiio::Pixels contents;
  contents.width = color.width;
  contents.height = color.height;
  contents.channels = channel_count;
  for (const char* name : kColorChannels) contents.channel_names.emplace_back(name);
  if (variance)
    for (const char* name : kVarianceChannels) contents.channel_names.emplace_back(name);
  for (const ExrChannel& channel : extra) contents.channel_names.push_back(channel.name);
  for (const auto& [key, value] : metadata)
    contents.strings.emplace_back(metadata_attribute_name(key), value);

  // Interleave the pixels.
  contents.data.resize(pixel_count * channel_count);
  for (size_t p = 0; p < pixel_count; ++p) {
    float* out = &contents.data[p * channel_count];
    for (int c = 0; c < 3; ++c) out[c] = color.rgb[p * 3 + c];
    if (variance)
      for (int c = 0; c < 3; ++c) out[3 + c] = variance->rgb[p * 3 + c];
    for (size_t k = 0; k < extra.size(); ++k) out[base_channels + int(k)] = extra[k].values[p];
  }
  return contents;
}

int find_channel(const oiio::Pixels& image, std::string_view name) {
  for (size_t i = 0; i < image.channel_names.size(); ++i)
    if (image.channel_names[i] == name) return int(i);
  return -1;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ",") + name;
  return out;
}

// R,G,B by name (any channel order), variance.R/G/B when asked and present, and every
// "penumbra:" string attribute of a read EXR.
Image image_of(const oiio::Pixels& pixels, const std::string& where, ImageMetadata* metadata,
               Image* variance) {
  // Find the channels.
  int color_index[3], variance_index[3];
  for (int c = 0; c < 3; ++c) {
    color_index[c] = find_channel(pixels, kColorChannels[c]);
    if (color_index[c] < 0)
      throw std::runtime_error(where + ": no channel " + kColorChannels[c] +
                               " (channels: " + joined(pixels.channel_names) + ")");
    variance_index[c] = find_channel(pixels, kVarianceChannels[c]);
  }
  bool has_variance = variance_index[0] >= 0 && variance_index[1] >= 0 && variance_index[2] >= 0;

  // De-interleave.
  size_t pixel_count = size_t(pixels.width) * size_t(pixels.height);
  size_t channel_count = size_t(pixels.channels);
  Image color(pixels.width, pixels.height);
  for (size_t p = 0; p < pixel_count; ++p)
    for (int c = 0; c < 3; ++c)
      color.rgb[p * 3 + c] = pixels.data[p * channel_count + color_index[c]];
  if (variance) {
    *variance = Image();
    if (has_variance) {
      *variance = Image(pixels.width, pixels.height);
      for (size_t p = 0; p < pixel_count; ++p)
        for (int c = 0; c < 3; ++c)
          variance->rgb[p * 3 + c] = pixels.data[p * channel_count + variance_index[c]];
    }
  }

  // Collect the metadata.
  if (metadata) {
    metadata->clear();
    for (const auto& [name, value] : pixels.strings)
      if (name.compare(0, kMetadataPrefix.size(), kMetadataPrefix) == 0) (*metadata)[name] = value;
  }
  return color;
}

// Runs an operation of the image module, naming `where` in its errors.
template <typename F>
auto in_module(const std::string& where, F&& operation) {
  try {
    return operation(oiio::services());
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(where + ": " + error.what());
  }
}

// sRGB transfer curve (IEC 61966-2-1) of a linear value in [0,1].
double srgb_encode(double linear) {
  if (linear <= 0.0031308) return 12.92 * linear;
  return 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

}  // namespace

namespace {

// Encodes to memory; `where` names the destination in errors.
std::string encode_exr_for(const std::string& where, const Image& color, const Image* variance,
                           const ImageMetadata& metadata, const std::vector<ExrChannel>& extra,
                           ExrPixelType pixel_type) {
  oiio::Pixels contents = exr_contents(color, variance, metadata, extra, where);
  return in_module(where, [&](const oiio::Services& services) {
    return services.encode_exr(contents, pixel_type == ExrPixelType::Half);
  });
}

// Writes the bytes to a temporary file beside `path`, then renames it over `path`: a reader (or a
// coordinator restarted after a crash) sees the old file or the complete new one, never a part.
void write_file_atomically(const std::string& path, const std::string& bytes,
                           const std::string& where) {
  static std::atomic<uint64_t> counter{0};
  std::string temporary =
      path + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file)
      throw std::runtime_error(where + ": cannot open for writing: " + std::strerror(errno));
    file.write(bytes.data(), std::streamsize(bytes.size()));
    file.close();
    if (!file) {
      std::remove(temporary.c_str());
      throw std::runtime_error(where + ": cannot write " + std::to_string(bytes.size()) + " bytes");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    throw std::runtime_error(where +
                             ": cannot move the finished file into place: " + error.message());
  }
}

}  // namespace

void write_exr(const std::string& path, const Image& color, const Image* variance,
               const ImageMetadata& metadata, ExrPixelType pixel_type) {
  write_exr(path, color, variance, metadata, {}, pixel_type);
}

void write_exr(const std::string& path, const Image& color, const Image* variance,
               const ImageMetadata& metadata, const std::vector<ExrChannel>& extra,
               ExrPixelType pixel_type) {
  std::string where = "EXR '" + path + "'";
  write_file_atomically(path, encode_exr_for(where, color, variance, metadata, extra, pixel_type),
                        where);
}

std::string encode_exr(const Image& color, const Image* variance, const ImageMetadata& metadata,
                       ExrPixelType pixel_type) {
  return encode_exr_for("EXR encoding", color, variance, metadata, {}, pixel_type);
}

std::string encode_exr(const Image& color, const Image* variance, const ImageMetadata& metadata,
                       const std::vector<ExrChannel>& extra, ExrPixelType pixel_type) {
  return encode_exr_for("EXR encoding", color, variance, metadata, extra, pixel_type);
}

Image read_exr(const std::string& path, ImageMetadata* metadata, Image* variance) {
  std::string where = "EXR '" + path + "'";
  oiio::Pixels pixels = in_module(where, [&](const oiio::Services& services) {
    return services.read_exr(path, /*from_memory=*/false, kMaxImageSide, kMaxChannels);
  });
  return image_of(pixels, where, metadata, variance);
}

Image decode_exr(const std::string& bytes, ImageMetadata* metadata, Image* variance) {
  std::string where = "EXR bytes (" + std::to_string(bytes.size()) + " bytes)";
  // OpenEXR files start with the magic number 76 2f 31 01; refuse anything else up front so the
  // error says what is wrong instead of a decoder's message about a missing header field.
  static constexpr unsigned char kExrMagic[4] = {0x76, 0x2f, 0x31, 0x01};
  if (bytes.size() < 4 ||
      !std::equal(kExrMagic, kExrMagic + 4, reinterpret_cast<const unsigned char*>(bytes.data())))
    throw std::runtime_error(where + ": not an OpenEXR image (bad magic number)");

  oiio::Pixels pixels = in_module(where, [&](const oiio::Services& services) {
    return services.read_exr(bytes, /*from_memory=*/true, kMaxImageSide, kMaxChannels);
  });
  return image_of(pixels, where, metadata, variance);
}

namespace {

std::string encode_png_for(const std::string& where, const Image& color, double exposure) {
  check_image_shape(color, "color", where);
  if (!std::isfinite(exposure) || exposure < 0)
    throw std::runtime_error(where + ": exposure must be finite and >= 0, got " +
                             std::to_string(exposure));

  // Expose, clamp, apply the sRGB curve and quantize (non-finite pixels become black).
  std::vector<uint8_t> pixels(color.rgb.size());
  for (size_t i = 0; i < color.rgb.size(); ++i) {
    double value = double(color.rgb[i]) * exposure;
    if (!std::isfinite(value)) value = 0;
    double encoded = srgb_encode(std::clamp(value, 0.0, 1.0));
    pixels[i] = uint8_t(std::lround(encoded * 255.0));
  }

  return in_module(where, [&](const oiio::Services& services) {
    return services.encode_png(pixels.data(), color.width, color.height);
  });
}

}  // namespace

std::string encode_png_preview(const Image& color, double exposure) {
  return encode_png_for("PNG encoding", color, exposure);
}

void write_png_preview(const std::string& path, const Image& color, double exposure) {
  std::string where = "PNG '" + path + "'";
  write_file_atomically(path, encode_png_for(where, color, exposure), where);
}

namespace {

std::vector<float> channel_of(const oiio::Pixels& pixels, const std::string& name) {
  const int index = find_channel(pixels, name);
  if (index < 0) return {};
  const size_t pixel_count = size_t(pixels.width) * size_t(pixels.height);
  std::vector<float> values(pixel_count);
  for (size_t p = 0; p < pixel_count; ++p)
    values[p] = pixels.data[p * size_t(pixels.channels) + size_t(index)];
  return values;
}

}  // namespace

std::vector<float> read_exr_channel(const std::string& path, const std::string& name) {
  std::string where = "EXR '" + path + "'";
  oiio::Pixels pixels = in_module(where, [&](const oiio::Services& services) {
    return services.read_exr(path, /*from_memory=*/false, kMaxImageSide, kMaxChannels);
  });
  return channel_of(pixels, name);
}

std::vector<float> decode_exr_channel(const std::string& bytes, const std::string& name) {
  std::string where = "EXR bytes (" + std::to_string(bytes.size()) + " bytes)";
  oiio::Pixels pixels = in_module(where, [&](const oiio::Services& services) {
    return services.read_exr(bytes, /*from_memory=*/true, kMaxImageSide, kMaxChannels);
  });
  return channel_of(pixels, name);
}

}  // namespace penumbra
