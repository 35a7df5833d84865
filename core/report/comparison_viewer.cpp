// The comparison viewer's section of a report: images encoded as RGBE planes (zlib), the
// numbers as JSON, and the embedded script and style.

#include "core/report/comparison_viewer.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <tuple>

#include "core/image/metrics.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "penumbra/viewer_assets.h"

namespace penumbra {

namespace {

// Exponents below this store the pixel as black: 2^-120 is far below any radiance a render
// produces, and the byte e + 128 stays above 0, which marks black.
constexpr int kMinExponent = -120;
constexpr int kMaxExponent = 127;

double clean(float value) {
  return std::isfinite(value) && value > 0 ? double(value) : 0.0;
}

nlohmann::json interval_json(const MeanInterval& value) {
  nlohmann::json json = {{"mean", value.mean}, {"count", value.count}};
  if (value.has_interval) {
    json["lower"] = value.lower();
    json["upper"] = value.upper();
  }
  return json;
}

nlohmann::json image_json(const ViewerImage& image, int width, int height) {
  if (!image.image) throw std::invalid_argument("comparison viewer: " + image.label + ": no image");
  if (image.image->width != width || image.image->height != height ||
      image.image->rgb.size() != size_t(width) * height * 3)
    throw std::invalid_argument("comparison viewer: " + image.label + ": image is " +
                                std::to_string(image.image->width) + "x" +
                                std::to_string(image.image->height) + ", expected " +
                                std::to_string(width) + "x" + std::to_string(height));
  nlohmann::json json = {{"label", image.label},
                         {"method", image.method},
                         {"sampler", image.sampler},
                         {"spp", image.spp},
                         {"repeat", image.repeat},
                         {"repeats", image.repeats},
                         {"compute_seconds", image.compute_seconds},
                         {"data", base64_encode(encode_viewer_image(*image.image))}};
  if (image.variance) {
    if (image.variance->width != width || image.variance->height != height ||
        image.variance->rgb.size() != size_t(width) * height * 3)
      throw std::invalid_argument("comparison viewer: " + image.label + ": variance layer is " +
                                  std::to_string(image.variance->width) + "x" +
                                  std::to_string(image.variance->height) + ", expected " +
                                  std::to_string(width) + "x" + std::to_string(height));
    json["variance"] = base64_encode(encode_viewer_image(*image.variance));
  }
  json["mrse"] = nlohmann::json::object();
  for (const auto& [region, value] : image.mrse) json["mrse"][region] = value;
  json["corrected"] = nlohmann::json::object();
  for (const auto& [region, value] : image.corrected)
    json["corrected"][region] = interval_json(value);
  return json;
}

// JSON inside a <script> element: "</script" would end the element and "<!--" change how it is
// parsed, so every '<' (which JSON has only inside strings) is written as the escape \u003c.
std::string script_safe(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (char c : json) {
    if (c == '<')
      out += "\\u003c";
    else
      out += c;
  }
  return out;
}

}  // namespace

std::string encode_viewer_image(const Image& image) {
  const size_t pixels = size_t(image.width) * size_t(image.height);
  if (image.rgb.size() != pixels * 3)
    throw std::invalid_argument("encode_viewer_image: the image has no full pixel buffer");
  std::string planes(pixels * 4, '\0');
  for (size_t i = 0; i < pixels; ++i) {
    double rgb[3] = {clean(image.rgb[3 * i]), clean(image.rgb[3 * i + 1]),
                     clean(image.rgb[3 * i + 2])};
    double largest = std::max({rgb[0], rgb[1], rgb[2]});
    int exponent = 0;
    if (largest > 0) std::frexp(largest, &exponent);        // largest = f 2^exponent, f in [0.5, 1)
    if (largest <= 0 || exponent < kMinExponent) continue;  // black: all four bytes 0
    if (std::lround(std::ldexp(largest, 8 - exponent)) > 255) ++exponent;
    exponent = std::min(exponent, kMaxExponent);
    const double scale = std::ldexp(1.0, 8 - exponent);
    for (int c = 0; c < 3; ++c)
      planes[size_t(c) * pixels + i] = char(uint8_t(std::min(255.0, std::round(rgb[c] * scale))));
    planes[3 * pixels + i] = char(uint8_t(exponent + 128));
  }
  uLongf size = compressBound(uLong(planes.size()));
  std::string compressed(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &size,
                reinterpret_cast<const Bytef*>(planes.data()), uLong(planes.size()),
                Z_BEST_COMPRESSION) != Z_OK)
    throw std::runtime_error("encode_viewer_image: zlib failed");
  compressed.resize(size);
  return compressed;
}

Image decode_viewer_image(const std::string& bytes, int width, int height) {
  const size_t pixels = size_t(width) * size_t(height);
  std::string planes(pixels * 4, '\0');
  uLongf size = uLongf(planes.size());
  if (uncompress(reinterpret_cast<Bytef*>(planes.data()), &size,
                 reinterpret_cast<const Bytef*>(bytes.data()), uLong(bytes.size())) != Z_OK ||
      size != planes.size())
    throw std::runtime_error("decode_viewer_image: not a zlib stream of " +
                             std::to_string(planes.size()) + " bytes");
  Image image(width, height);
  for (size_t i = 0; i < pixels; ++i) {
    int stored = uint8_t(planes[3 * pixels + i]);
    if (stored == 0) continue;
    const double scale = std::ldexp(1.0, stored - 128 - 8);
    for (int c = 0; c < 3; ++c)
      image.rgb[3 * i + size_t(c)] = float(uint8_t(planes[size_t(c) * pixels + i]) * scale);
  }
  return image;
}

