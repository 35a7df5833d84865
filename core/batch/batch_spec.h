#pragma once
// The `penumbra/batch@1` format (batches/README.md): an equal-time comparison of several methods
// on one scene, run by the farm's coordinator as a set of jobs (a reference, then one job per
// method, budget and repeat; an equal-time job calibrates itself on its first passes). This is
// the reader only: no network, no filesystem. Errors are FormatError (core/scene/scene.h) naming
// the JSON path, the source and the bad value, like the scene reader's.
//
//   {"format": "penumbra/batch@1", "name": "fig1-monoliths", "scene": "monoliths",
//    "methods": [{"method": "line-sa:v", "sampler": "stratified", "label": "ours"}, "sa"],
//    "budget": {"seconds": 10, "spp": [16, 64]},
//    "reference": "auto",  // or "job:job-7", "path/to/ref.exr", {"method":..,"spp":..},
//                          // {"spp": "auto", "target_share": 0.01, "max_seconds": 300},
//                          // {"kind": "exact", "camera_samples": 16}
//    "regions": {"penumbra": [120, 300, 220, 400]}, "seed": 1, "repeats": 3}

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/scene/scene.h"

namespace penumbra {

inline constexpr std::string_view kBatchFormat = "penumbra/batch@1";

// Past these a spec is refused as absurd (the error names the limit).
struct BatchLimits {
  size_t max_json_bytes = size_t{1} << 20;
  int max_json_depth = 16;
  size_t max_methods = 64;
  size_t max_spp_levels = 32;   // entries of budget.spp
  uint32_t max_spp = 1u << 20;  // each spp level and the reference's spp
  double max_seconds = 1e6;     // budget.seconds (per method and repeat), reference.max_seconds
  uint32_t max_repeats = 100;
  size_t max_regions = 64;
  size_t max_text_length = 1024;     // names, labels, methods, samplers, paths
  int64_t max_coordinate = 1 << 16;  // region corners (the scene's resolution is checked later)
};

struct BatchMethodSpec {
  std::string method;   // penumbra/method@1 text as written (its grammar is checked)
  std::string sampler;  // a pattern name (core/sampling/pattern.h); default "stratified"
  std::string label;    // as written, or the method text; unique within the batch
};

enum class BatchReferenceKind {
  // Rendered by the farm with a robust method, cached by scene and settings; its spp given, or
  // sized from short probes of every method and of the reference method (core/batch/
  // reference_sizing.h) so that its noise is a small share of the best method's error.
  Auto,
  Exr,  // an EXR file the client uploads
  Job,  // the result of a finished job on the same coordinator
  // Closed-form direct illumination per camera sample (core/exact), rendered by the client
  // (cached by scene hash, build flavour and settings) and uploaded like an EXR; pixels without
  // a closed form fall back to a converged estimate.
  Exact,
};

struct BatchReferenceSpec {
  BatchReferenceKind kind = BatchReferenceKind::Auto;
  std::string exr_path;  // Exr: as written (relative paths are relative to the spec's folder)
  std::string job_id;    // Job: "job-7"
  // Auto: what renders the reference.
  std::string method = "bsdf+sa";
  std::string sampler = "stratified";
  uint32_t spp = 1024;  // when not sized
  uint64_t seed = 0x5eed;
  // Auto with "spp": "auto" (the default): spp sized so that the reference's expected noise term
  // is at most target_share of the best method's expected MRSE at the batch's budget, in the
  // image and every region, unless rendering that many passes would take more than max_seconds
  // compute seconds (then the cap decides, and the report says so).
  bool sized = true;
  double target_share = 0.01;
  double max_seconds = 300;
  // Exact: camera rays per pixel, and the fallback where no closed form applies (method, and
  // samples per term for each camera sample).
  uint32_t camera_samples = 16;
  std::string fallback_method = "bsdf+sa";
  uint32_t fallback_samples = 64;
};

struct BatchSpec {
  std::string name;   // "name", else the source's file stem
  std::string scene;  // a bundled scene name or a path (the client packs it)
  std::vector<BatchMethodSpec> methods;
  std::optional<double> budget_seconds;  // compute seconds per method and repeat
  std::vector<uint32_t> budget_spp;      // spp levels (ascending, distinct)
  BatchReferenceSpec reference;
  std::map<std::string, Region> regions;  // merged with the scene's ("image" is reserved)
  uint64_t seed = 1;                      // repeat r renders with seed + r
  uint32_t repeats = 3;                   // independent repeats (intervals need two or more)
  std::string baseline;  // the label efficiencies are relative to (empty: the first method)
  // "strict": true refuses a scene whose reader warns (unknown keys, ignored parameters); by
  // default the warnings are printed and carried in every run's status and EXR.
  bool strict = false;
  // Unknown keys the reader ignored (forward compatibility), each as "JSON path: note".
  std::vector<std::string> warnings;
};

// Parses and validates a batch spec. `source_name` names the document in messages. Throws
// FormatError (and nothing else) on any bad input.
BatchSpec parse_batch_spec(std::string_view json, std::string_view source_name,
                           const BatchLimits& limits = {});

// A label made safe as a file name: [A-Za-z0-9._-] kept, anything else becomes '_'
// ("line-sa:v" -> "line-sa_v"); never empty, never "." or "..".
std::string file_safe_label(std::string_view label);

}  // namespace penumbra
