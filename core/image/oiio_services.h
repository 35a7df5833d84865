#pragma once
// OpenImageIO behind a module loaded on first use.
//
// Debian's OpenImageIO links about 260 shared libraries (OpenCV, FFmpeg, GDAL, GStreamer, ...);
// loading them costs every process about 0.8 s of CPU before main() (measured with `perf stat`
// on a program that only links it), whatever the process does. So no Penumbra program links
// OpenImageIO: the code that calls it lives in the module libpenumbra_oiio.so (core/oiio/), and
// services() opens that module the first time an image is read or written, a texture looked up
// or a figure drawn. `penumbra --help`, a refused scene, a worker rendering an untextured scene or
// a unit test that touches no image never load it.
//
// The interface carries plain data (pixels as floats, string attributes) so that the module
// shares no code with the rest of core. Every operation throws std::runtime_error with what went
// wrong (without naming the file: the caller knows what it is working on).

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace penumbra::oiio {

// An image as OpenImageIO hands it over: interleaved float channels, row-major from the top.
struct Pixels {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<std::string> channel_names;
  std::vector<float> data;  // width * height * channels
  // String attributes of the file (EXR header), in the file's order.
  std::vector<std::pair<std::string, std::string>> strings;
};

enum class Wrap { Periodic, Black, Clamp };

// One filtered lookup: texture coordinates in OpenImageIO's convention (t = 0 the top row) and
// their screen-space derivatives.
struct TextureLookup {
  float s = 0, t = 0, dsdx = 0, dtdx = 0, dsdy = 0, dtdy = 0;
  Wrap wrap = Wrap::Periodic;
  bool trilinear = false;  // else anisotropic
  int max_anisotropy = 8;
  int channels = 3;
};

// A texture system of its own (not OpenImageIO's shared one) over MIP-mapped files.
class TextureSystem {
 public:
  virtual ~TextureSystem() = default;
  // A handle for a MIP-mapped file written by Services::write_mip_map; throws when the file
  // cannot be opened.
  virtual const void* handle(const std::string& file) = 0;
  // Filtered value of `lookup.channels` channels into `out`; false when the lookup failed.
  virtual bool texture(const void* handle, const TextureLookup& lookup, float* out) const = 0;
};

// A drawing surface of 3 float channels (display values in [0, 1]), for figures.
class Canvas {
 public:
  virtual ~Canvas() = default;
  // `rgb` holds width * height * 3 floats.
  virtual void paste(const float* rgb, int width, int height, int x, int y) = 0;
  // The box [x0, x1] x [y0, y1], filled or as a one-pixel outline.
  virtual void box(int x0, int y0, int x1, int y1, const float* color, bool filled) = 0;
  // Width in pixels of `text` in the font file at `size`, 0 when it cannot be measured.
  virtual int text_width(const std::string& text, int size, const std::string& font) const = 0;
  virtual void text(int x, int baseline, const std::string& text, int size, const std::string& font,
                    const float* color) = 0;
  // 8-bit file of the format its extension names.
  virtual void write(const std::string& path) const = 0;
};

class Services {
 public:
  virtual ~Services() = default;

  // OpenEXR, zip-compressed, float or half channels; the image's strings become string
  // attributes.
  virtual std::string encode_exr(const Pixels& image, bool half) const = 0;
  // Every channel as float and every string attribute of an OpenEXR file (`from_memory`: `source`
  // holds its bytes; else its path). Refuses, before reading pixels, an image larger than
  // max_side per side or with more than max_channels channels.
  virtual Pixels read_exr(const std::string& source, bool from_memory, int max_side,
                          int max_channels) const = 0;
  // PNG of 8-bit sRGB pixels (3 per pixel).
  virtual std::string encode_png(const uint8_t* rgb, int width, int height) const = 0;
  // Any image format OpenImageIO reads, from its bytes; `extension` (".png", ".exr", ...) picks
  // the reader.
  virtual Pixels decode_image(const std::string& bytes, const std::string& extension) const = 0;
  // A tiled, box-filtered MIP map of `image` as an OpenEXR texture file.
  virtual void write_mip_map(const Pixels& image, const std::string& file) const = 0;
  virtual std::unique_ptr<TextureSystem> texture_system(float max_memory_mb) const = 0;
  // A white canvas.
  virtual std::unique_ptr<Canvas> canvas(int width, int height) const = 0;
};

// The module's entry point, `extern "C" const Services* penumbra_oiio_services(int version)`:
// it returns null when the module was built for another version of this interface.
inline constexpr int kInterfaceVersion = 1;
inline constexpr const char* kEntryPoint = "penumbra_oiio_services";
inline constexpr const char* kModuleFile = "libpenumbra_oiio.so";

// The module's services, loaded once (thread-safe). The module is looked for at
// $PENUMBRA_OIIO_MODULE when it is set (only there), else beside the executable, in
// ../lib/penumbra/ from it, in the build tree it was built in, then by the dynamic linker's search
// path; throws std::runtime_error listing where it looked when it is in none of them.
const Services& services();

// Whether the module is loaded in this process (for tests of what loads it).
bool loaded();

}  // namespace penumbra::oiio