double choose_difference_scale(const std::vector<const Image*>& images, const Image& reference) {
  std::vector<float> magnitudes;
  for (const Image* image : images) {
    if (!image) continue;
    check_same_size(*image, reference);
    for (size_t i = 0; i + 2 < reference.rgb.size(); i += 3) {
      double difference = 0;
      for (size_t c = 0; c < 3; ++c) difference += double(image->rgb[i + c]) - reference.rgb[i + c];
      difference = std::abs(difference / 3);
      if (std::isfinite(difference)) magnitudes.push_back(float(difference));
    }
  }
  if (magnitudes.empty()) return 1;
  size_t index = std::min(magnitudes.size() - 1, size_t(0.99 * double(magnitudes.size())));
  std::nth_element(magnitudes.begin(), magnitudes.begin() + ptrdiff_t(index), magnitudes.end());
  return magnitudes[index] > 0 ? double(magnitudes[index]) : 1.0;
}

namespace {

// Appends the positive relative variances of `variance` against `denominator` (the mean over
// channels of variance / (d^2 + kMrseEpsilon)) to `relative`.
void add_relative_variances(const Image& variance, const Image& denominator,
                            std::vector<float>& relative) {
  check_same_size(variance, denominator);
  for (size_t i = 0; i + 2 < denominator.rgb.size(); i += 3) {
    double sum = 0;
    for (size_t c = 0; c < 3; ++c) {
      double r = denominator.rgb[i + c];
      sum += double(variance.rgb[i + c]) / (r * r + kMrseEpsilon);
    }
    if (std::isfinite(sum) && sum > 0) relative.push_back(float(sum / 3));
  }
}

// The decades around the 1st and 99th percentiles of `relative`; [1e-6, 1] when it is empty.
std::pair<double, double> variance_scale_of(std::vector<float>& relative) {
  if (relative.empty()) return {1e-6, 1};
  auto at = [&](double fraction) {
    size_t index = std::min(relative.size() - 1, size_t(fraction * double(relative.size())));
    std::nth_element(relative.begin(), relative.begin() + ptrdiff_t(index), relative.end());
    return double(relative[index]);
  };
  double low = std::pow(10.0, std::floor(std::log10(at(0.01))));
  double high = std::pow(10.0, std::ceil(std::log10(at(0.99))));
  if (!(high > low)) high = low * 10;
  return {low, high};
}

}  // namespace

std::pair<double, double> choose_variance_scale(const std::vector<const Image*>& variances,
                                                const Image& reference) {
  std::vector<float> relative;
  for (const Image* variance : variances)
    if (variance) add_relative_variances(*variance, reference, relative);
  return variance_scale_of(relative);
}

void choose_viewer_scales(ComparisonViewerContent& content) {
  if (!content.reference.image) {
    if (content.methods.empty() || !content.methods.front().image)
      throw std::invalid_argument("comparison viewer: no reference and no method's image");
    std::vector<float> relative;
    for (const ViewerImage& method : content.methods)
      if (method.image && method.variance)
        add_relative_variances(*method.variance, *method.image, relative);
    content.exposure = choose_exposure(*content.methods.front().image);
    content.error_scale = 1;
    content.difference_scale = 1;
    std::tie(content.variance_low, content.variance_high) = variance_scale_of(relative);
    return;
  }
  const Image& reference = *content.reference.image;
  std::vector<const Image*> images, variances;
  for (const ViewerImage& method : content.methods) {
    images.push_back(method.image);
    variances.push_back(method.variance);
  }
  content.exposure = choose_exposure(reference);
  content.error_scale = choose_error_scale(images, reference);
  content.difference_scale = choose_difference_scale(images, reference);
  std::tie(content.variance_low, content.variance_high) =
      choose_variance_scale(variances, reference);
}

std::string comparison_viewer_html(const ComparisonViewerContent& content) {
  nlohmann::json data = {{"encoding", kViewerImageEncoding},
                         {"width", content.width},
                         {"height", content.height},
                         {"exposure", content.exposure},
                         {"error_scale", content.error_scale},
                         {"difference_scale", content.difference_scale},
                         {"relative_error_offset", kRelativeErrorOffset},
                         {"mrse_epsilon", kMrseEpsilon},
                         {"variance_scale", {content.variance_low, content.variance_high}}};
  data["regions"] = nlohmann::json::array();
  for (const ViewerRegion& region : content.regions)
    data["regions"].push_back(
        {{"name", region.name},
         {"rect", {region.rect.x0, region.rect.y0, region.rect.x1, region.rect.y1}}});
  if (content.reference.image)
    data["reference"] = image_json(content.reference, content.width, content.height);
  else if (content.methods.empty())
    throw std::invalid_argument("comparison viewer: no reference and no method");
  else
    data["reference"] = nullptr;
  data["methods"] = nlohmann::json::array();
  for (const ViewerImage& method : content.methods)
    data["methods"].push_back(image_json(method, content.width, content.height));

  std::string html;
  html += "<section id=\"viewer\" class=\"pv\">\n<style>";
  html += comparison_viewer_style();
  html +=
      "</style>\n<noscript><p class=\"note\">The interactive viewer needs JavaScript; the "
      "figure below shows the same images.</p></noscript>\n"
      "<script type=\"application/json\" id=\"viewer-data\">";
  html += script_safe(data.dump());
  html += "</script>\n<script>";
  html += comparison_viewer_script();
  html += "</script>\n</section>\n";
  return html;
}

std::string_view comparison_viewer_script() {
  return kViewerScript;
}
std::string_view comparison_viewer_style() {
  return kViewerStyle;
}

}  // namespace penumbra
