// The renderer and the probe: determinism across threads and pass splits, lights seen directly,
// the probe's statistics against a closed form, finite images in stress scenes.
#include "core/render/renderer.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/math/lambert_polygon.h"
#include "core/render/film.h"
#include "core/render/local_render.h"
#include "core/render/probe.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

// A floor, a floating occluder and a quad light facing down; camera looking at the floor.
const char* kSceneJson = R"({
  "format": "penumbra/scene@1", "name": "render-test",
  "camera": { "position": [0, 1.2, 2.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 50, "width": 48, "height": 40 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] },
                 "shiny": { "type": "phong", "kd": [0.2, 0.2, 0.2], "ks": [0.5, 0.5, 0.5], "exponent": 40 },
                 "metal": { "type": "ggx", "diffuse": [0.05, 0.05, 0.05], "specular": [0.9, 0.9, 0.9], "roughness": 0.2 } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "box", "min": [-0.2, 0.4, -0.2], "max": [0.2, 0.45, 0.2], "material": "shiny" },
    { "type": "sphere", "center": [0.5, 0.2, 0.3], "radius": 0.2, "subdivisions": 2, "material": "metal" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";

std::shared_ptr<const Scene> test_scene(const char* json = kSceneJson) {
  return std::make_shared<const Scene>(parse_scene(json, "."));
}

TileAccumulator render_with_threads(const Renderer& renderer, const TileRect& rect, int threads,
                                    uint32_t begin, uint32_t end) {
  TileAccumulator tile(rect);
  tbb::task_arena arena(threads);
  arena.execute([&] { renderer.render_tile(rect, begin, end, tile); });
  return tile;
}

TEST(Renderer, TileIsBitIdenticalWithOneAndTwoThreadsTwice) {
  auto scene = test_scene();
  for (const char* method : {"sa", "bsdf+sa/power", "area+bsdf/avg"}) {
    Renderer renderer(scene, RenderOptions{method, Pattern::Cmj, 11});
    TileRect rect{8, 4, 40, 36};
    TileAccumulator reference = render_with_threads(renderer, rect, 1, 0, 6);
    EXPECT_TRUE(render_with_threads(renderer, rect, 1, 0, 6) == reference) << method;
    EXPECT_TRUE(render_with_threads(renderer, rect, 2, 0, 6) == reference) << method;
    EXPECT_TRUE(render_with_threads(renderer, rect, 2, 0, 6) == reference) << method;
    // Split into pass ranges and merged: the same bits.
    TileAccumulator split = render_with_threads(renderer, rect, 2, 4, 6);
    split.merge(render_with_threads(renderer, rect, 1, 0, 1));
    split.merge(render_with_threads(renderer, rect, 2, 1, 4));
    EXPECT_TRUE(split == reference) << method;
    // Another seed renders other bits.
    Renderer other(scene, RenderOptions{method, Pattern::Cmj, 12});
    EXPECT_FALSE(render_with_threads(other, rect, 2, 0, 6) == reference);
  }
}

TEST(Renderer, LocalRenderEqualsTheSameTilesMergedAnyWay) {
  auto scene = test_scene();
  Renderer renderer(scene, RenderOptions{"bsdf+sa", Pattern::Stratified, 3});
  RenderBudget budget;
  budget.spp = 5;
  LocalRenderResult a = render_local(renderer, budget, 2, 16);
  LocalRenderResult b = render_local(renderer, budget, 1, 7);  // other tiles
  EXPECT_EQ(a.spp, 5u);
  EXPECT_EQ(a.film.color.rgb, b.film.color.rgb);
  EXPECT_EQ(a.film.variance.rgb, b.film.variance.rgb);
  EXPECT_EQ(a.film.min_spp, 5u);
  EXPECT_EQ(a.film.nonfinite_samples, 0u);
}

TEST(Renderer, SecondsBudgetStopsAtAPassBoundary) {
  auto scene = test_scene();
  Renderer renderer(scene, RenderOptions{"sa", Pattern::Random, 0});
  RenderBudget budget;
  budget.seconds = 0.3;
  LocalRenderResult r = render_local(renderer, budget, 1, 16);
  EXPECT_GE(r.spp, 1u);
  EXPECT_EQ(r.film.min_spp, r.spp);
  EXPECT_EQ(r.film.max_spp, r.spp);
}

TEST(Renderer, RefusesMethodsItCannotRun) {
  auto scene = test_scene();
  EXPECT_THROW(Renderer(scene, RenderOptions{"line-sa:rand", Pattern::Random, 0}), FormatError);
  EXPECT_THROW(Renderer(scene, RenderOptions{"nope", Pattern::Random, 0}), FormatError);
}

TEST(Renderer, CutTilesCoversTheImageOnce) {
  std::vector<int> covered(50 * 37, 0);
  for (const TileRect& t : cut_tiles(50, 37, 16))
    for (int y = t.y0; y < t.y1; ++y)
      for (int x = t.x0; x < t.x1; ++x) covered[y * 50 + x]++;
  for (int c : covered) EXPECT_EQ(c, 1);
  EXPECT_THROW(cut_tiles(10, 10, 0), std::invalid_argument);
}

TEST(Probe, PixelOnTheLightHasItsRadianceAndNoVariance) {
  // Camera looking straight up at the light from below, past the occluder's edge (|x|,|z| <= 0.2).
  std::string json = kSceneJson;
  json.replace(json.find("\"position\": [0, 1.2, 2.5]"), 25, "\"position\": [0.23, 0.1, 0.23]");
  json.replace(json.find("\"look_at\": [0, 0.3, 0]"), 22, "\"look_at\": [0.23, 1.0, 0.23]");
  json.replace(json.find("\"up\": [0, 1, 0]"), 15, "\"up\": [0, 0, 1]");
  auto scene = test_scene(json.c_str());
  ProbeSpec probe = parse_probe(R"({"format": "penumbra/probe@1", "pixels": [[24, 20]]})");
  std::vector<int> counts{1, 4};
  ProbeResult result = run_probe(scene, probe, "sa", Pattern::Random, counts, 8, 0);
  ASSERT_EQ(result.points.size(), 1u);
  for (const ProbeRun& run : result.points[0]) {
    EXPECT_DOUBLE_EQ(run.mean.x, 5.0);
    EXPECT_DOUBLE_EQ(run.variance.x, 0.0);
  }
}

TEST(Probe, UnoccludedPointMatchesTheClosedFormAndVarianceFallsWithN) {
  auto scene = test_scene();
  // A point on the floor outside the occluder's shadow? Use a point above the box: unoccluded.
  ProbeSpec probe = parse_probe(R"({"format": "penumbra/probe@1",
      "points": [{"position": [0, 0.46, 0], "normal": [0, 1, 0], "wo": [0, 1, 1], "material": "white"}]})");
  std::vector<int> counts{1, 4, 16, 64};
  ProbeResult result = run_probe(scene, probe, "area", Pattern::Random, counts, 400, 5);
  const Light& light = scene->lights[0];
  double expected = lambert_polygon_radiance({0.8, 0.8, 0.8}, light.radiance, {0, 0.46, 0},
                                             {0, 1, 0}, light.vertices, light.normal)
                        .x;
  const auto& runs = result.points[0];
  for (const ProbeRun& run : runs) {
    double standard_error = std::sqrt(run.variance.x / 400);
    EXPECT_NEAR(run.mean.x, expected, 4 * standard_error) << "n = " << run.n;
  }
  // Random sampling: variance ~ 1/N (slope -1 within sampling noise of 400 trials).
  double slope = std::log(runs.back().variance.x / runs.front().variance.x) / std::log(64.0);
  EXPECT_NEAR(slope, -1.0, 0.2);
  std::string json = probe_result_json(result);
  EXPECT_NE(json.find("penumbra/probe-result@1"), std::string::npos);
  EXPECT_NE(json.find("seconds_per_estimate"), std::string::npos);
  // Each point says what it is and its convergence slope (least squares over the four n).
  auto document = nlohmann::json::parse(json);
  const auto& point = document["points"][0];
  EXPECT_EQ(point["position"], nlohmann::json::array({0, 0.46, 0}));
  EXPECT_EQ(point["material"], "white");
  ASSERT_TRUE(point["variance_slope"][0].is_number());
  EXPECT_NEAR(point["variance_slope"][0].get<double>(), -1.0, 0.2);
  // The fit itself: exactly -1 for variance 1/n, undefined for one run or zero variances.
  std::vector<ProbeRun> exact(3);
  for (int k = 0; k < 3; ++k) {
    exact[k].n = 1 << (2 * k);
    exact[k].variance = Rgb(1.0 / exact[k].n, 0, 2.0 / exact[k].n);
  }
  EXPECT_NEAR(*variance_slope(exact, 0), -1.0, 1e-12);
  EXPECT_FALSE(variance_slope(exact, 1).has_value());
  EXPECT_FALSE(variance_slope({exact[0]}, 2).has_value());
}

