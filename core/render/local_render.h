#pragma once
// A whole image rendered in this process: by samples per pixel, or progressively until a
// compute-time budget is spent (stopping at a pass boundary, so every pixel has the same spp and
// the image is unbiased). The farm renders the same passes of the same tiles.

#include <atomic>
#include <functional>
#include <span>

#include "core/render/film.h"
#include "core/render/renderer.h"

namespace penumbra {

struct RenderBudget {
  uint32_t spp = 0;    // render exactly this many passes, or
  double seconds = 0;  // pass blocks until this much compute (CPU) time is spent
  uint32_t max_spp = 1u << 20;
  // The index of the first pass drawn: a render of passes [first_pass, first_pass + spp), which
  // merges exactly with one of passes [0, first_pass) (core/render/sums_file.h). The counts above
  // (spp, max_spp) are of passes drawn, not pass indices.
  uint32_t first_pass = 0;
};

struct LocalRenderResult {
  Film film;
  std::vector<TileAccumulator> tiles;
  uint32_t spp = 0;
  double compute_seconds = 0;  // CPU seconds of all threads
  double wall_seconds = 0;
  bool stopped = false;  // `stop` was set: fewer passes than the budget asked for
};

// Progress is called after every pass block with the passes done and compute seconds so far.
// With `stop`, pass blocks last at most about kStoppableBlockSeconds of wall time (and at most a
// tenth of an spp budget, so that progress moves), and once *stop is true the render ends at the
// next block boundary: every pixel then has the same whole passes, an unbiased image of
// result.spp samples, bit-identical to a render of that many passes.
// `inspect`, when given, is called after every pass block, before `progress`, with the tiles so
// far (whole passes each): e.g. to measure the error of the image so far.
inline constexpr double kStoppableBlockSeconds = 0.5;
LocalRenderResult render_local(
    const Renderer& renderer, const RenderBudget& budget, int threads, int tile_size = 64,
    const std::function<void(uint32_t, double)>& progress = {},
    const std::atomic<bool>* stop = nullptr,
    const std::function<void(std::span<const TileAccumulator>)>& inspect = {});

// CPU time of the process (all threads), seconds.
double process_cpu_seconds();

}  // namespace penumbra
