#pragma once
// The probe (`penumbra/probe@1`, SCENE_FORMAT.md): the estimator's statistics at fixed shading
// points, for convergence and error analysis.
//
// For each point and each N, K independent estimates are made, each with N samples per method
// term (a term with COUNT c draws c*N samples, stratified together by the sampler); the mean and
// the unbiased sample variance of the K estimates are reported. Trials use independent streams.

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/render/shading.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"

namespace penumbra {

struct ProbePointSpec {
  Vec3 position, normal, wo;
  std::string material;
};

struct ProbeSpec {
  std::vector<std::pair<int, int>> pixels;
  std::vector<ProbePointSpec> points;
};

// Throws FormatError naming the JSON path.
ProbeSpec parse_probe(const std::string& json_text, const std::string& source = "<probe>");

struct ProbeRun {
  int n = 0;
  Rgb mean, variance;
  double seconds_per_estimate = 0;
};

struct ProbeResult {
  std::string method, sampler;
  int trials = 0;
  ProbeSpec probe;                            // what was probed: names each entry of `points`
  std::vector<std::vector<ProbeRun>> points;  // pixels first, then points, in input order
};

// The least-squares slope of log(variance) against log(n) over the runs with a positive
// variance (per channel); empty for a channel with fewer than two such runs of distinct n.
std::optional<double> variance_slope(const std::vector<ProbeRun>& runs, int channel);

// What each probe entry shades, pixels first, then points: the first hit of the ray through a
// pixel's centre (no jitter), or the point as described. A point with a pbrt-v3 material that
// lies on a triangle of that material (within a few ray epsilons) gets that triangle's BSDF there
// (textures, bump, shading frame); elsewhere the material's constant values. Throws FormatError
// for a pixel outside the image or an unknown material.
std::vector<SceneShading::FirstHit> resolve_probe_points(const SceneShading& shading,
                                                         const ProbeSpec& probe);

// Throws FormatError for a bad method, a pixel outside the image, an unknown material.
ProbeResult run_probe(std::shared_ptr<const Scene> scene, const ProbeSpec& probe,
                      const std::string& method, Pattern sampler,
                      std::span<const int> sample_counts, int trials, uint64_t seed);

// `penumbra/probe-result@1` JSON. Each point names what it is ("pixel": [x, y], or "position",
// "normal", "wo", "material") and carries "variance_slope": [r, g, b] (null where undefined).
std::string probe_result_json(const ProbeResult& result);

}  // namespace penumbra
