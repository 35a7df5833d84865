// The module libpenumbra_oiio.so: core/image/oiio_services.h implemented on OpenImageIO 2.4.
// It is the only code of Penumbra that links OpenImageIO; processes open it on first use.
//
// In-memory encoding and decoding use OIIO's IOVecOutput / IOMemReader proxies: the OpenEXR and
// PNG plugins of OIIO 2.4 support them, so encode/decode never touch the disk.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/image/oiio_services.h"

namespace penumbra::oiio {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what);
}

void write_image(OIIO::ImageOutput& output, const std::string& name, const OIIO::ImageSpec& spec,
                 OIIO::TypeDesc format, const void* pixels) {
  if (!output.open(name, spec)) fail("cannot open for writing: " + output.geterror());
  if (!output.write_image(format, pixels)) {
    std::string error = output.geterror();
    output.close();
    fail("cannot write pixels: " + error);
  }
  if (!output.close()) fail("cannot finish the file: " + output.geterror());
}

std::string encode(const std::string& format_name, const OIIO::ImageSpec& spec,
                   OIIO::TypeDesc format, const void* pixels) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  auto output = OIIO::ImageOutput::create(format_name, &proxy);
  if (!output) fail("no " + format_name + " writer: " + OIIO::geterror());
  if (!output->supports("ioproxy"))
    fail("this OpenImageIO's " + format_name + " writer cannot write to memory");
  write_image(*output, "memory." + format_name, spec, format, pixels);
  return std::string(bytes.begin(), bytes.end());
}

Pixels read_opened(OIIO::ImageInput& input, int max_side, int max_channels) {
  const OIIO::ImageSpec& spec = input.spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1)
    fail("unsupported image size " + std::to_string(spec.width) + "x" +
         std::to_string(spec.height) + "x" + std::to_string(spec.depth));
  // A corrupt or hostile header must not make us allocate terabytes.
  if (spec.width > max_side || spec.height > max_side || spec.nchannels > max_channels)
    fail("image of " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
         " pixels and " + std::to_string(spec.nchannels) + " channels exceeds the limits (" +
         std::to_string(max_side) + " per side, " + std::to_string(max_channels) + " channels)");
  Pixels image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.channel_names = spec.channelnames;
  image.data.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
  if (!input.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.data.data()))
    fail("cannot read pixels: " + input.geterror());
  for (const OIIO::ParamValue& attribute : spec.extra_attribs)
    if (attribute.type() == OIIO::TypeDesc::STRING)
      image.strings.emplace_back(attribute.name().string(), attribute.get_string());
  return image;
}

// Every TextureSystem of the process shares OpenImageIO's one texture system (each scene's files
// have names of their own); a scene's files are released from it when its TextureSystem goes.
// The shared system is never destroyed: OpenImageIO 2.4's TextureSystem::destroy frees a private
// system with the wrong size (AddressSanitizer: new-delete-type-mismatch), the shared one it
// keeps until exit.
class OiioTextureSystem final : public TextureSystem {
 public:
  explicit OiioTextureSystem(float max_memory_mb)
      : system_(OIIO::TextureSystem::create(/*shared=*/true)) {
    float current = 0;
    system_->getattribute("max_memory_MB", current);
    if (max_memory_mb > current) system_->attribute("max_memory_MB", max_memory_mb);
  }
  ~OiioTextureSystem() override {
    for (const OIIO::ustring& file : files_) system_->invalidate(file, /*force=*/true);
  }

  const void* handle(const std::string& file) override {
    OIIO::ustring name(file);
    OIIO::TextureSystem::TextureHandle* handle = system_->get_texture_handle(name);
    if (!handle) fail("texture system: " + system_->geterror());
    files_.push_back(name);
    return handle;
  }

  bool texture(const void* handle, const TextureLookup& lookup, float* out) const override {
    OIIO::TextureOpt opt;
    OIIO::TextureOpt::Wrap wrap = lookup.wrap == Wrap::Periodic ? OIIO::TextureOpt::WrapPeriodic
                                  : lookup.wrap == Wrap::Black  ? OIIO::TextureOpt::WrapBlack
                                                                : OIIO::TextureOpt::WrapClamp;
    opt.swrap = opt.twrap = wrap;
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;
    if (lookup.trilinear) {
      opt.mipmode = OIIO::TextureOpt::MipModeTrilinear;
    } else {
      opt.mipmode = OIIO::TextureOpt::MipModeAniso;
      opt.anisotropic = lookup.max_anisotropy;
    }
    // Per-thread state of this system, fetched once per thread (the lookup's hot path).
    thread_local OIIO::TextureSystem::Perthread* thread_info = nullptr;
    thread_local const OIIO::TextureSystem* thread_system = nullptr;
    if (thread_system != system_) {
      thread_info = system_->get_perthread_info();
      thread_system = system_;
    }
    auto* h = static_cast<OIIO::TextureSystem::TextureHandle*>(const_cast<void*>(handle));
    return system_->texture(h, thread_info, opt, lookup.s, lookup.t, lookup.dsdx, lookup.dtdx,
                            lookup.dsdy, lookup.dtdy, lookup.channels, out);
  }

