#include "core/render/probe.h"

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/render/camera.h"
#include "core/render/shading.h"

namespace penumbra {

namespace {

using json = nlohmann::json;

Vec3 read_vec3(const json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 3) throw FormatError(path, "expected [x, y, z]");
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!value[i].is_number()) throw FormatError(path, "expected numbers");
    v[i] = value[i].get<double>();
  }
  if (!is_finite(v)) throw FormatError(path, "coordinates must be finite");
  return v;
}

}  // namespace

ProbeSpec parse_probe(const std::string& text, const std::string& source) {
  json doc = json::parse(text, nullptr, false, false);
  if (doc.is_discarded()) throw FormatError("$", source + ": not valid JSON");
  if (!doc.is_object()) throw FormatError("$", source + ": expected an object");
  if (!doc.contains("format")) throw FormatError("$.format", "missing required key");
  if (doc["format"] != "penumbra/probe@1")
    throw FormatError("$.format",
                      "unknown format " + doc["format"].dump() + "; expected \"penumbra/probe@1\"");
  ProbeSpec probe;
  if (doc.contains("pixels")) {
    const json& pixels = doc["pixels"];
    if (!pixels.is_array()) throw FormatError("$.pixels", "expected an array of [x, y]");
    for (size_t i = 0; i < pixels.size(); ++i) {
      std::string path = "$.pixels[" + std::to_string(i) + "]";
      const json& p = pixels[i];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number_integer() || !p[1].is_number_integer())
        throw FormatError(path, "expected [x, y] integers");
      probe.pixels.emplace_back(p[0].get<int>(), p[1].get<int>());
    }
  }
  if (doc.contains("points")) {
    const json& points = doc["points"];
    if (!points.is_array()) throw FormatError("$.points", "expected an array");
    for (size_t i = 0; i < points.size(); ++i) {
      std::string path = "$.points[" + std::to_string(i) + "]";
      const json& p = points[i];
      if (!p.is_object()) throw FormatError(path, "expected an object");
      ProbePointSpec point;
      for (const char* key : {"position", "normal", "wo", "material"})
        if (!p.contains(key)) throw FormatError(path + "." + key, "missing required key");
      point.position = read_vec3(p["position"], path + ".position");
      point.normal = read_vec3(p["normal"], path + ".normal");
      point.wo = read_vec3(p["wo"], path + ".wo");
      if (!(length(point.normal) > 0)) throw FormatError(path + ".normal", "must be nonzero");
      if (!(length(point.wo) > 0)) throw FormatError(path + ".wo", "must be nonzero");
      if (!p["material"].is_string()) throw FormatError(path + ".material", "expected a name");
      point.material = p["material"].get<std::string>();
      probe.points.push_back(point);
    }
  }
  if (probe.pixels.empty() && probe.points.empty())
    throw FormatError("$", "a probe needs at least one pixel or point");
  return probe;
}

namespace {

// The surface a probe point lies on: a triangle of `material` within a few ray epsilons of
// `position` along the normal `n` (either side), whose geometric normal is parallel to `n`.
std::optional<SceneShading::FirstHit> surface_under(const SceneShading& shading,
                                                    const Material& material, const Vec3& position,
                                                    const Vec3& n) {
  const double reach = 16 * shading.embree().ray_epsilon();
  for (double side : {1.0, -1.0}) {
    Vec3 origin = position + n * (side * reach);
    SceneShading::FirstHit hit = shading.first_hit(origin, n * -side);
    if (!hit.shading_point || hit.shading_point->material != &material) continue;
    if (length(hit.shading_point->position - position) > 2 * reach) continue;
    if (std::abs(dot(hit.shading_point->normal, n)) < 1 - 1e-9) continue;
    return hit;
  }
  return std::nullopt;
}

}  // namespace

std::vector<SceneShading::FirstHit> resolve_probe_points(const SceneShading& shading,
                                                         const ProbeSpec& probe) {
  const Scene* scene = &shading.scene();
  CameraRays camera(scene->camera);

  std::vector<SceneShading::FirstHit> hits;
  for (size_t i = 0; i < probe.pixels.size(); ++i) {
    auto [x, y] = probe.pixels[i];
    if (x < 0 || y < 0 || x >= scene->camera.width || y >= scene->camera.height)
      throw FormatError("$.pixels[" + std::to_string(i) + "]", "pixel outside the image");
    hits.push_back(shading.first_hit(camera.origin(), camera.direction(x + 0.5, y + 0.5)));
  }
  for (size_t i = 0; i < probe.points.size(); ++i) {
    const ProbePointSpec& p = probe.points[i];
    const Material* material = nullptr;
    for (const Material& m : scene->materials)
      if (m.name == p.material) material = &m;
    if (!material)
      throw FormatError("$.points[" + std::to_string(i) + "].material",
                        "unknown material \"" + p.material + "\"");
    ShadingPoint sp;
    sp.position = p.position;
    sp.wo = normalize(p.wo);
    Vec3 n = normalize(p.normal);
    sp.normal = dot(n, sp.wo) < 0 ? -n : n;
    sp.material = material;
    SceneShading::FirstHit hit;
    hit.shading_point = sp;
    if (is_pbrt_material(material->type)) {
      if (auto surface = surface_under(shading, *material, p.position, n)) {
        // The point lies on a triangle of its material: the BSDF that triangle has there
        // (textures at its uv, the finest MIP level, bump mapping, the mesh's shading frame).
        hit.surface = surface->surface;
        hit.shading_point->normal = dot(surface->shading_point->normal, sp.wo) < 0
                                        ? -surface->shading_point->normal
                                        : surface->shading_point->normal;
      } else {
        // Off the scene's geometry: the material's constant values (textures ignored).
        hit.surface = make_pbrt_bsdf(*material, constant_material_values(material->params),
                                     Frame::from_normal(n), n);
      }
      hit.shading_point->bsdf = &hit.surface;
    }
    hits.push_back(hit);
  }

  return hits;
}

