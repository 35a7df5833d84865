#pragma once
// The paper-style figure of a batch (Salesin & Jarosz Figs. 1, 8-10): one column per method
// (the reference first) with the full image tonemapped at one exposure for all, each region's
// crop enlarged (nearest neighbour) with its MRSE, and a false-colour map of the relative error
// |x - ref| / (ref + 0.01) on one shared scale with a colour bar. One PNG, drawn with
// OpenImageIO's ImageBuf (text with render_text and DejaVu Sans).

#include <filesystem>

#include "core/image/image.h"
#include "core/report/batch_report.h"
#include "core/report/batch_table.h"

namespace penumbra {

inline constexpr double kRelativeErrorOffset = 1e-2;  // |x - ref| / (ref + 0.01)

struct BatchFigureInfo {
  int width = 0, height = 0;  // of the PNG
  double exposure = 1;        // applied to every image
  double error_scale = 1;     // relative error at the top of the colour bar
  // Per method (in batch order), the run shown: index into its runs, or -1 for a refused method.
  std::vector<int> shown_runs;
};

// Exposure that maps the 99th percentile of the reference's luminance to 0.9 (1 for a black
// image).
double choose_exposure(const Image& reference);

// Relative error per pixel, averaged over the three channels: |x - ref| / (ref + 0.01).
Image relative_error_map(const Image& image, const Image& reference);

// The top of the relative error's colour scale shared by every image: the 99th percentile of
// their pooled relative errors, rounded up to 1, 2 or 5 times a power of ten (1 when every error
// is 0). Null images are skipped.
double choose_error_scale(const std::vector<const Image*>& images, const Image& reference);

// The viridis colour map at t in [0, 1] (clamped), linear interpolation between 9 samples.
Rgb viridis(double t);

// Writes the figure to `png_path`. Throws std::runtime_error when an EXR cannot be read or the
// PNG cannot be written.
BatchFigureInfo write_batch_figure(const BatchResult& result, const RecomputedErrors& recomputed,
                                   const std::filesystem::path& result_dir,
                                   const std::filesystem::path& png_path,
                                   const BatchReportOptions& options);

}  // namespace penumbra
