// EXR and PNG I/O: bit-exact float round trips (file and memory), metadata and the variance layer
// kept, half precision within half's rounding, clear errors for bad input, the PNG tone curve.

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>

#include "core/image/image.h"
#include "image_test_support.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

using image_test::test_directory;

// Random floats over many magnitudes and both signs, plus special-but-finite values, so a lossy
// path (half conversion, a float->double->float slip) would change some bits.
Image random_image(int width, int height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-30, 30);
  Image image(width, height);
  for (float& v : image.rgb) v = std::ldexp(mantissa(rng), exponent(rng));
  image.rgb[0] = 0.0f;
  image.rgb[1] = -0.0f;
  image.rgb[2] = 1e-40f;  // denormal
  image.rgb[3] = 3.0e38f;
  return image;
}

void expect_bit_identical(const Image& a, const Image& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
}

ImageMetadata sample_metadata() {
  return {{"penumbra:method", "mis(bsdf, line-sa:u)"},
          {"penumbra:sampler", "stratified"},
          {"penumbra:spp", "64"},
          {"penumbra:scene_hash", std::string(64, 'a')},
          {"penumbra:note", "unicode \xc3\xa9 and spaces, commas = fine"}};
}

TEST(ExrFile, FloatRoundTripIsBitExactWithMetadataAndVariance) {
  Image color = random_image(37, 23, 1);
  Image variance = random_image(37, 23, 2);
  for (float& v : variance.rgb) v = std::abs(v);
  ImageMetadata metadata = sample_metadata();
  std::string path = (test_directory() / "roundtrip.exr").string();
  write_exr(path, color, &variance, metadata);

  ImageMetadata read_metadata;
  Image read_variance;
  Image read_color = read_exr(path, &read_metadata, &read_variance);
  expect_bit_identical(color, read_color);
  expect_bit_identical(variance, read_variance);
  EXPECT_EQ(metadata, read_metadata);
}

TEST(ExrFile, ChannelNamesAreRgbAndVarianceLayer) {
  Image color = random_image(4, 3, 3);
  Image variance = random_image(4, 3, 4);
  std::string path = (test_directory() / "channels.exr").string();
  write_exr(path, color, &variance, {});
  auto input = OIIO::ImageInput::open(path);
  ASSERT_TRUE(input);
  std::vector<std::string> names = input->spec().channelnames;
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names,
            (std::vector<std::string>{"B", "G", "R", "variance.B", "variance.G", "variance.R"}));
  EXPECT_EQ(input->spec().format, OIIO::TypeDesc::FLOAT);
}

TEST(ExrFile, BareMetadataKeysGetThePrefix) {
  Image color = random_image(2, 2, 5);
  std::string path = (test_directory() / "prefix.exr").string();
  write_exr(path, color, nullptr, {{"method", "sa"}});
  ImageMetadata metadata;
  read_exr(path, &metadata);
  EXPECT_EQ(metadata, (ImageMetadata{{"penumbra:method", "sa"}}));
}

TEST(ExrFile, WithoutVarianceReadsAnEmptyVariance) {
  Image color = random_image(5, 6, 6);
  std::string path = (test_directory() / "novariance.exr").string();
  write_exr(path, color, nullptr, {});
  Image variance(3, 3);
  Image read = read_exr(path, nullptr, &variance);
  expect_bit_identical(color, read);
  EXPECT_EQ(variance.width, 0);
  EXPECT_EQ(variance.height, 0);
  EXPECT_TRUE(variance.rgb.empty());
}

TEST(ExrFile, HalfKeepsHalfPrecision) {
  Image color(16, 8);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(0.001f, 1000.0f);
  for (float& v : color.rgb) v = value(rng);
  color.rgb[0] = 0.5f;  // exactly representable in half
  std::string float_path = (test_directory() / "float.exr").string();
  std::string half_path = (test_directory() / "half.exr").string();
  write_exr(float_path, color, nullptr, {}, ExrPixelType::Float);
  write_exr(half_path, color, nullptr, {}, ExrPixelType::Half);
  auto input = OIIO::ImageInput::open(half_path);
  ASSERT_TRUE(input);
  EXPECT_EQ(input->spec().format, OIIO::TypeDesc::HALF);
  Image read = read_exr(half_path);
  EXPECT_EQ(read.rgb[0], 0.5f);
  for (size_t i = 0; i < color.rgb.size(); ++i)
    EXPECT_NEAR(read.rgb[i], color.rgb[i], std::abs(color.rgb[i]) * 0x1p-11f) << i;
}