 private:
  OIIO::TextureSystem* system_;
  std::vector<OIIO::ustring> files_;
};

class OiioCanvas final : public Canvas {
 public:
  OiioCanvas(int width, int height)
      : buffer_(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT)) {
    OIIO::ImageBufAlgo::fill(buffer_, {1.0f, 1.0f, 1.0f});
  }

  void paste(const float* rgb, int width, int height, int x, int y) override {
    OIIO::ImageBuf tile(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT),
                        const_cast<float*>(rgb));
    OIIO::ImageBufAlgo::paste(buffer_, x, y, 0, 0, tile);
  }

  void box(int x0, int y0, int x1, int y1, const float* color, bool filled) override {
    OIIO::ImageBufAlgo::render_box(buffer_, x0, y0, x1, y1, {color, 3}, filled);
  }

  int text_width(const std::string& text, int size, const std::string& font) const override {
    if (text.empty()) return 0;  // OIIO measures empty text as an undefined ROI
    OIIO::ROI extent = OIIO::ImageBufAlgo::text_size(text, size, font);
    return extent.defined() ? extent.width() : 0;
  }

  void text(int x, int baseline, const std::string& text, int size, const std::string& font,
            const float* color) override {
    if (text.empty()) return;
    OIIO::ImageBufAlgo::render_text(buffer_, x, baseline, text, size, font, {color, 3});
  }

  void write(const std::string& path) const override {
    if (!buffer_.write(path, OIIO::TypeDesc::UINT8))
      fail("cannot write the figure: " + buffer_.geterror());
  }

 private:
  OIIO::ImageBuf buffer_;
};

class OiioServices final : public Services {
 public:
  std::string encode_exr(const Pixels& image, bool half) const override {
    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    spec.channelnames = image.channel_names;
    spec.alpha_channel = -1;
    spec.attribute("compression", "zip");
    for (const auto& [name, value] : image.strings) spec.attribute(name, value);
    return encode("openexr", spec, OIIO::TypeDesc::FLOAT, image.data.data());
  }

  Pixels read_exr(const std::string& source, bool from_memory, int max_side,
                  int max_channels) const override {
    auto input = OIIO::ImageInput::create("openexr");
    if (!input) fail("no OpenEXR reader: " + OIIO::geterror());
    std::unique_ptr<OIIO::Filesystem::IOMemReader> proxy;
    if (from_memory) {
      proxy = std::make_unique<OIIO::Filesystem::IOMemReader>(source.data(), source.size());
      if (!input->supports("ioproxy") || !input->set_ioproxy(proxy.get()))
        fail("this OpenImageIO's OpenEXR reader cannot read memory");
    }
    OIIO::ImageSpec spec;
    if (!input->open(from_memory ? std::string("memory.exr") : source, spec)) {
      std::string error = input->geterror();
      if (from_memory)
        fail("cannot decode: " + (error.empty() ? std::string("corrupt OpenEXR data") : error));
      fail("cannot open: " + (error.empty() ? std::string("not a readable EXR file") : error));
    }
    Pixels image = read_opened(*input, max_side, max_channels);
    input->close();
    return image;
  }

  std::string encode_png(const uint8_t* rgb, int width, int height) const override {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    return encode("png", spec, OIIO::TypeDesc::UINT8, rgb);
  }

  Pixels decode_image(const std::string& bytes, const std::string& extension) const override {
    OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
    OIIO::ImageSpec config;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &reader);
    OIIO::ImageBuf source("in" + extension, 0, 0, nullptr, &config, &reader);
    if (!source.read(0, 0, true, OIIO::TypeDesc::FLOAT)) fail(source.geterror());
    const OIIO::ImageSpec& spec = source.spec();
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1) fail("empty image");
    Pixels image;
    image.width = spec.width;
    image.height = spec.height;
    image.channels = spec.nchannels;
    image.channel_names = spec.channelnames;
    image.data.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
    if (!source.get_pixels(source.roi(), OIIO::TypeDesc::FLOAT, image.data.data()))
      fail(source.geterror());
    return image;
  }

  void write_mip_map(const Pixels& image, const std::string& file) const override {
    OIIO::ImageBuf decoded(
        OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
        const_cast<float*>(image.data.data()));
    OIIO::ImageSpec config;
    config.attribute("maketx:filtername", "box");
    config.attribute("maketx:highlightcomp", 0);
    config.attribute("maketx:fixnan", "box3");
    config.attribute("tile_width", 64);
    config.attribute("tile_height", 64);
    if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, decoded, file, config))
      fail("MIP map: " + OIIO::geterror());
  }

  std::unique_ptr<TextureSystem> texture_system(float max_memory_mb) const override {
    return std::make_unique<OiioTextureSystem>(max_memory_mb);
  }

  std::unique_ptr<Canvas> canvas(int width, int height) const override {
    return std::make_unique<OiioCanvas>(width, height);
  }
};

}  // namespace
}  // namespace penumbra::oiio

extern "C" __attribute__((visibility("default"))) const penumbra::oiio::Services*
penumbra_oiio_services(int version) {
  static const penumbra::oiio::OiioServices services;
  return version == penumbra::oiio::kInterfaceVersion ? &services : nullptr;
}
