#include "core/render/local_render.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <ctime>
#include <stdexcept>

namespace penumbra {

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + ts.tv_nsec * 1e-9;
}

LocalRenderResult render_local(
    const Renderer& renderer, const RenderBudget& budget, int threads, int tile_size,
    const std::function<void(uint32_t, double)>& progress, const std::atomic<bool>* stop,
    const std::function<void(std::span<const TileAccumulator>)>& inspect) {
  if (budget.spp == 0 && !(budget.seconds > 0))
    throw std::invalid_argument("a render needs a budget: spp >= 1 or seconds > 0");
  if (uint64_t(budget.first_pass) + std::max(budget.spp, budget.max_spp) > (uint64_t(1) << 31))
    throw std::invalid_argument("a render's passes must end below pass 2^31");
  const Camera& camera = renderer.scene().camera;
  LocalRenderResult result;
  std::vector<TileRect> rects = cut_tiles(camera.width, camera.height, tile_size);
  for (const TileRect& r : rects) result.tiles.emplace_back(r);

  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  const double cpu_start = process_cpu_seconds();
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  uint32_t done = 0;
  uint32_t block = 1;
  while (true) {
    if (stop && stop->load()) {
      result.stopped = true;
      break;
    }
    uint32_t target = budget.spp > 0 ? std::min(budget.spp, stop ? done + block : budget.spp)
                                     : std::min(budget.max_spp, done + block);
    if (target <= done) break;
    arena.execute([&] {
      tbb::parallel_for(size_t(0), rects.size(), [&](size_t t) {
        renderer.render_tile(rects[t], budget.first_pass + done, budget.first_pass + target,
                             result.tiles[t]);
      });
    });
    done = target;
    double spent = process_cpu_seconds() - cpu_start;
    if (inspect) inspect(result.tiles);
    if (progress) progress(done, spent);
    if ((budget.spp > 0 && done >= budget.spp) || done >= budget.max_spp) break;
    if (budget.spp > 0) {
      // Stoppable spp render: blocks of about kStoppableBlockSeconds, at most a tenth of the
      // budget.
      double wall_per_pass = wall() / done;
      block = uint32_t(std::clamp(kStoppableBlockSeconds / std::max(wall_per_pass, 1e-9), 1.0,
                                  std::max(1.0, std::ceil(budget.spp / 10.0))));
      continue;
    }
    // Pass blocks grow so the time check costs nothing, but never overshoot the budget much:
    // the next block is sized from the cost per pass so far.
    double per_pass = spent / done;
    if (spent + per_pass >= budget.seconds) break;
    double remaining_passes = (budget.seconds - spent) / std::max(per_pass, 1e-9);
    block = uint32_t(std::clamp(remaining_passes / 2, 1.0, double(std::max<uint32_t>(1, done))));
    if (stop)
      block = std::min(block, uint32_t(std::max(1.0, kStoppableBlockSeconds * done / wall())));
  }
  result.spp = done;
  result.compute_seconds = process_cpu_seconds() - cpu_start;
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.film = assemble_film(camera.width, camera.height, result.tiles);
  return result;
}

}  // namespace penumbra
