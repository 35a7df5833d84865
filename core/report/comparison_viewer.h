#pragma once
// The interactive comparison viewer of a batch report: every method's image and the reference
// at full resolution in one HTML section (data, style and script inlined, no network), flipped by
// key or click, zoomed to single pixels (nearest neighbour) and panned in step across all
// methods, tonemapped in the page (exposure in stops, sRGB), with false-colour error views, the
// regions outlined and each method's MRSE with its 95% interval beside it, and a view of each
// image's per-pixel variance (its EXR's variance layer). The script and style are
// viewer/viewer.js and viewer/viewer.css, embedded at build time.
//
// Pixel data: "rgbe8-planar-deflate". Each pixel's linear RGB is stored as three 8-bit mantissas
// sharing one 8-bit exponent (Ward's RGBE, as in Radiance .hdr files, rounded to nearest): with e
// such that max(R, G, B) = f 2^e, f in [0.5, 1), a channel c is stored as m = round(c 2^(8 - e))
// (e one larger when the brightest channel would round to 256) and read back as m 2^(e - 8); the
// exponent byte is e + 128, and 0 marks a black pixel. Every channel is then within
// max(R, G, B) / 255 of its value (half a step: 0.39% of the brightest channel), far below the
// per-pixel Monte Carlo noise the viewer shows, and zero stays zero. A pixel costs 4 bytes before
// compression instead of 6 for half floats or 12 for floats. The four planes (all R mantissas,
// then G, B, exponents; rows top to bottom) are compressed with zlib and decoded in the page by
// the browser's DecompressionStream("deflate"). Negative, NaN and infinite channels are stored as
// 0; a pixel whose brightest channel is below 2^-120 as black. An image's variance layer
// (variance of the mean per channel) is encoded the same way.

#include <map>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/image/metrics.h"
#include "core/report/significance.h"

namespace penumbra {

inline constexpr const char* kViewerImageEncoding = "rgbe8-planar-deflate";
// A decoded channel is within this fraction of its pixel's largest channel.
inline constexpr double kViewerQuantization = 1.0 / 255;

// The encoded bytes (zlib stream) of `image`, and their inverse. decode_viewer_image throws
// std::runtime_error when the bytes are not a zlib stream of 4 width x height bytes.
std::string encode_viewer_image(const Image& image);
Image decode_viewer_image(const std::string& bytes, int width, int height);

// One image in the viewer: a method's run or the reference.
struct ViewerImage {
  std::string label;    // the method's label, or "reference"
  std::string method;   // penumbra/method@1 text form
  std::string sampler;  // pattern name
  uint32_t spp = 0;
  int repeat = 0;
  double compute_seconds = 0;
  const Image* image = nullptr;
  // This image's own MRSE per region ("image" first in the page), against the reference; empty
  // for the reference.
  std::map<std::string, double> mrse;
  // The table row's corrected MRSE over its repeats with the 95% interval, per region; empty when
  // there is no such row (the reference, or a report without the comparison).
  std::map<std::string, MeanInterval> corrected;
  int repeats = 0;  // in the row
  // The variance of the mean per pixel and channel (the EXR's variance layer), or null when the
  // image has none: the variance view then says so.
  const Image* variance = nullptr;
};

struct ViewerRegion {
  std::string name;
  Region rect;  // [x0, x1) x [y0, y1), pixels
};

struct ComparisonViewerContent {
  int width = 0, height = 0;
  double exposure = 1;          // the base exposure (the figure's), scale on linear values
  double error_scale = 1;       // top of the relative error's colour scale (the figure's)
  double difference_scale = 1;  // the signed difference's colour scale is [-this, this]
  // The variance view's logarithmic colour scale, [variance_low, variance_high], on the relative
  // variance: mean over channels of variance / (ref^2 + kMrseEpsilon), a pixel's expected term of
  // the MRSE from noise alone.
  double variance_low = 1e-6, variance_high = 1;
  // The reference; its image may be null (a farm job without one): the viewer then shows the
  // methods alone, without the error and difference views, and each image's variance relative
  // to its own values (variance / (x^2 + kMrseEpsilon)).
  ViewerImage reference;
  std::vector<ViewerImage> methods;  // in batch order, refused methods left out
  std::vector<ViewerRegion> regions;
};

// The 99th percentile over every method's pixels of |mean over channels of (x - ref)|: the
// signed difference's colour scale (1 when every difference is 0).
double choose_difference_scale(const std::vector<const Image*>& images, const Image& reference);

// The variance view's scale: the decades around the 1st and 99th percentiles of every method's
// positive relative variance (see ComparisonViewerContent); [1e-6, 1] when no method has a
// variance layer.
std::pair<double, double> choose_variance_scale(const std::vector<const Image*>& variances,
                                                const Image& reference);

// Every scale of the content from its images, as the report's figure chooses them: the
// exposure (choose_exposure of the reference), the relative error's (choose_error_scale), the
// signed difference's and the variance view's. Without a reference: the exposure of the first
// method's image, the variance scale of each image relative to itself, the error scales 1.
void choose_viewer_scales(ComparisonViewerContent& content);

// The viewer's section of the page (a <section id="viewer"> with its <style>, the data as a
// <script type="application/json"> and the viewer's <script>). Throws std::invalid_argument when
// an image is missing (a method's; without a reference at least one method is needed) or its
// size differs from width x height.
std::string comparison_viewer_html(const ComparisonViewerContent& content);

// The viewer's script and style as embedded in the build (viewer/viewer.js, viewer/viewer.css).
std::string_view comparison_viewer_script();
std::string_view comparison_viewer_style();

}  // namespace penumbra
