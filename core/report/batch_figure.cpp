// The batch figure: layout in columns (reference, then each method), images resampled and
// tonemapped onto one canvas of the image module (OpenImageIO), labels drawn with its text.

#include "core/report/batch_figure.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/image/oiio_services.h"

namespace penumbra {

namespace {

constexpr const char* kFontRegular = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
constexpr const char* kFontBold = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";
constexpr int kMargin = 14;
constexpr int kColumnGap = 10;
constexpr int kLabelHeight = 18;

// Outline colours of the regions (display sRGB), cycled.
constexpr float kRegionColors[][3] = {{1.0f, 0.55f, 0.0f}, {0.0f, 0.8f, 1.0f}, {1.0f, 0.2f, 0.8f},
                                      {1.0f, 1.0f, 0.2f},  {0.3f, 1.0f, 0.3f}, {1.0f, 0.3f, 0.3f}};
constexpr int kRegionColorCount = int(sizeof(kRegionColors) / sizeof(kRegionColors[0]));

// Display values in [0, 1], 3 per pixel (already sRGB-encoded).
struct DisplayImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

double srgb_encode(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// Source pixel range [begin, end) of output pixel `o` when `in` pixels map to `out`: the nearest
// pixel when enlarging, the covered pixels (box filter) when reducing.
std::pair<int, int> source_span(int o, int in, int out) {
  if (out >= in) {
    int nearest = std::min(in - 1, int((o + 0.5) * in / out));
    return {nearest, nearest + 1};
  }
  int begin = int(std::floor(double(o) * in / out));
  int end = std::max(begin + 1, int(std::ceil(double(o + 1) * in / out)));
  return {begin, std::min(end, in)};
}

// The rectangle [x0,x1) x [y0,y1) of `image` resampled to out_width x out_height.
Image resample(const Image& image, const Region& rect, int out_width, int out_height) {
  Image out(out_width, out_height);
  int in_width = rect.x1 - rect.x0, in_height = rect.y1 - rect.y0;
  for (int oy = 0; oy < out_height; ++oy) {
    auto [y_begin, y_end] = source_span(oy, in_height, out_height);
    for (int ox = 0; ox < out_width; ++ox) {
      auto [x_begin, x_end] = source_span(ox, in_width, out_width);
      Rgb sum{0, 0, 0};
      for (int y = y_begin; y < y_end; ++y)
        for (int x = x_begin; x < x_end; ++x) sum = sum + image.at(rect.x0 + x, rect.y0 + y);
      out.set(ox, oy, sum / double((y_end - y_begin) * (x_end - x_begin)));
    }
  }
  return out;
}

DisplayImage tonemap(const Image& image, double exposure) {
  DisplayImage display{image.width, image.height, std::vector<float>(image.rgb.size())};
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    double value = double(image.rgb[i]) * exposure;
    display.rgb[i] = float(srgb_encode(std::isfinite(value) ? value : 0.0));
  }
  return display;
}

// The first channel of `map` (the relative error) through viridis on [0, scale].
DisplayImage false_colour(const Image& map, double scale) {
  DisplayImage display{map.width, map.height, std::vector<float>(map.rgb.size())};
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      Rgb color = viridis(map.at(x, y).x / scale);
      size_t i = (size_t(y) * map.width + x) * 3;
      display.rgb[i] = float(color.x);
      display.rgb[i + 1] = float(color.y);
      display.rgb[i + 2] = float(color.z);
    }
  return display;
}

// A "nice" value (1, 2 or 5 times a power of ten) at or above `value`.
double nice_ceiling(double value) {
  double power = std::pow(10.0, std::floor(std::log10(value)));
  for (double step : {1.0, 2.0, 5.0, 10.0})
    if (step * power >= value * (1 - 1e-12)) return step * power;
  return 10 * power;
}

double percentile(std::vector<float> values, double fraction) {
  if (values.empty()) return 0;
  size_t index = std::min(values.size() - 1, size_t(fraction * double(values.size())));
  std::nth_element(values.begin(), values.begin() + ptrdiff_t(index), values.end());
  return values[index];
}

class Canvas {
 public:
  Canvas(int width, int height) : canvas_(oiio::services().canvas(width, height)) {}

  void paste(const DisplayImage& image, int x, int y) {
    canvas_->paste(image.rgb.data(), image.width, image.height, x, y);
  }

  // A rectangle outline `thickness` pixels wide inside [x0, x1] x [y0, y1].
  void outline(int x0, int y0, int x1, int y1, const float* color, int thickness) {
    for (int t = 0; t < thickness && x0 + t <= x1 - t && y0 + t <= y1 - t; ++t)
      canvas_->box(x0 + t, y0 + t, x1 - t, y1 - t, color, false);
  }

  void fill(int x0, int y0, int x1, int y1, const float* color) {
    canvas_->box(x0, y0, x1, y1, color, true);
  }