TEST(ExrMemory, EncodeDecodeRoundTripIsBitExact) {
  Image color = random_image(64, 17, 8);
  Image variance = random_image(64, 17, 9);
  ImageMetadata metadata = sample_metadata();
  std::string bytes = encode_exr(color, &variance, metadata);
  ASSERT_GT(bytes.size(), 4u);
  ImageMetadata read_metadata;
  Image read_variance;
  Image read_color = decode_exr(bytes, &read_metadata, &read_variance);
  expect_bit_identical(color, read_color);
  expect_bit_identical(variance, read_variance);
  EXPECT_EQ(metadata, read_metadata);
}

TEST(ExrMemory, FileAndMemoryEncodingsReadTheSame) {
  Image color = random_image(9, 9, 10);
  std::string path = (test_directory() / "same.exr").string();
  write_exr(path, color, nullptr, sample_metadata());
  std::ifstream file(path, std::ios::binary);
  std::string file_bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  ImageMetadata from_file;
  Image decoded = decode_exr(file_bytes, &from_file);
  expect_bit_identical(color, decoded);
  EXPECT_EQ(from_file, sample_metadata());
  ImageMetadata from_memory;
  Image read = read_exr(path, &from_memory);
  expect_bit_identical(decode_exr(encode_exr(color, nullptr, sample_metadata())), read);
}

TEST(ExrMemory, GarbageBytesGiveAClearError) {
  std::mt19937 rng(11);
  std::string garbage(1000, '\0');
  for (char& c : garbage) c = char(rng());
  try {
    decode_exr(garbage);
    FAIL() << "garbage decoded";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("not an OpenEXR image"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(decode_exr(""), std::runtime_error);
}

TEST(ExrMemory, TruncatedAndCorruptedExrThrows) {
  Image color = random_image(32, 32, 12);
  std::string bytes = encode_exr(color, nullptr, {});
  // Keep the magic number and part of the header; then keep the header, lose most pixels.
  for (size_t kept : {size_t(40), bytes.size() / 3}) {
    try {
      decode_exr(bytes.substr(0, kept));
      ADD_FAILURE() << "decoded a truncated EXR of " << kept << " bytes";
    } catch (const std::runtime_error& error) {
      std::string message = error.what();
      EXPECT_NE(message.find("EXR bytes (" + std::to_string(kept) + " bytes)"), std::string::npos)
          << message;
      std::cout << "truncated to " << kept << ": " << message << "\n";
    }
  }
}

TEST(ExrMemory, HugeDimensionsInTheHeaderAreRefused) {
  std::string bytes = encode_exr(random_image(4, 4, 18), nullptr, {});
  // The header's window attributes: name, type "box2i", size 16, then xMin yMin xMax yMax
  // (int32, little endian). Widen both windows, first past our limit of 16384 pixels per side
  // (a valid header: OpenEXR accepts it, our check must refuse it), then to 2^30 (OpenEXR's own
  // checks refuse it).
  for (int32_t width : {20000, 1 << 30}) {
    std::string widened = bytes;
    for (const char* name : {"dataWindow", "displayWindow"}) {
      std::string key = std::string(name) + std::string("\0box2i\0", 7);
      size_t attribute = widened.find(key);
      ASSERT_NE(attribute, std::string::npos) << name;
      int32_t x_max = width - 1;
      std::memcpy(&widened[attribute + key.size() + 4 + 8], &x_max, 4);
    }
    try {
      decode_exr(widened);
      ADD_FAILURE() << "decoded a " << width << " pixel wide image";
    } catch (const std::runtime_error& error) {
      std::string message = error.what();
      EXPECT_NE(message.find("EXR bytes"), std::string::npos) << message;
      if (width == 20000) {
        EXPECT_NE(message.find("exceeds the limits"), std::string::npos) << message;
      }
    }
  }
}

TEST(ExrFile, ErrorsNameThePath) {
  std::string missing = (test_directory() / "does-not-exist.exr").string();
  try {
    read_exr(missing);
    FAIL() << "read a missing file";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos) << error.what();
  }
  std::string unwritable = (test_directory() / "no-such-dir" / "x.exr").string();
  try {
    write_exr(unwritable, random_image(2, 2, 13), nullptr, {});
    FAIL() << "wrote into a missing directory";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(unwritable), std::string::npos) << error.what();
  }
}

