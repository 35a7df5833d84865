// `penumbra verify` over every bundled scene: each shipped method (every strategy, every line
// direction, every combination) renders 4 independent runs at a short budget on the scene at 32
// pixels across, z-tested per 8x8 block against the scene's exact reference (closed form on the
// Lambertian surfaces under constant polygonal lights, `bsdf+sa` with 64 samples per term and
// camera sample elsewhere; 32 camera samples per pixel, 16 where the closed form costs more). No
// block may be beyond 5 sigma; a method the estimator refuses on a scene (line-bd16 on GGX, Peters'
// combinations on a disk light, ...) is skipped with its reason, and every method must run on some
// scene. core/analysis/verify.h for the statistics; tests/core/analysis/verify_test.cpp shows the
// check catches a wrong pdf at this budget.
//
// Statistical and long (a few seconds per scene): run in the Release pass only.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/analysis/verify.h"
#include "core/render/renderer.h"

namespace penumbra {
namespace {

// The shipped methods: each strategy alone (line strategies along u, v and at random), and
// each combination heuristic with the terms it is meant for.
const std::vector<std::string>& shipped_methods() {
  static const std::vector<std::string> methods = {"bsdf",
                                                   "area",
                                                   "sa",
                                                   "psa",
                                                   "ltc",
                                                   "line-area:u",
                                                   "line-area:v",
                                                   "line-sa:u",
                                                   "line-sa:v",
                                                   "line-bd16:u",
                                                   "line-bd16:rand",
                                                   "bsdf+sa/balance",
                                                   "bsdf+area/power",
                                                   "bsdf+psa/avg",
                                                   "bsdf+line-sa:v/balance",
                                                   "bsdf+line-sa:v/smooth",
                                                   "bsdf+line-area:u/smooth-fixed",
                                                   "psa+ltc/weighted",
                                                   "psa+ltc/clamped-optimal",
                                                   "2*bsdf+line-sa:u+line-sa:v/power"};
  return methods;
}

// How each scene is checked. The exact reference is the default; grid-planes gets a deep `sa`
// render instead (its exact reference costs 3 ms per camera sample: the union of ~130 bar
// shadows per point). `skip`: methods whose check is not meaningful on the scene at this budget,
// with the reason.
struct SceneCase {
  std::string name;
  std::string deep_reference_method;  // empty: the exact reference
  std::map<std::string, std::string> skip;
  uint32_t camera_samples = 32;  // of the exact reference (fewer where it costs more)
};
void PrintTo(const SceneCase& c, std::ostream* out) {
  *out << c.name;
}

const std::vector<SceneCase>& scene_cases() {
  // distant-light's lights subtend 6e-8 and 6e-10 sr: BSDF sampling finds them about once per
  // 10^7 samples, so its runs are all zero (`bsdf` is reported inconclusive) and `avg` gives
  // half the light (its BSDF half is all zero, its psa half has no noise).
  const std::string tiny = "a light of 6e-8 sr: BSDF samples never find it at this budget";
  // grids-linear's light is a 1 x 0.005 strip: BSDF samples find it once in a few thousand.
  const std::string thin = "a 1 x 0.005 light: BSDF samples rarely find it at this budget";
  static const std::vector<SceneCase> cases = {
      {"cornell-box", "", {}},
      {"cornell-occluders", "", {}},
      {"distant-light", "", {{"bsdf", tiny}, {"bsdf+psa/avg", tiny}}},
      {"glossy-strips", "", {}},
      {"grid-planes", "sa", {}},
      {"grids-linear", "", {{"bsdf", thin}, {"bsdf+psa/avg", thin}}},
      {"monoliths", "", {}},
      {"occluded-planes", "", {}},
      {"pentagon-room", "", {}},
      {"polygon-cornell", "", {}},
      {"quad-over-floor", "", {}},
      {"spheres-plane-disk", "", {}},
      {"spheres-plane-gaussian", "", {}},
      {"spheres-plane-square", "", {}, 16},
      {"thin-fibers", "", {}},
      {"triangle-soup", "", {}, 16},
      {"veach-occluders", "", {}}};
  return cases;
}

class VerifyShippedMethods : public ::testing::TestWithParam<SceneCase> {};

TEST_P(VerifyShippedMethods, NoBlockBiasedBeyondFiveSigma) {
  const SceneCase& c = GetParam();
  const auto start = std::chrono::steady_clock::now();
  const std::string path = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + c.name + ".json";
  auto scene = std::make_shared<const Scene>(scene_at_width(load_scene(path), 32));
  VerifyReference reference;
  if (c.deep_reference_method.empty()) {
    ExactReferenceOptions options;
    options.camera_samples = c.camera_samples;
    options.threads = 1;
    reference = render_verify_reference(scene, options);
  } else {
    reference =
        render_deep_reference(scene, c.deep_reference_method, Pattern::Stratified, 256, 0x5eed, 1);
  }
  int ran = 0;
  double worst = 0;
  std::string worst_method, refused, skipped;
  for (const std::string& method : shipped_methods()) {
    if (c.skip.count(method)) {
      skipped += " " + method;
      continue;
    }
    // BSDF samples find small lights rarely: where they are not MIS-weighted (`bsdf` alone,
    // `avg`, whose other half may have no noise at all: psa on an unoccluded Lambertian
    // receiver) they need more samples for the block means to be close to normal.
    const bool unweighted_bsdf = method == "bsdf" || method.find("/avg") != std::string::npos;
    RenderBudget budget;
    budget.spp = unweighted_bsdf ? 64 : 8;
    RunRenderer runs;
    try {
      runs = method_run_renderer(scene, method, Pattern::Stratified, budget, 1);
    } catch (const FormatError& e) {
      refused += " " + method;
      continue;
    }
    VerifyResult result = verify_runs(reference, 4, 1, runs);
    EXPECT_TRUE(result.check.passed() && result.check.inconclusive.empty())
        << c.name << ": " << bias_check_text(result.check, method);
    ++ran;
    if (std::abs(result.check.worst.z) > std::abs(worst)) {
      worst = result.check.worst.z;
      worst_method = method;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%s: %d methods, largest |z| %.2f (%s); reference: %s; refused:%s; skipped:%s; %.1f s\n",
      c.name.c_str(), ran, std::abs(worst), worst_method.c_str(), reference.description.c_str(),
      refused.empty() ? " none" : refused.c_str(), skipped.empty() ? " none" : skipped.c_str(),
      seconds);
  EXPECT_GT(ran, 0);
}

// Every shipped method runs on some bundled scene (so the scenes' checks cover it).
TEST(VerifyShippedMethodsCover, EveryMethodRunsOnSomeScene) {
  std::vector<std::shared_ptr<const Scene>> scenes;
  for (const SceneCase& c : scene_cases())
    scenes.push_back(std::make_shared<const Scene>(scene_at_width(
        load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + c.name + ".json"), 8)));
  for (const std::string& method : shipped_methods()) {
    bool runs = false;
    for (size_t i = 0; i < scenes.size() && !runs; ++i) {
      if (scene_cases()[i].skip.count(method)) continue;
      try {
        Renderer renderer(scenes[i], RenderOptions{method, Pattern::Stratified, 0});
        runs = true;
      } catch (const FormatError&) {
      }
    }
    EXPECT_TRUE(runs) << method << " runs on no bundled scene";
  }
}

INSTANTIATE_TEST_SUITE_P(BundledScenes, VerifyShippedMethods, ::testing::ValuesIn(scene_cases()),
                         [](const ::testing::TestParamInfo<SceneCase>& info) {
                           std::string name = info.param.name;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace penumbra