  // Text centred on `center_x` (or starting at it), shrunk until it fits in `max_width`.
  void text(int x, int baseline, const std::string& text, int size, bool bold, int max_width,
            bool centered = true) {
    if (text.empty()) return;
    const char* font = bold ? kFontBold : kFontRegular;
    int width = 0;
    for (; size >= 8; --size) {
      width = canvas_->text_width(text, size, font);
      if (width <= max_width) break;
    }
    float black[3] = {0.05f, 0.05f, 0.05f};
    int start = centered ? x - width / 2 : x;
    canvas_->text(start, baseline, text, std::max(size, 8), font, black);
  }

  // Text broken into centred lines at spaces, each at most `max_width` wide; at most
  // `max_lines` lines (the last one ends in "..." when the text is longer).
  void wrapped_text(int center, int baseline, const std::string& text, int size, int max_width,
                    int max_lines) {
    std::vector<std::string> words;
    std::string word;
    for (char c : text + " ") {
      if (c != ' ') {
        word += c;
      } else if (!word.empty()) {
        words.push_back(word);
        word.clear();
      }
    }
    std::vector<std::string> lines;
    for (const std::string& next : words) {
      std::string candidate = lines.empty() ? next : lines.back() + " " + next;
      int width = canvas_->text_width(candidate, size, kFontRegular);
      if (!lines.empty() && width > 0 && width <= max_width)
        lines.back() = candidate;
      else
        lines.push_back(next);
    }
    if (int(lines.size()) > max_lines) {
      lines.resize(size_t(max_lines));
      lines.back() += " ...";
    }
    for (size_t i = 0; i < lines.size(); ++i)
      this->text(center, baseline + int(i) * (size + 4), lines[i], size, false, max_width);
  }

  void write(const std::filesystem::path& path) {
    try {
      canvas_->write(path.string());
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(path.string() + ": " + error.what());
    }
  }

 private:
  std::unique_ptr<oiio::Canvas> canvas_;
};

// The run a method's column shows: its highest spp, lowest repeat.
int shown_run(const BatchMethod& method) {
  int best = -1;
  for (size_t r = 0; r < method.runs.size(); ++r) {
    const BatchRun& run = method.runs[r];
    if (best < 0) {
      best = int(r);
      continue;
    }
    const BatchRun& current = method.runs[size_t(best)];
    if (run.spp > current.spp || (run.spp == current.spp && run.repeat < current.repeat))
      best = int(r);
  }
  return best;
}

Region clip_to_image(const Region& region, int width, int height) {
  return {std::clamp(region.x0, 0, width), std::clamp(region.y0, 0, height),
          std::clamp(region.x1, 0, width), std::clamp(region.y1, 0, height)};
}

}  // namespace

double choose_error_scale(const std::vector<const Image*>& images, const Image& reference) {
  std::vector<float> pooled;
  for (const Image* image : images) {
    if (!image) continue;
    Image map = relative_error_map(*image, reference);
    for (size_t i = 0; i < map.rgb.size(); i += 3) pooled.push_back(map.rgb[i]);
  }
  double high = percentile(std::move(pooled), 0.99);
  return high > 0 ? nice_ceiling(high) : 1.0;
}

double choose_exposure(const Image& reference) {
  std::vector<float> luminances;
  luminances.reserve(size_t(reference.width) * reference.height);
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      double value = luminance(reference.at(x, y));
      if (std::isfinite(value)) luminances.push_back(float(value));
    }
  double high = percentile(std::move(luminances), 0.99);
  return high > 0 ? 0.9 / high : 1.0;
}

Image relative_error_map(const Image& image, const Image& reference) {
  Image map(image.width, image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      Rgb value = image.at(x, y), ref = reference.at(x, y);
      double sum = 0;
      for (int c = 0; c < 3; ++c) {
        double error = std::abs(value[c] - ref[c]) / (std::abs(ref[c]) + kRelativeErrorOffset);
        sum += std::isfinite(error) ? error : 0.0;
      }
      double mean = sum / 3;
      map.set(x, y, {mean, mean, mean});
    }
  return map;
}

Rgb viridis(double t) {
  // viridis sampled at 9 evenly spaced points (#440154 ... #fde725), display sRGB.
  static const unsigned kSamples[9] = {0x440154, 0x472d7b, 0x3b528b, 0x2c728e, 0x21918c,
                                       0x28ae80, 0x5ec962, 0xaddc30, 0xfde725};
  auto color = [](unsigned hex) {
    return Rgb{double((hex >> 16) & 0xff) / 255, double((hex >> 8) & 0xff) / 255,
               double(hex & 0xff) / 255};
  };
  if (!std::isfinite(t)) t = t > 0 ? 1 : 0;
  double position = std::clamp(t, 0.0, 1.0) * 8;
  int index = std::min(7, int(position));
  double fraction = position - index;
  return color(kSamples[index]) * (1 - fraction) + color(kSamples[index + 1]) * fraction;
}