// An EXR's bytes with the value of its capDate attribute blanked: OpenImageIO stamps every file
// with the time it was written (to the second), so two encodings a second apart differ there.
std::string without_capture_date(std::string bytes) {
  static const std::string kName("capDate\0string\0", 15);
  size_t at = bytes.find(kName);
  if (at == std::string::npos || at + kName.size() + 4 > bytes.size()) return bytes;
  size_t length_at = at + kName.size();
  uint32_t length = 0;
  for (int i = 3; i >= 0; --i) length = length * 256 + uint8_t(bytes[length_at + size_t(i)]);
  size_t value_at = length_at + 4;
  for (size_t i = value_at; i < std::min(bytes.size(), value_at + length); ++i) bytes[i] = '0';
  return bytes;
}

TEST(ExrFile, OverwritesAndLeavesNoTemporaryFiles) {
  fs::path directory = test_directory() / "overwrite";
  fs::create_directories(directory);
  std::string path = (directory / "image.exr").string();
  Image first = random_image(8, 8, 16), second = random_image(5, 3, 17);
  write_exr(path, first, nullptr, {{"penumbra:pass", "1"}});
  write_exr(path, second, nullptr, {{"penumbra:pass", "2"}});
  ImageMetadata metadata;
  expect_bit_identical(read_exr(path, &metadata), second);
  EXPECT_EQ(metadata.at("penumbra:pass"), "2");
  // The bytes on disk are exactly encode_exr's.
  std::ifstream file(path, std::ios::binary);
  std::string on_disk((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(without_capture_date(on_disk),
            without_capture_date(encode_exr(second, nullptr, {{"penumbra:pass", "2"}})));
  size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(directory)) {
    ++entries;
    EXPECT_EQ(entry.path().filename(), "image.exr");
  }
  EXPECT_EQ(entries, 1u);
}

TEST(ExrFile, MismatchedVarianceIsRefused) {
  Image color = random_image(4, 4, 14);
  Image variance = random_image(4, 5, 15);
  EXPECT_THROW(encode_exr(color, &variance, {}), std::runtime_error);
  Image broken(4, 4);
  broken.rgb.pop_back();
  EXPECT_THROW(encode_exr(broken, nullptr, {}), std::runtime_error);
  EXPECT_THROW(encode_exr(Image(), nullptr, {}), std::runtime_error);
}

// The sRGB curve of IEC 61966-2-1, quantized to 8 bits, for the expected PNG values.
int srgb_byte(double linear) {
  double c = std::clamp(linear, 0.0, 1.0);
  double encoded = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
  return int(std::lround(encoded * 255));
}

TEST(PngPreview, AppliesExposureClampAndSrgbCurve) {
  Image color(4, 2);
  color.set(0, 0, {0.0, 0.25, 0.5});
  color.set(1, 0, {2.0, -1.0, 0.001});
  color.set(2, 0, {std::nan(""), INFINITY, 0.18});
  color.set(3, 0, {1.0, 0.75, 0.04});
  color.set(0, 1, {0.1, 0.2, 0.3});
  std::string path = (test_directory() / "preview.png").string();
  double exposure = 2.0;
  write_png_preview(path, color, exposure);

  auto input = OIIO::ImageInput::open(path);
  ASSERT_TRUE(input);
  const OIIO::ImageSpec& spec = input->spec();
  ASSERT_EQ(spec.width, 4);
  ASSERT_EQ(spec.height, 2);
  ASSERT_EQ(spec.nchannels, 3);
  std::vector<uint8_t> pixels(4 * 2 * 3);
  ASSERT_TRUE(input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      Rgb c = color.at(x, y);
      for (int k = 0; k < 3; ++k) {
        double linear = std::isfinite(c[k] * exposure) ? c[k] * exposure : 0.0;
        EXPECT_EQ(int(pixels[(y * 4 + x) * 3 + k]), srgb_byte(linear))
            << x << "," << y << " channel " << k;
      }
    }
  // Spot checks of the curve itself: 0.5 linear (0.25 at exposure 2) is 188, 1 is 255.
  EXPECT_EQ(int(pixels[1]), 188);
  EXPECT_EQ(int(pixels[2]), 255);
}

// The file preview and the in-memory one (the coordinator's HTTP previews) are the same bytes.
TEST(PngPreview, FileAndMemoryEncodingsAreTheSameBytes) {
  Image color(5, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) color.set(x, y, {0.1 * x, 0.3 * y, 0.05 * (x + y)});
  std::string path = (test_directory() / "same.png").string();
  write_png_preview(path, color, 1.5);
  std::ifstream in(path, std::ios::binary);
  std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string memory = encode_png_preview(color, 1.5);
  EXPECT_EQ(memory.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(file, memory);
  EXPECT_THROW(encode_png_preview(color, -1), std::runtime_error);
}

}  // namespace
}  // namespace penumbra
