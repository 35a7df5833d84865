// A real batch (six repeats of two methods rendered locally on a small scene) measured against
// a short reference and against one 16x deeper: the corrected MRSEs agree within their 95%
// intervals, the plain ones do not: against the short reference every run's plain MRSE is
// higher, significantly (paired by repeat), by its noise.

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "core/image/noise_corrected_mrse.h"
#include "core/render/local_render.h"
#include "core/report/significance.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

// A floor under a small floating plate and a quad light: a penumbra without umbra (from every
// floor point the plate hides at most a quarter of the light). The errors are measured over the
// floor around the shadow, away from the floor's far edge, whose pixels are partly background
// and so nearly black: MRSE would be ruled by their tiny denominators.
const char* kSceneJson = R"({
  "format": "penumbra/scene@1", "name": "deeper-reference-test",
  "camera": { "position": [0, 0.8, 2.2], "look_at": [0, 0, 0], "up": [0, 1, 0],
              "fov_y_deg": 50, "width": 64, "height": 48 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "quad", "origin": [-0.06, 0.45, -0.06], "edge1": [0.12, 0, 0], "edge2": [0, 0, 0.12], "material": "white" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";

const Region kFloor{4, 27, 60, 47};
constexpr uint64_t kRepeats = 6;

Film render(const std::shared_ptr<const Scene>& scene, const std::string& method, uint64_t seed,
            uint32_t spp) {
  Renderer renderer(scene, RenderOptions{method, Pattern::Stratified, seed});
  RenderBudget budget;
  budget.spp = spp;
  return render_local(renderer, budget, 2).film;
}

TEST(DeeperReference, CorrectedMrseAgreesWithinIntervalsPlainDoesNot) {
  auto scene = std::make_shared<const Scene>(parse_scene(kSceneJson, "."));
  const Film shallow = render(scene, "bsdf+sa", 1000, 64);
  const Film deep = render(scene, "bsdf+sa", 2000, 16 * 64);
  for (const char* method : {"sa", "area"}) {
    std::vector<double> corrected_shallow, corrected_deep, plain_shallow, plain_deep;
    double deviation_shallow = 0, deviation_deep = 0;
    for (uint64_t repeat = 0; repeat < kRepeats; ++repeat) {
      const Film run = render(scene, method, 1 + repeat, 16);
      NoiseCorrectedError a =
          noise_corrected_mrse(run.color, shallow.color, shallow.variance, kFloor);
      NoiseCorrectedError b = noise_corrected_mrse(run.color, deep.color, deep.variance, kFloor);
      corrected_shallow.push_back(a.corrected);
      corrected_deep.push_back(b.corrected);
      plain_shallow.push_back(a.plain);
      plain_deep.push_back(b.plain);
      deviation_shallow = a.reference_deviation;
      deviation_deep = b.reference_deviation;
    }
    const MeanInterval cs = mean_interval(corrected_shallow, deviation_shallow);
    const MeanInterval cd = mean_interval(corrected_deep, deviation_deep);
    const MeanInterval ps = mean_interval(plain_shallow), pd = mean_interval(plain_deep);
    std::printf(
        "%s: corrected %.4g [%.4g, %.4g] (64 spp ref) vs %.4g [%.4g, %.4g] (1024 spp); plain %.4g "
        "[%.4g, %.4g] vs %.4g [%.4g, %.4g]\n",
        method, cs.mean, cs.lower(), cs.upper(), cd.mean, cd.lower(), cd.upper(), ps.mean,
        ps.lower(), ps.upper(), pd.mean, pd.lower(), pd.upper());
    // Corrected: the intervals overlap.
    EXPECT_LE(cs.lower(), cd.upper()) << method;
    EXPECT_LE(cd.lower(), cs.upper()) << method;
    // Plain: the short reference's is higher in every repeat, significantly (paired by repeat:
    // the same runs against both references), by about the short reference's own term.
    const PairedDifference plain = paired_difference(plain_shallow, plain_deep);
    const PairedDifference corrected = paired_difference(corrected_shallow, corrected_deep);
    std::printf("%s: plain shallow - deep %.4g +- %.4g (p %.3g); corrected %.4g +- %.4g (p %.3g)\n",
                method, plain.difference, plain.half_width, plain.p_value, corrected.difference,
                corrected.half_width, corrected.p_value);
    EXPECT_EQ(plain.sign, 1) << method;
    EXPECT_EQ(corrected.sign, 0) << method;
  }
}

}  // namespace
}  // namespace penumbra