BatchFigureInfo write_batch_figure(const BatchResult& result, const RecomputedErrors& recomputed,
                                   const std::filesystem::path& result_dir,
                                   const std::filesystem::path& png_path,
                                   const BatchReportOptions& options) {
  BatchFigureInfo info;
  Image reference = read_exr((result_dir / result.reference.exr).string());
  const int width = reference.width, height = reference.height;
  info.exposure = options.exposure.value_or(choose_exposure(reference));

  // The columns: the reference, then every method (a refused one shows its refusal).
  std::vector<Image> images;  // per method, the shown run's image (empty when refused)
  for (const BatchMethod& method : result.methods) {
    int run = shown_run(method);
    info.shown_runs.push_back(run);
    images.push_back(run < 0 ? Image()
                             : read_exr((result_dir / method.runs[size_t(run)].exr).string()));
    if (run >= 0 && (images.back().width != width || images.back().height != height))
      throw std::runtime_error(method.runs[size_t(run)].exr + ": size differs from the reference");
  }

  // One error scale for all maps.
  std::vector<Image> error_maps;
  std::vector<const Image*> shown;
  for (const Image& image : images) {
    error_maps.push_back(image.width ? relative_error_map(image, reference) : Image());
    if (image.width) shown.push_back(&image);
  }
  info.error_scale = choose_error_scale(shown, reference);

  // Geometry.
  const int column_width = std::max(64, options.figure_column_width);
  const int image_height = std::max(1, int(std::lround(double(height) * column_width / width)));
  const int columns = int(result.methods.size()) + 1;
  const int canvas_width = 2 * kMargin + columns * column_width + (columns - 1) * kColumnGap;
  struct CropLayout {
    Region rect;
    int display_width, display_height;
  };
  std::vector<CropLayout> crops;
  for (const BatchRegion& region : result.regions) {
    Region rect = clip_to_image(region.rect, width, height);
    int region_width = std::max(1, rect.x1 - rect.x0),
        region_height = std::max(1, rect.y1 - rect.y0);
    int factor = std::min(column_width / region_width, column_width / region_height);
    CropLayout crop{rect, region_width * factor, region_height * factor};
    if (factor < 1) {  // a region wider than the column: reduce it to fit
      double scale =
          std::min(double(column_width) / region_width, double(column_width) / region_height);
      crop.display_width = std::max(1, int(region_width * scale));
      crop.display_height = std::max(1, int(region_height * scale));
    }
    crops.push_back(crop);
  }
  const int title_height = 28, header_height = 36, colour_bar_height = 14;
  int canvas_height = kMargin + title_height + header_height + image_height + 4 + kLabelHeight;
  for (const CropLayout& crop : crops) canvas_height += 6 + crop.display_height + 4 + kLabelHeight;
  canvas_height += 6 + image_height + 4 + kLabelHeight + 10 + colour_bar_height + 34 + kMargin;
  Canvas canvas(canvas_width, canvas_height);
  info.width = canvas_width;
  info.height = canvas_height;

  std::string title = (result.name.empty() ? std::string("batch") : result.name) + ", scene " +
                      result.scene.name + ", " + std::to_string(width) + "x" +
                      std::to_string(height) + ", exposure " + format_number(info.exposure);
  canvas.text(kMargin, kMargin + 18, title, 18, true, canvas_width - 2 * kMargin, false);

  for (int column = 0; column < columns; ++column) {
    const int x = kMargin + column * (column_width + kColumnGap);
    const int center = x + column_width / 2;
    const bool is_reference = column == 0;
    const size_t m = size_t(column - 1);
    const Image* image = is_reference ? &reference : &images[m];
    const BatchMethod* method = is_reference ? nullptr : &result.methods[m];
    const int run_index = is_reference ? -1 : info.shown_runs[m];
    const BatchRun* run = run_index >= 0 ? &method->runs[size_t(run_index)] : nullptr;
    int y = kMargin + title_height;

    // Header: label, then spp and compute seconds.
    std::string label = is_reference ? "reference" : method->label;
    std::string detail;
    if (is_reference)
      detail = result.reference.method + ", " + std::to_string(result.reference.spp) + " spp";
    else if (run)
      detail = std::to_string(run->spp) + " spp, " + format_number(run->compute_seconds) +
               " s, repeat " + std::to_string(run->repeat);
    else
      detail = "refused";
    canvas.text(center, y + 14, label, 14, true, column_width);
    canvas.text(center, y + 30, detail, 11, false, column_width);
    y += header_height;

    // Full image with the regions outlined.
    if (image->width) {
      canvas.paste(tonemap(resample(*image, {0, 0, width, height}, column_width, image_height),
                           info.exposure),
                   x, y);
      for (size_t k = 0; k < crops.size(); ++k) {
        const Region& rect = crops[k].rect;
        double scale = double(column_width) / width;
        canvas.outline(x + int(rect.x0 * scale), y + int(rect.y0 * scale),
                       x + std::max(int(rect.x0 * scale) + 1, int(std::ceil(rect.x1 * scale)) - 1),
                       y + std::max(int(rect.y0 * scale) + 1, int(std::ceil(rect.y1 * scale)) - 1),
                       kRegionColors[k % kRegionColorCount], 2);
      }
    } else {
      float grey[3] = {0.85f, 0.85f, 0.85f};
      canvas.fill(x, y, x + column_width - 1, y + image_height - 1, grey);
      canvas.text(center, y + 24, "refused", 14, true, column_width);
      canvas.wrapped_text(center, y + 46, method->error.empty() ? "no runs" : method->error, 11,
                          column_width - 12, std::max(1, (image_height - 50) / 15));
    }
    y += image_height + 4;
    std::string under =
        is_reference ? "MRSE (full image)"
        : run ? "MRSE " + format_number(recomputed.at(m).at(size_t(run_index)).at("image").mrse)
              : "";
    canvas.text(center, y + 13, under, 12, false, column_width);
    y += kLabelHeight;

    // Region crops, enlarged.
    for (size_t k = 0; k < crops.size(); ++k) {
      y += 6;
      const CropLayout& crop = crops[k];
      int crop_x = x + (column_width - crop.display_width) / 2;
      if (image->width) {
        canvas.paste(tonemap(resample(*image, crop.rect, crop.display_width, crop.display_height),
                             info.exposure),
                     crop_x, y);
        canvas.outline(crop_x, y, crop_x + crop.display_width - 1, y + crop.display_height - 1,
                       kRegionColors[k % kRegionColorCount], 2);
      }
      y += crop.display_height + 4;
      const std::string& name = result.regions[k].name;
      std::string caption =
          is_reference ? name
          : run        ? name + ": MRSE " +
                      format_number(recomputed.at(m).at(size_t(run_index)).at(name).mrse)
                : "";
      canvas.text(center, y + 13, caption, 12, false, column_width);
      y += kLabelHeight;
    }

    // Relative error map on the shared scale.
    y += 6;
    if (!is_reference && image->width) {
      Image map = resample(error_maps[m], {0, 0, width, height}, column_width, image_height);
      canvas.paste(false_colour(map, info.error_scale), x, y);
      double mean_error = 0;
      for (size_t i = 0; i < error_maps[m].rgb.size(); i += 3) mean_error += error_maps[m].rgb[i];
      mean_error /= double(size_t(width) * height);
      canvas.text(center, y + image_height + 4 + 13,
                  "mean relative error " + format_number(mean_error), 12, false, column_width);
    } else if (is_reference) {
      canvas.text(center, y + image_height / 2, "relative error", 13, true, column_width);
      canvas.text(center, y + image_height / 2 + 18, "|x - ref| / (ref + 0.01)", 12, false,
                  column_width);
      canvas.text(center, y + image_height / 2 + 36, "(mean of R, G, B)", 11, false, column_width);
    }
  }

  // The colour bar under the error maps, with its scale.
  int bar_y = canvas_height - kMargin - 34 - colour_bar_height;
  int bar_width = std::min(canvas_width - 2 * kMargin, 360);
  DisplayImage bar{bar_width, colour_bar_height,
                   std::vector<float>(size_t(bar_width) * colour_bar_height * 3)};
  for (int bx = 0; bx < bar_width; ++bx) {
    Rgb color = viridis((bx + 0.5) / bar_width);
    for (int by = 0; by < colour_bar_height; ++by) {
      size_t i = (size_t(by) * bar_width + bx) * 3;
      bar.rgb[i] = float(color.x);
      bar.rgb[i + 1] = float(color.y);
      bar.rgb[i + 2] = float(color.z);
    }
  }
  canvas.paste(bar, kMargin, bar_y);
  int label_y = bar_y + colour_bar_height + 13;
  canvas.text(kMargin, label_y, "0", 11, false, 40, false);
  canvas.text(kMargin + bar_width / 2, label_y, format_number(info.error_scale / 2), 11, false, 80);
  std::string top = ">= " + format_number(info.error_scale);
  canvas.text(kMargin + bar_width - 30, label_y, top, 11, false, 80);
  canvas.text(kMargin, label_y + 16, "relative error |x - ref| / (ref + 0.01), shared scale", 11,
              false, canvas_width - 2 * kMargin, false);

  std::filesystem::create_directories(png_path.parent_path().empty() ? "."
                                                                     : png_path.parent_path());
  canvas.write(png_path);
  return info;
}

}  // namespace penumbra