ProbeResult run_probe(std::shared_ptr<const Scene> scene, const ProbeSpec& probe,
                      const std::string& method, Pattern sampler, std::span<const int> counts,
                      int trials, uint64_t seed) {
  if (trials < 2) throw FormatError("trials", "at least 2 trials are needed for a variance");
  for (int n : counts)
    if (n < 1 || n > 1 << 20) throw FormatError("samples", "sample counts must be in 1..2^20");
  SceneShading shading(scene, parse_method(method));
  const std::vector<SceneShading::FirstHit> hits = resolve_probe_points(shading, probe);

  ProbeResult result;
  result.probe = probe;
  result.method = method;
  result.sampler = std::string(pattern_name(sampler));
  result.trials = trials;
  for (size_t index = 0; index < hits.size(); ++index) {
    std::vector<ProbeRun> runs;
    for (int n : counts) {
      ProbeRun run;
      run.n = n;
      std::vector<Rgb> estimates(trials);
      auto start = std::chrono::steady_clock::now();
      for (int trial = 0; trial < trials; ++trial) {
        // Independent streams per (point, N, trial).
        StreamKey key{seed ^ (0x9E3779B97F4A7C15ull * uint64_t(n)), uint64_t(index),
                      uint32_t(trial), 0};
        const auto& hit = hits[index];
        estimates[trial] = hit.shading_point ? shading.direct_lighting().estimate(
                                                   *hit.shading_point, shading, sampler, key, n)
                                             : hit.emitted;
      }
      double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      run.seconds_per_estimate = seconds / trials;
      for (const Rgb& e : estimates) run.mean += e;
      run.mean /= trials;
      for (const Rgb& e : estimates) {
        Rgb d = e - run.mean;
        run.variance += d * d;
      }
      run.variance /= (trials - 1.0);
      runs.push_back(run);
    }
    result.points.push_back(std::move(runs));
  }
  return result;
}

std::optional<double> variance_slope(const std::vector<ProbeRun>& runs, int channel) {
  std::vector<std::pair<double, double>> xy;
  for (const ProbeRun& run : runs) {
    const double variance = run.variance[channel];
    if (run.n > 0 && variance > 0 && std::isfinite(variance))
      xy.emplace_back(std::log(double(run.n)), std::log(variance));
  }
  if (xy.size() < 2) return std::nullopt;
  double mx = 0, my = 0;
  for (const auto& [x, y] : xy) {
    mx += x;
    my += y;
  }
  mx /= double(xy.size());
  my /= double(xy.size());
  double sxx = 0, sxy = 0;
  for (const auto& [x, y] : xy) {
    sxx += (x - mx) * (x - mx);
    sxy += (x - mx) * (y - my);
  }
  if (!(sxx > 0)) return std::nullopt;
  return sxy / sxx;
}

std::string probe_result_json(const ProbeResult& result) {
  json doc;
  doc["format"] = "penumbra/probe-result@1";
  doc["method"] = result.method;
  doc["sampler"] = result.sampler;
  doc["trials"] = result.trials;
  doc["points"] = json::array();
  for (size_t i = 0; i < result.points.size(); ++i) {
    json point;
    point["index"] = i;
    const size_t pixels = result.probe.pixels.size();
    if (i < pixels) {
      point["pixel"] = {result.probe.pixels[i].first, result.probe.pixels[i].second};
    } else if (i - pixels < result.probe.points.size()) {
      const ProbePointSpec& spec = result.probe.points[i - pixels];
      point["position"] = {spec.position.x, spec.position.y, spec.position.z};
      point["normal"] = {spec.normal.x, spec.normal.y, spec.normal.z};
      point["wo"] = {spec.wo.x, spec.wo.y, spec.wo.z};
      point["material"] = spec.material;
    }
    point["variance_slope"] = json::array();
    for (int channel = 0; channel < 3; ++channel) {
      std::optional<double> slope = variance_slope(result.points[i], channel);
      point["variance_slope"].push_back(slope ? json(*slope) : json(nullptr));
    }
    point["runs"] = json::array();
    for (const ProbeRun& run : result.points[i]) {
      point["runs"].push_back({{"n", run.n},
                               {"mean", {run.mean.x, run.mean.y, run.mean.z}},
                               {"variance", {run.variance.x, run.variance.y, run.variance.z}},
                               {"seconds_per_estimate", run.seconds_per_estimate}});
    }
    doc["points"].push_back(point);
  }
  return doc.dump(2);
}

}  // namespace penumbra
