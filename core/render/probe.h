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
  std::vector<std::vector<ProbeRun>> points;  // pixels first, then points, in input order
};

// Throws FormatError for a bad method, a pixel outside the image, an unknown material.
ProbeResult run_probe(std::shared_ptr<const Scene> scene, const ProbeSpec& probe,
                      const std::string& method, Pattern sampler,
                      std::span<const int> sample_counts, int trials, uint64_t seed);

// `penumbra/probe-result@1` JSON.
std::string probe_result_json(const ProbeResult& result);

}  // namespace penumbra