TEST(Probe, PixelEntriesNameTheirPixel) {
  auto scene = test_scene();
  ProbeSpec probe = parse_probe(R"({"format": "penumbra/probe@1", "pixels": [[3, 5]],
      "points": [{"position": [0, 0.46, 0], "normal": [0, 1, 0], "wo": [0, 1, 1], "material": "white"}]})");
  std::vector<int> counts{1, 2};
  auto document = nlohmann::json::parse(
      probe_result_json(run_probe(scene, probe, "sa", Pattern::Random, counts, 4, 1)));
  ASSERT_EQ(document["points"].size(), 2u);
  EXPECT_EQ(document["points"][0]["pixel"], nlohmann::json::array({3, 5}));
  EXPECT_FALSE(document["points"][0].contains("position"));
  EXPECT_EQ(document["points"][1]["material"], "white");
}

TEST(Probe, BadInputGetsItsError) {
  auto scene = test_scene();
  EXPECT_THROW(parse_probe("{"), FormatError);
  EXPECT_THROW(parse_probe(R"({"format": "penumbra/probe@2", "pixels": [[0,0]]})"), FormatError);
  EXPECT_THROW(parse_probe(R"({"format": "penumbra/probe@1"})"), FormatError);
  EXPECT_THROW(parse_probe(R"({"format": "penumbra/probe@1", "pixels": [[0]]})"), FormatError);
  try {
    parse_probe(
        R"({"format": "penumbra/probe@1", "points": [{"position": [0,0,0], "normal": [0,1,0], "wo": [0,1,0]}]})");
    ADD_FAILURE();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.json_path(), "$.points[0].material");
  }
  std::vector<int> counts{1};
  ProbeSpec outside = parse_probe(R"({"format": "penumbra/probe@1", "pixels": [[48, 0]]})");
  EXPECT_THROW(run_probe(scene, outside, "sa", Pattern::Random, counts, 4, 0), FormatError);
  ProbeSpec unknown = parse_probe(R"({"format": "penumbra/probe@1",
      "points": [{"position": [0,0,0], "normal": [0,1,0], "wo": [0,1,0], "material": "gold"}]})");
  EXPECT_THROW(run_probe(scene, unknown, "sa", Pattern::Random, counts, 4, 0), FormatError);
}

