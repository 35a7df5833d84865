#pragma once
// `penumbra verify SCENE --method M`: k independent renders of a method (seeds seed .. seed+k-1)
// z-tested block by block against a reference (core/analysis/bias_check.h for the statistics).
//
// The reference is the exact reference of core/exact (the closed form per camera sample on
// Lambertian receivers under constant polygonal lights; elsewhere the fallback method with many
// samples per camera sample, i.e. a deep render), or an EXR with a variance layer. Its seed must
// differ from the runs' so that its noise is independent of theirs.
//
// A bias check is cheap at a reduced resolution: `width` renders the scene's camera at fewer
// pixels (the same view), which keeps the whole image in the test at a fraction of the cost.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/analysis/bias_check.h"
#include "core/exact/exact_reference.h"
#include "core/render/local_render.h"
#include "core/sampling/pattern.h"

namespace penumbra {

// The scene with its camera at `width` pixels across (the height in proportion, at least 1; a
// pbrt-v3 crop window is scaled with it). The view is unchanged. Its regions are dropped (they
// are in the original's pixels).
Scene scene_at_width(const Scene& scene, int width);

struct VerifyReference {
  Film film;
  Image exact_fraction;  // per pixel (empty: unknown, e.g. an EXR reference)
  std::string description;
  double exact_share = -1;  // of the camera samples; -1 unknown
  double compute_seconds = 0;
  uint64_t seed = 0;
};

VerifyReference render_verify_reference(std::shared_ptr<const Scene> scene,
                                        const ExactReferenceOptions& options);
// A deep render instead (where the exact reference is too costly: its cost grows with the
// occluders that cut the light): `method` at `spp` with `seed`.
VerifyReference render_deep_reference(std::shared_ptr<const Scene> scene, const std::string& method,
                                      Pattern sampler, uint32_t spp, uint64_t seed,
                                      int threads = 0);

// Renders run `index` with `seed` and returns its film (mean and variance of the mean).
using RunRenderer = std::function<Film(int index, uint64_t seed)>;

// The method's runs with the local renderer: `budget` per run, `threads` (0: all).
RunRenderer method_run_renderer(std::shared_ptr<const Scene> scene, const std::string& method,
                                Pattern sampler, const RenderBudget& budget, int threads = 0);

struct VerifyResult {
  BiasCheckResult check;
  std::vector<uint32_t> spp;  // per run (the film's minimum)
};

// Renders `runs` runs with seeds seed, seed + 1, ... and checks them. Throws
// std::invalid_argument when a run's seed is the reference's, or for fewer than two runs.
VerifyResult verify_runs(const VerifyReference& reference, int runs, uint64_t seed,
                         const RunRenderer& render, const BiasCheckOptions& options = {});

}  // namespace penumbra
