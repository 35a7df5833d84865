#include "core/scene/pbrt_integrator.h"

#include <cmath>

namespace penumbra {

namespace {

struct SeedStrategy {
  std::string text;  // a penumbra/method@1 STRATEGY[:DIR]
  bool is_line = false;
};

// One of pointline's strategy1..3 with its angle#: the seed's strategies and Penumbra's.
SeedStrategy seed_strategy(PbrtParams& params, int index) {
  std::string key = "strategy" + std::to_string(index);
  std::string name = params.string(key, "none");
  double angle = params.number("angle" + std::to_string(index), 0);
  // importance#: surface-area line offsets proportional to the segment length (the seed's
  // default) or uniform. Lines along a rectangle's edge all have the same length, so the two
  // are the same distribution for every line direction Penumbra samples.
  params.ignore("importance" + std::to_string(index));
  if (name == "none") return {};
  if (name == "pt-surf-area") return {"area", false};
  if (name == "pt-solid-angle") return {"sa", false};
  if (name == "brdf") return {"bsdf", false};
  if (name == "line-surf-area") {
    // The seed's surface-area angle is the direction of its line offsets, angle * pi from the
    // light's u edge; each line runs across it (Quad::LineSample: offsets along x, segments along
    // y = x cross n). Angle 0 draws lines along v, angle 0.5 lines along u (on the seed's Cornell
    // box, its angle-0 render has the per-sample variance of line-area:v, 1.009 +- 0.012 of it,
    // and 0.83 of line-area:u's: tests/reproduce/seed_variance_test.cpp).
    double turns = angle - std::floor(angle);
    if (turns == 0) return {"line-area:v", true};
    if (turns == 0.5) return {"line-area:u", true};
    const PbrtParameter* parameter = params.find("angle" + std::to_string(index));
    params.fail(*parameter, "surface-area lines at angle " + std::to_string(angle) +
                                " pi are not along an edge of the light; Penumbra draws lines "
                                "along edge2 (angle 0: the seed's angle is the direction of its "
                                "line offsets) or edge1 (angle 0.5) only");
  }
  if (name == "line-solid-angle") {
    // The seed passes the angle to its spherical-rectangle line sampler as an integer: 1 selects
    // lines along v, anything else lines along u.
    return {static_cast<int>(angle) == 1 ? "line-sa:v" : "line-sa:u", true};
  }
  params.fail(*params.find(key), "unknown strategy '" + name +
                                     "' (the seed's are pt-surf-area, pt-solid-angle, brdf, "
                                     "line-surf-area, line-solid-angle)");
}

std::string term(int count, const std::string& strategy) {
  if (count == 1) return strategy;
  std::string text = std::to_string(count);
  text += '*';
  text += strategy;
  return text;
}

void map_pointline(PbrtParams& params, int n, SceneRenderDefaults& defaults, int& max_depth,
                   std::vector<std::string>& warnings) {
  std::string mode = params.string("method", "render");
  if (mode != "render")
    params.fail(*params.find("method"), "the seed's '" + mode +
                                            "' mode is a visualisation; Penumbra renders "
                                            "(method \"render\") only");
  std::vector<SeedStrategy> strategies;
  for (int i = 1; i <= 3; ++i) {
    SeedStrategy s = seed_strategy(params, i);
    if (!s.text.empty()) strategies.push_back(s);
  }
  if (strategies.empty())
    params.fail("strategy1 is required (the seed refuses a pointline integrator without one)");
  bool stratified = params.boolean("stratified", false);
  bool mis = params.boolean("mis", true);
  double ratio = params.number("ratio", 0.5);
  double smoothstep = params.number("smoothstep", 0);
  max_depth = static_cast<int>(params.integer("maxdepth", 1));
  defaults.seconds = std::max(0.0, params.number("max-seconds", -1));
  if (params.has("max-traversals")) {
    params.ignore("max-traversals");
    warnings.push_back(params.statement().location.str() +
                       ": pointline \"max-traversals\" ignored (Penumbra budgets by samples or "
                       "compute seconds)");
  }

  // How the seed divides a light's xsamples * ysamples samples between its strategies.
  const int k = static_cast<int>(strategies.size());
  std::vector<int> counts(k, n);
  if (n == 1) {
    counts.assign(k, 1);  // one sample of each strategy
  } else if (k == 2) {
    if (stratified) {
      counts = {n / 2, n - n / 2};
    } else {
      int first = static_cast<int>(std::floor(ratio * n));
      counts = {first, n - first};
    }
  } else if (k == 3) {
    if (stratified) {
      counts = {n / 3, n / 3, n - 2 * (n / 3)};
    } else {
      int first = static_cast<int>(std::ceil(ratio * n));
      counts = {first, first, n - 2 * first};
    }
  }
  std::string method;
  int kept = 0;
  for (int i = 0; i < k; ++i) {
    if (counts[i] < 0)
      params.fail(*params.find("ratio"),
                  "ratio " + std::to_string(ratio) + " leaves a negative sample count");
    if (counts[i] == 0) continue;
    if (!method.empty()) method += '+';
    method += term(counts[i], strategies[i].text);
    ++kept;
  }
  if (method.empty()) params.fail("no strategy is left with a sample");
  if (kept > 1) {
    if (!mis) {
      method += "/avg";
    } else if (smoothstep != 0) {
      method += "/smooth";
      warnings.push_back(params.statement().location.str() + ": pointline \"smoothstep\" width " +
                         std::to_string(smoothstep) +
                         " replaced by Penumbra's discontinuity smoothing (width half the "
                         "light's shorter side, narrowed next to occluders; Salesin & Jarosz "
                         "Eq. 22-24)");
    } else {
      method += "/balance";
    }
  }
  if (stratified && n > 1 && k > 1)
    warnings.push_back(params.statement().location.str() +
                       ": pointline \"stratified\": the light samples are split " +
                       "between the strategies in fixed counts (the seed splits one "
                       "stratified array by its first coordinate)");
  defaults.method = method;
}

}  // namespace

void map_pbrt_integrator(PbrtParams& params, int light_samples, SceneRenderDefaults& defaults,
                         int& max_depth, std::vector<std::string>& warnings) {
  const std::string type = params.statement().arguments[0].text;
  const std::string where = params.statement().location.str();
  const int n = std::max(1, light_samples);
  if (type == "pointline") {
    map_pointline(params, n, defaults, max_depth, warnings);
  } else if (type == "directlighting") {
    // pbrt-v3: per light, its samples from the light (uniform over the shape's area) and as many
    // from the BSDF, combined by the power heuristic.
    std::string strategy = params.string("strategy", "all");
    if (strategy != "all")
      warnings.push_back(where + ": directlighting strategy \"" + strategy +
                         "\" (one light chosen at random per sample) rendered as \"all\" (every "
                         "light, same expectation)");
    max_depth = static_cast<int>(params.integer("maxdepth", 5));
    defaults.method = term(n, "area") + "+" + term(n, "bsdf") + "/power";
  } else if (type == "path" || type == "whitted") {
    max_depth = static_cast<int>(params.integer("maxdepth", 5));
    defaults.method = term(n, "area") + "+" + term(n, "bsdf") + "/power";
    warnings.push_back(where + ": Integrator \"" + type +
                       "\": rendered as direct illumination (Penumbra's only light transport; "
                       "indirect light is omitted) with " +
                       defaults.method);
  } else {
    warnings.push_back(where + ": Integrator \"" + type +
                       "\" is not modelled; the scene states no default method (give --method)");
    for (const PbrtParameter& parameter : params.statement().parameters)
      params.ignore(parameter.name);
    return;
  }
  if (max_depth < 1) params.fail(*params.find("maxdepth"), "maxdepth must be at least 1");
  if (params.has("pixelbounds"))
    params.fail(*params.find("pixelbounds"), "pixel bounds are not modelled (use Film cropwindow)");
}

}  // namespace penumbra
