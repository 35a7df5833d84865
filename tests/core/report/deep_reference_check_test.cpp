// The depth check (core/report/deep_reference_check.h) on batch folders rendered here: three
// repeats of `sa` at 16 spp on a small scene, measured against a reference 16x deeper than the
// runs (256 spp, with its variance layer) pass against one 16x deeper still (4096 spp): every
// cell's corrected MRSE within 10%. The same runs against a 16-spp reference without a variance
// layer (nothing to correct) report more than 1.5 times their error, and the check fails them.

#include "core/report/deep_reference_check.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include "core/image/image.h"
#include "core/image/metrics.h"
#include "core/render/local_render.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

// A floor under a floating plate and a quad light: a soft shadow without umbra.
const char* kScene = R"({
  "format": "penumbra/scene@1", "name": "depth-check-test",
  "camera": { "position": [0, 0.8, 2.2], "look_at": [0, 0, 0], "up": [0, 1, 0],
              "fov_y_deg": 40, "width": 32, "height": 24 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "quad", "origin": [-0.08, 0.45, -0.08], "edge1": [0.16, 0, 0], "edge2": [0, 0, 0.16], "material": "white" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";
const Region kShadow{8, 12, 24, 23};

Film render(const std::shared_ptr<const Scene>& scene, const std::string& method, uint64_t seed,
            uint32_t spp) {
  Renderer renderer(scene, RenderOptions{method, Pattern::Stratified, seed});
  RenderBudget budget;
  budget.spp = spp;
  return render_local(renderer, budget, 2).film;
}

// A result folder: the runs and a reference (with its variance layer or without).
fs::path write_folder(const std::string& name, const std::shared_ptr<const Scene>& scene,
                      const std::vector<Film>& runs, const Film& reference, uint32_t reference_spp,
                      bool with_variance) {
  const fs::path dir = fs::path(PENUMBRA_BINARY_DIR) / "test-output" / "report" / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "runs");
  write_exr((dir / "reference.exr").string(), reference.color,
            with_variance ? &reference.variance : nullptr, {});
  const std::map<std::string, Region> regions = {{"shadow", kShadow}};
  nlohmann::json method = {{"label", "sa"},
                           {"method", "sa"},
                           {"sampler", "stratified"},
                           {"budget_seconds", nullptr},
                           {"runs", nlohmann::json::array()}};
  for (size_t r = 0; r < runs.size(); ++r) {
    const std::string exr = "runs/sa.spp16.r" + std::to_string(r) + ".exr";
    write_exr((dir / exr).string(), runs[r].color, &runs[r].variance, {});
    nlohmann::json errors = nlohmann::json::array();
    for (const auto& [region, summary] : error_summary(runs[r].color, reference.color, regions))
      errors.push_back({{"region", region},
                        {"mrse", summary.mrse},
                        {"mse", summary.mse},
                        {"rmse", summary.rmse}});
    method["runs"].push_back({{"repeat", r},
                              {"seed", 1 + r},
                              {"exr", exr},
                              {"spp", 16},
                              {"equal_time", false},
                              {"compute_seconds", 0.1},
                              {"errors", errors}});
  }
  nlohmann::json batch = {
      {"format", "penumbra/batch-result@1"},
      {"batch_id", "local"},
      {"name", name},
      {"spec", {{"format", "penumbra/batch@1"}}},
      {"scene",
       {{"name", scene->name}, {"hash", scene->content_hash}, {"width", 32}, {"height", 24}}},
      {"regions",
       {{{"name", "shadow"}, {"rect", {kShadow.x0, kShadow.y0, kShadow.x1, kShadow.y1}}}}},
      {"reference", {{"exr", "reference.exr"}, {"method", "bsdf+sa"}, {"spp", reference_spp}}},
      {"methods", {method}}};
  std::ofstream(dir / "batch.json") << batch.dump(2);
  return dir;
}

TEST(DeepReferenceCheck, ADeepEnoughReferencePassesAShallowUncorrectedOneFails) {
  auto scene = std::make_shared<const Scene>(parse_scene(kScene, "."));
  std::vector<Film> runs;
  for (uint64_t repeat = 0; repeat < 3; ++repeat)
    runs.push_back(render(scene, "sa", 1 + repeat, 16));
  const Film reference = render(scene, "bsdf+sa", 1000, 256);
  const Film shallow = render(scene, "sa", 3000, 16);  // as noisy as a run
  const Film deep = render(scene, "bsdf+sa", 2000, 4096);
  const fs::path deep_path = fs::path(PENUMBRA_BINARY_DIR) / "test-output" / "report" / "deep.exr";
  fs::create_directories(deep_path.parent_path());
  ImageMetadata metadata{{"spp", "4096"}};
  write_exr(deep_path.string(), deep.color, &deep.variance, metadata);

  const DeepCheck good = check_against_deep_reference(
      write_folder("depth-good", scene, runs, reference, 256, true), deep_path);
  std::printf("%s", deep_check_text(good).c_str());
  ASSERT_EQ(good.cells.size(), 2u);  // image and shadow
  EXPECT_TRUE(good.passed());
  EXPECT_EQ(good.deep_spp, 4096u);
  EXPECT_EQ(good.reference_spp, 256u);
  for (const DeepCheckCell& cell : good.cells) EXPECT_EQ(cell.repeats, 3);

  const DeepCheck bad = check_against_deep_reference(
      write_folder("depth-bad", scene, runs, shallow, 16, false), deep_path);
  std::printf("%s", deep_check_text(bad).c_str());
  EXPECT_FALSE(bad.passed());
  // Without a variance layer nothing is corrected: the reference's own noise adds to every
  // cell, more than the run's where it is dark (its near-zero pixels weigh 1 / (r^2 + 1e-6)).
  for (const DeepCheckCell& cell : bad.cells) EXPECT_GT(cell.ratio, 1.5) << cell.region;
  const nlohmann::json json = deep_check_json(bad);
  EXPECT_EQ(json["format"], "penumbra/depth-check@1");
  EXPECT_FALSE(json["passed"].get<bool>());
}

}  // namespace
}  // namespace penumbra
