#pragma once
// Numerical stability where methods fail: every method against every adversarial
// configuration -- shading points on and near the light's plane, light edges parallel to the
// normal, 1 cm and 1 mm lights at 40 m, a huge light at 1e-3, zero-area and edge-on occluder
// triangles, an occluder whose edge lies in the shadow triangles of line samples, a phong
// exponent of 10^4, ggx roughness 1e-4 and 1. For each (method, case) the table counts
// non-finite estimates (must be 0), and measures bias against the case's reference (Lambert's
// closed form where the receiver is Lambertian and the visible part of the light is a polygon;
// else a converged bsdf+sa estimate) and the relative standard deviation of one estimate.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/math/vec.h"

namespace penumbra {

struct StabilityCase {
  std::string name, description;
  std::string scene_json;  // penumbra/scene@1; the receiver's material is named "receiver"
  Vec3 position, normal, wo;
  // The exact reflected radiance when it has a closed form (Lambert's polygon formula).
  std::optional<Rgb> closed_form;
};

// The adversarial configurations, in table order.
std::vector<StabilityCase> stability_cases();
// The methods the table covers (method@1 text), in table order.
std::vector<std::string> stability_methods();

struct StabilityOptions {
  int trials = 256;              // independent estimates per (method, case)
  int samples = 4;               // sample multiplier N per estimate
  int reference_trials = 256;    // for cases without a closed form: bsdf+sa estimates ...
  int reference_samples = 1024;  // ... of this many samples each
  uint64_t seed = 7;
  std::vector<std::string> methods;  // empty: stability_methods()
  std::vector<std::string> cases;    // empty: every case
  // Called as each step (a reference, then a method on a case) starts with what it computes, the
  // steps done before it and their total, and once more at the end with done == total.
  std::function<void(const std::string& what, int done, int total)> progress;
};

struct StabilityCell {
  std::string method, case_name;
  bool refused = false;
  std::string refusal;  // the estimator's error message
  uint64_t estimates = 0;
  uint64_t nonfinite = 0;     // estimates with a NaN or infinite channel
  double mean = 0;            // luminance-free: the mean of the three channels' mean
  double reference = 0;       // same, for the reference
  double standard_error = 0;  // of `mean`
  double relative_bias = 0;   // (mean - reference) / reference; 0 when both are 0
  double bias_sigmas = 0;     // |mean - reference| / combined standard error
  double relative_std = 0;    // std. dev. of one estimate / reference
  // Unbiased within the test's tolerance: Welch's t test of the mean against the reference at
  // the false-alarm rate of a 5-standard-error normal test (core/analysis/mean_consistency.h:
  // 5 standard errors for many trials, more for few), or |relative bias| <= 1e-3 (the
  // reference's own error for converged references).
  bool consistent = true;
  // Set when the method is unbiased but cannot converge at any practical budget in this case
  // (e.g. BSDF sampling of a 1 mm light 40 m away): the reason, shown as "~" in the table.
  std::string expected_unconverged;
};

// The reason a (method, case) pair is known not to converge at the table's budget, or empty.
std::string expected_unconverged(const std::string& method, const std::string& case_name);

struct StabilityTable {
  std::vector<StabilityCase> cases;
  std::vector<std::string> methods;
  std::vector<StabilityCell> cells;         // method-major
  std::vector<std::string> reference_kind;  // per case: "closed form" or "bsdf+sa, N samples"
  const StabilityCell& cell(const std::string& method, const std::string& case_name) const;
};

StabilityTable run_stability(const StabilityOptions& options = {});

// Markdown: one row per method, one column per case; a cell shows the relative bias in percent
// (or "refused"), with "NaN:k" when non-finite estimates occurred and "!" when inconsistent.
std::string stability_markdown(const StabilityTable& table);
// JSON (`penumbra/stability@1`): every cell with every field.
std::string stability_json(const StabilityTable& table);

}  // namespace penumbra
