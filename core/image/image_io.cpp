// EXR and PNG I/O through OpenImageIO 2.4.
//
// Precision: pixels are float in memory. EXR channels are written as float (bit-exact round
// trip) or half (half the bytes, ~3 decimal digits) as the caller asks; every channel of one file
// has the same type. In-memory encoding uses OIIO's IOVecOutput / IOMemReader proxies: the
// OpenEXR plugin of OIIO 2.4 supports them, so encode/decode never touch the disk. write_exr
// encodes in memory too, then writes the file atomically (temporary file + rename).

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
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

namespace penumbra {

namespace {

namespace oiio = OIIO;

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

// The spec and the interleaved float pixels of an EXR with R,G,B and optionally variance.R/G/B.
struct ExrContents {
  oiio::ImageSpec spec;
  std::vector<float> pixels;
};

ExrContents exr_contents(const Image& color, const Image* variance, const ImageMetadata& metadata,
                         ExrPixelType pixel_type, const std::string& where) {
  // Check the images.
  check_image_shape(color, "color", where);
  if (variance) {
    check_image_shape(*variance, "variance", where);
    if (variance->width != color.width || variance->height != color.height)
      throw std::runtime_error(where + ": variance image is " + std::to_string(variance->width) +
                               "x" + std::to_string(variance->height) + " but color is " +
                               std::to_string(color.width) + "x" + std::to_string(color.height));
  }

  // Describe the channels and the metadata.
  int channel_count = variance ? 6 : 3;
  oiio::TypeDesc format =
      pixel_type == ExrPixelType::Half ? oiio::TypeDesc::HALF : oiio::TypeDesc::FLOAT;
  ExrContents contents;
  contents.spec = oiio::ImageSpec(color.width, color.height, channel_count, format);
  contents.spec.channelnames.clear();
  for (const char* name : kColorChannels) contents.spec.channelnames.emplace_back(name);
  if (variance)
    for (const char* name : kVarianceChannels) contents.spec.channelnames.emplace_back(name);
  contents.spec.alpha_channel = -1;
  contents.spec.attribute("compression", "zip");
  for (const auto& [key, value] : metadata)
    contents.spec.attribute(metadata_attribute_name(key), value);

  // Interleave the pixels.
  size_t pixel_count = size_t(color.width) * size_t(color.height);
  contents.pixels.resize(pixel_count * channel_count);
  for (size_t p = 0; p < pixel_count; ++p) {
    float* out = &contents.pixels[p * channel_count];
    for (int c = 0; c < 3; ++c) out[c] = color.rgb[p * 3 + c];
    if (variance)
      for (int c = 0; c < 3; ++c) out[3 + c] = variance->rgb[p * 3 + c];
  }
  return contents;
}

void write_contents(oiio::ImageOutput& output, const std::string& name, const ExrContents& contents,
                    const std::string& where) {
  if (!output.open(name, contents.spec))
    throw std::runtime_error(where + ": cannot open for writing: " + output.geterror());
  if (!output.write_image(oiio::TypeDesc::FLOAT, contents.pixels.data())) {
    std::string error = output.geterror();
    output.close();
    throw std::runtime_error(where + ": cannot write pixels: " + error);
  }
  if (!output.close())
    throw std::runtime_error(where + ": cannot finish the file: " + output.geterror());
}

int find_channel(const oiio::ImageSpec& spec, std::string_view name) {
  for (size_t i = 0; i < spec.channelnames.size(); ++i)
    if (spec.channelnames[i] == name) return int(i);
  return -1;
}

// Reads an opened EXR: R,G,B by name (any channel order), variance.R/G/B when asked and present,
// and every "penumbra:" string attribute.
Image read_contents(oiio::ImageInput& input, const std::string& where, ImageMetadata* metadata,
                    Image* variance) {
  const oiio::ImageSpec& spec = input.spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1)
    throw std::runtime_error(where + ": unsupported image size " + std::to_string(spec.width) +
                             "x" + std::to_string(spec.height) + "x" + std::to_string(spec.depth));
  // A corrupt or hostile header must not make us allocate terabytes.
  if (spec.width > kMaxImageSide || spec.height > kMaxImageSide || spec.nchannels > kMaxChannels)
    throw std::runtime_error(where + ": image of " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height) + " pixels and " +
                             std::to_string(spec.nchannels) + " channels exceeds the limits (" +
                             std::to_string(kMaxImageSide) + " per side, " +
                             std::to_string(kMaxChannels) + " channels)");

  // Find the channels.
  int color_index[3], variance_index[3];
  for (int c = 0; c < 3; ++c) {
    color_index[c] = find_channel(spec, kColorChannels[c]);
    if (color_index[c] < 0)
      throw std::runtime_error(where + ": no channel " + kColorChannels[c] +
                               " (channels: " + oiio::Strutil::join(spec.channelnames, ",") + ")");
    variance_index[c] = find_channel(spec, kVarianceChannels[c]);
  }
  bool has_variance = variance_index[0] >= 0 && variance_index[1] >= 0 && variance_index[2] >= 0;