TEST(Renderer, StressScenesRenderFiniteImages) {
  // A 1 cm light 40 m above a floor and a 1 mm one, an occluder close to the floor.
  const char* json = R"({
    "format": "penumbra/scene@1", "name": "stress",
    "camera": { "position": [0, 1, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 60,
                "width": 24, "height": 24 },
    "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] },
                   "glossy": { "type": "ggx", "diffuse": [0, 0, 0], "specular": [1, 1, 1], "roughness": 0.0001 },
                   "sharp": { "type": "phong", "kd": [0, 0, 0], "ks": [1, 1, 1], "exponent": 10000 } },
    "shapes": [
      { "type": "quad", "origin": [-2, 0, -2], "edge1": [4, 0, 0], "edge2": [0, 0, 4], "material": "white" },
      { "type": "box", "min": [-0.5, 0.01, -0.5], "max": [0.0, 0.02, 0.0], "material": "glossy" },
      { "type": "box", "min": [0.2, 0.0, 0.2], "max": [0.6, 0.3, 0.6], "material": "sharp" }
    ],
    "lights": [
      { "type": "quad", "origin": [-0.005, 40, -0.005], "edge1": [0.01, 0, 0], "edge2": [0, 0, 0.01], "radiance": [1e7, 1e7, 1e7] },
      { "type": "quad", "origin": [1, 40, 1], "edge1": [0.001, 0, 0], "edge2": [0, 0, 0.001], "radiance": [1e9, 1e9, 1e9] },
      { "type": "disk", "center": [0, 0.5, -1.5], "normal": [0, 0, 1], "radius": 0.2, "radiance": [3, 3, 3] }
    ]
  })";
  auto scene = test_scene(json);
  for (const char* method : {"area", "sa", "bsdf", "bsdf+sa", "bsdf+sa/power", "area+sa/avg"}) {
    Renderer renderer(scene, RenderOptions{method, Pattern::Stratified, 1});
    RenderBudget budget;
    budget.spp = 4;
    LocalRenderResult r = render_local(renderer, budget, 2, 8);
    EXPECT_EQ(r.film.nonfinite_samples, 0u) << method;
    for (float v : r.film.color.rgb) ASSERT_TRUE(std::isfinite(v)) << method;
  }
}

}  // namespace
}  // namespace penumbra
