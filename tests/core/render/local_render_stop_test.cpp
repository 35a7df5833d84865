// render_local with a stop flag: an spp render in bounded pass blocks gives the same bits as one
// block, and a stop requested mid-render ends at a block boundary with whole passes, the same
// bits as a render of exactly that many passes.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>

#include "core/render/local_render.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

const char* kScene = R"({
  "format": "penumbra/scene@1", "name": "stop-test",
  "camera": { "position": [0, 1.2, 2.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 50, "width": 24, "height": 16 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "box", "min": [-0.2, 0.4, -0.2], "max": [0.2, 0.45, 0.2], "material": "white" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";

LocalRenderResult render(uint32_t spp, const std::atomic<bool>* stop,
                         const std::function<void(uint32_t, double)>& progress = {}) {
  auto scene = std::make_shared<const Scene>(parse_scene(kScene, "."));
  Renderer renderer(scene, RenderOptions{"sa", Pattern::Stratified, 3});
  RenderBudget budget;
  budget.spp = spp;
  return render_local(renderer, budget, 2, 8, progress, stop);
}

TEST(LocalRenderStop, BlocksGiveTheBitsOfOneBlock) {
  std::atomic<bool> stop{false};
  int blocks = 0;
  LocalRenderResult blocked = render(40, &stop, [&](uint32_t, double) { ++blocks; });
  LocalRenderResult whole = render(40, nullptr);
  EXPECT_FALSE(blocked.stopped);
  EXPECT_EQ(blocked.spp, 40u);
  EXPECT_GE(blocks, 5);  // blocks of at most a tenth of the budget (4 passes) after the first
  EXPECT_EQ(blocked.film.color.rgb, whole.film.color.rgb);
  EXPECT_EQ(blocked.film.variance.rgb, whole.film.variance.rgb);
}

TEST(LocalRenderStop, StopEndsAtABlockBoundaryWithWholePasses) {
  std::atomic<bool> stop{false};
  LocalRenderResult partial = render(1000, &stop, [&](uint32_t passes, double) {
    if (passes >= 3) stop = true;
  });
  EXPECT_TRUE(partial.stopped);
  EXPECT_GE(partial.spp, 3u);
  EXPECT_LT(partial.spp, 1000u);
  EXPECT_EQ(partial.film.min_spp, partial.spp);
  EXPECT_EQ(partial.film.max_spp, partial.spp);
  LocalRenderResult exact = render(partial.spp, nullptr);
  EXPECT_EQ(partial.film.color.rgb, exact.film.color.rgb);
}

TEST(LocalRenderStop, StopBeforeTheFirstPassRendersNothing) {
  std::atomic<bool> stop{true};
  LocalRenderResult result = render(10, &stop);
  EXPECT_TRUE(result.stopped);
  EXPECT_EQ(result.spp, 0u);
}

}  // namespace
}  // namespace penumbra