  // Read every channel as float.
  size_t pixel_count = size_t(spec.width) * size_t(spec.height);
  size_t channel_count = size_t(spec.nchannels);
  std::vector<float> pixels(pixel_count * channel_count);
  if (!input.read_image(0, 0, 0, spec.nchannels, oiio::TypeDesc::FLOAT, pixels.data()))
    throw std::runtime_error(where + ": cannot read pixels: " + input.geterror());

  // De-interleave.
  Image color(spec.width, spec.height);
  for (size_t p = 0; p < pixel_count; ++p)
    for (int c = 0; c < 3; ++c) color.rgb[p * 3 + c] = pixels[p * channel_count + color_index[c]];
  if (variance) {
    *variance = Image();
    if (has_variance) {
      *variance = Image(spec.width, spec.height);
      for (size_t p = 0; p < pixel_count; ++p)
        for (int c = 0; c < 3; ++c)
          variance->rgb[p * 3 + c] = pixels[p * channel_count + variance_index[c]];
    }
  }

  // Collect the metadata.
  if (metadata) {
    metadata->clear();
    for (const oiio::ParamValue& attribute : spec.extra_attribs) {
      std::string name = attribute.name().string();
      if (name.compare(0, kMetadataPrefix.size(), kMetadataPrefix) != 0) continue;
      if (attribute.type() != oiio::TypeDesc::STRING) continue;
      (*metadata)[name] = attribute.get_string();
    }
  }
  return color;
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
                           const ImageMetadata& metadata, ExrPixelType pixel_type) {
  ExrContents contents = exr_contents(color, variance, metadata, pixel_type, where);
  std::vector<unsigned char> bytes;
  oiio::Filesystem::IOVecOutput proxy(bytes);
  auto output = oiio::ImageOutput::create("openexr", &proxy);
  if (!output) throw std::runtime_error(where + ": no OpenEXR writer: " + oiio::geterror());
  if (!output->supports("ioproxy"))
    throw std::runtime_error(where + ": this OpenImageIO's OpenEXR writer cannot write to memory");
  write_contents(*output, "memory.exr", contents, where);
  return std::string(bytes.begin(), bytes.end());
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
  std::string where = "EXR '" + path + "'";
  write_file_atomically(path, encode_exr_for(where, color, variance, metadata, pixel_type), where);
}

std::string encode_exr(const Image& color, const Image* variance, const ImageMetadata& metadata,
                       ExrPixelType pixel_type) {
  return encode_exr_for("EXR encoding", color, variance, metadata, pixel_type);
}

Image read_exr(const std::string& path, ImageMetadata* metadata, Image* variance) {
  std::string where = "EXR '" + path + "'";
  auto input = oiio::ImageInput::create("openexr");
  if (!input) throw std::runtime_error(where + ": no OpenEXR reader: " + oiio::geterror());
  oiio::ImageSpec spec;
  if (!input->open(path, spec)) {
    std::string error = input->geterror();
    throw std::runtime_error(where + ": cannot open: " +
                             (error.empty() ? std::string("not a readable EXR file") : error));
  }
  Image color = read_contents(*input, where, metadata, variance);
  input->close();
  return color;
}

Image decode_exr(const std::string& bytes, ImageMetadata* metadata, Image* variance) {
  std::string where = "EXR bytes (" + std::to_string(bytes.size()) + " bytes)";
  // OpenEXR files start with the magic number 76 2f 31 01; refuse anything else up front so the
  // error says what is wrong instead of a decoder's message about a missing header field.
  static constexpr unsigned char kExrMagic[4] = {0x76, 0x2f, 0x31, 0x01};
  if (bytes.size() < 4 ||
      !std::equal(kExrMagic, kExrMagic + 4, reinterpret_cast<const unsigned char*>(bytes.data())))
    throw std::runtime_error(where + ": not an OpenEXR image (bad magic number)");

  oiio::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  auto input = oiio::ImageInput::create("openexr");
  if (!input) throw std::runtime_error(where + ": no OpenEXR reader: " + oiio::geterror());
  if (!input->supports("ioproxy") || !input->set_ioproxy(&proxy))
    throw std::runtime_error(where + ": this OpenImageIO's OpenEXR reader cannot read memory");
  oiio::ImageSpec spec;
  if (!input->open("memory.exr", spec)) {
    std::string error = input->geterror();
    throw std::runtime_error(where + ": cannot decode: " +
                             (error.empty() ? std::string("corrupt OpenEXR data") : error));
  }
  Image color = read_contents(*input, where, metadata, variance);
  input->close();
  return color;
}

void write_png_preview(const std::string& path, const Image& color, double exposure) {
  std::string where = "PNG '" + path + "'";
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

  oiio::ImageSpec spec(color.width, color.height, 3, oiio::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  auto output = oiio::ImageOutput::create("png");
  if (!output) throw std::runtime_error(where + ": no PNG writer: " + oiio::geterror());
  if (!output->open(path, spec))
    throw std::runtime_error(where + ": cannot open for writing: " + output->geterror());
  if (!output->write_image(oiio::TypeDesc::UINT8, pixels.data())) {
    std::string error = output->geterror();
    output->close();
    throw std::runtime_error(where + ": cannot write pixels: " + error);
  }
  if (!output->close())
    throw std::runtime_error(where + ": cannot finish the file: " + output->geterror());
}

}  // namespace penumbra
