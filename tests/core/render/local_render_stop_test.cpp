// render_local with a stop flag: an spp render in bounded pass blocks gives the same bits as one
// block, and a stop requested mid-render ends at a block boundary with whole passes, the same
// bits as a render of exactly that many passes. The sums of a render stopped part-way and of its
// remaining passes (first_pass, another tile size), through their files, merge into the bits of
// one whole render; the merge and the file reader refuse what does not fit, naming it.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>

#include "core/render/local_render.h"
#include "core/render/sums_file.h"
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
                         const std::function<void(uint32_t, double)>& progress = {},
                         uint32_t first_pass = 0, int tile = 8, uint64_t seed = 3) {
  auto scene = std::make_shared<const Scene>(parse_scene(kScene, "."));
  Renderer renderer(scene, RenderOptions{"sa", Pattern::Stratified, seed});
  RenderBudget budget;
  budget.spp = spp;
  budget.first_pass = first_pass;
  return render_local(renderer, budget, 2, tile, progress, stop);
}

// The sums of a render as `penumbra render --sums` writes them.
RenderSums sums_of(const LocalRenderResult& result, uint32_t first_pass, uint64_t seed = 3) {
  RenderSums sums;
  sums.width = 24;
  sums.height = 16;
  sums.first_pass = first_pass;
  sums.passes = result.spp;
  sums.compute_seconds = result.compute_seconds;
  sums.metadata = {{"penumbra:method", "sa"},
                   {"penumbra:sampler", "stratified"},
                   {"penumbra:seed", std::to_string(seed)},
                   {"penumbra:scene_hash", "abc"},
                   {"penumbra:spp", std::to_string(result.spp)}};
  if (result.stopped) sums.metadata["penumbra:interrupted"] = "yes";
  sums.sums = whole_image_sums(24, 16, result.tiles);
  return sums;
}

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no error)";
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

TEST(LocalRenderStop, StoppedAndRemainingPassesMergeIntoTheWholeRender) {
  // Stopped after a few passes; the rest from there with another tile size.
  std::atomic<bool> stop{false};
  LocalRenderResult partial = render(1000, &stop, [&](uint32_t passes, double) {
    if (passes >= 3) stop = true;
  });
  ASSERT_TRUE(partial.stopped);
  const uint32_t total = partial.spp + 9;
  LocalRenderResult rest = render(9, nullptr, {}, partial.spp, 5);
  EXPECT_EQ(rest.spp, 9u);
  // Through the file format, in either order.
  RenderSums first = decode_sums(encode_sums(sums_of(partial, 0)), "partial.sums");
  RenderSums second = decode_sums(encode_sums(sums_of(rest, partial.spp)), "rest.sums");
  EXPECT_EQ(first.passes, partial.spp);
  EXPECT_EQ(second.first_pass, partial.spp);
  RenderSums merged = merge_sums({second, first}, {"rest.sums", "partial.sums"});
  EXPECT_EQ(merged.first_pass, 0u);
  EXPECT_EQ(merged.passes, total);
  EXPECT_EQ(merged.metadata["penumbra:spp"], std::to_string(total));
  EXPECT_EQ(merged.metadata.count("penumbra:interrupted"), 0u);
  EXPECT_EQ(merged.metadata.count("penumbra:first_pass"), 0u);
  Film film = sums_film(merged);
  LocalRenderResult whole = render(total, nullptr);
  EXPECT_EQ(film.color.rgb, whole.film.color.rgb);
  EXPECT_EQ(film.variance.rgb, whole.film.variance.rgb);
  EXPECT_EQ(film.min_spp, total);
  // The rest alone is an image of its own passes (not of the first ones).
  EXPECT_NE(sums_film(second).color.rgb, render(9, nullptr).film.color.rgb);
}

TEST(LocalRenderStop, MergeRefusesOverlapsGapsAndOtherRenders) {
  RenderSums a = sums_of(render(4, nullptr), 0);
  RenderSums b = sums_of(render(3, nullptr, {}, 4), 4);
  RenderSums overlap = sums_of(render(3, nullptr, {}, 2), 2);
  RenderSums gap = sums_of(render(3, nullptr, {}, 5), 5);
  RenderSums other_seed = sums_of(render(3, nullptr, {}, 4, 8, 4), 4, 4);
  EXPECT_EQ(merge_sums({a, b}, {"a", "b"}).passes, 7u);
  EXPECT_EQ(error_of([&] {
              merge_sums({a, overlap}, {"a", "c"});
            }),
            "c (passes 2..5) overlaps a (passes 0..4): a pass would count twice");
  EXPECT_EQ(error_of([&] {
              merge_sums({a, gap}, {"a", "d"});
            }),
            "d (passes 5..8) does not follow a (passes 0..4): passes 4..5 are missing");
  EXPECT_EQ(error_of([&] {
              merge_sums({a, other_seed}, {"a", "e"});
            }),
            "e: penumbra:seed is 4, a has 3: not passes of one render");
  // A later range alone keeps its first pass.
  RenderSums later = merge_sums({b}, {"b"});
  EXPECT_EQ(later.metadata["penumbra:first_pass"], "4");
}

TEST(LocalRenderStop, SumsFileReaderNamesWhatIsWrong) {
  const std::string bytes = encode_sums(sums_of(render(2, nullptr), 0));
  EXPECT_EQ(decode_sums(bytes, "x.sums").passes, 2u);
  EXPECT_EQ(error_of([&] { decode_sums("PNG...", "x.sums"); }),
            "x.sums: not a sums file (penumbra/sums@1): it does not start with PNSUMS01");
  EXPECT_NE(error_of([&] {
              decode_sums(bytes.substr(0, bytes.size() - 1), "x.sums");
            }).find("x.sums: the body's length"),
            std::string::npos);
  EXPECT_NE(error_of([&] { decode_sums(bytes + "!", "x.sums"); }).find("x.sums: the body's length"),
            std::string::npos);
  // A header that claims other passes than the body's counts.
  std::string header_passes = bytes;
  const size_t at = header_passes.find("\"passes\":2");
  ASSERT_NE(at, std::string::npos);
  header_passes[at + 9] = '3';
  EXPECT_EQ(error_of([&] { decode_sums(header_passes, "x.sums"); }),
            "x.sums: body: pixel (0, 0) has 2 samples, the header says 3 passes");
  // The header's JSON broken.
  std::string broken = bytes;
  broken[12] = '[';
  EXPECT_EQ(error_of([&] { decode_sums(broken, "x.sums"); }),
            "x.sums: the header is not a JSON object");
}

}  // namespace
}  // namespace penumbra
