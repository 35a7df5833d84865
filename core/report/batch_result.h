#pragma once
// The batch result folder (/work/briefs/s2_batch_contract.md, "penumbra/batch-result@1"): the
// index batch.json, reference.exr and one EXR per method run. `penumbra batch run` and
// `penumbra batch fetch` write it; the report reads it with read_batch_result.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/image/metrics.h"
#include "core/scene/scene.h"

namespace penumbra {

inline constexpr const char* kBatchResultFormat = "penumbra/batch-result@1";

// A batch.json that cannot be used. what() is "batch.json: <key path>: <problem>", e.g.
// "batch.json: methods[2].runs[0].exr: missing"; key_path() is the path alone.
class BatchResultError : public std::runtime_error {
 public:
  BatchResultError(const std::string& file, const std::string& key_path, const std::string& problem)
      : std::runtime_error(file + ": " + (key_path.empty() ? "" : key_path + ": ") + problem),
        key_path_(key_path) {}
  const std::string& key_path() const { return key_path_; }

 private:
  std::string key_path_;
};

// One MRSE measurement at a pass boundary of a farm job (it cannot be recomputed from the EXR).
struct BatchCurvePoint {
  uint32_t passes = 0;
  double compute_seconds = 0;
  double wall_seconds = 0;
  double mrse = 0;                        // the full image's
  std::map<std::string, double> regions;  // each region's MRSE (absent in older results)
};

struct BatchRun {
  int repeat = 0;
  uint64_t seed = 0;
  std::string job_id;
  std::string exr;  // relative to the result folder, e.g. "runs/line-sa_v.r0.exr"
  uint32_t spp = 0;
  // The method's equal-time run (its budget in seconds), else a run of a fixed spp level. When
  // batch.json does not say: equal time exactly when the method has a seconds budget.
  bool equal_time = false;
  double compute_seconds = 0;
  double wall_seconds = 0;
  std::vector<BatchCurvePoint> curve;
  // The errors the batch runner recorded: "image" and one entry per region (metrics.h).
  std::map<std::string, ErrorSummary> errors;
};

struct BatchMethod {
  std::string label;
  std::string method;                    // penumbra/method@1 text form
  std::string sampler;                   // pattern name
  std::optional<double> budget_seconds;  // empty when the method ran on an spp list only
  std::vector<BatchRun> runs;
  std::string error;  // the farm's refusal message (then runs is empty); empty when it ran
};

// How a sized auto reference ("spp": "auto") chose its spp (core/batch/reference_sizing.h).
struct BatchReferenceSizing {
  uint32_t probe_spp = 0;
  double target_share = 0;
  double max_seconds = 0;
  double seconds_per_pass = 0;
  double required_spp = 0;  // what the target asked for
  bool capped = false;      // max_seconds bound: fewer spp than the target asked for
  double predicted_share = 0;
  double predicted_seconds = 0;
  std::string deciding_region;
  std::string best_method;
};

struct BatchReference {
  std::string exr;   // relative to the result folder
  std::string kind;  // "auto", "job", "exr", "exact" (empty in older folders)
  std::string method;
  std::string sampler;
  uint32_t spp = 0;
  std::string job_id;
  bool cached = false;
  std::optional<BatchReferenceSizing> sizing;
};

struct BatchSceneInfo {
  std::string name;
  std::string hash;
  int width = 0, height = 0;
};

struct BatchRegion {
  std::string name;
  Region rect;
};

struct BatchResult {
  std::string batch_id;   // coordinator id, or "local"
  std::string name;       // the spec's name
  std::string spec_json;  // the penumbra/batch@1 spec as submitted, pretty-printed JSON
  BatchSceneInfo scene;
  std::vector<BatchRegion> regions;  // in file order; "image" is implicit and never listed
  BatchReference reference;
  std::vector<BatchMethod> methods;

  // The regions keyed by name, as error_summary takes them.
  std::map<std::string, Region> region_map() const;
};

// Parses batch.json text. `source` names the file in messages ("batch.json"). Unknown keys are
// ignored; a missing or mistyped required key throws BatchResultError naming its key path.
BatchResult parse_batch_result(const std::string& json_text,
                               const std::string& source = "batch.json");

// A reference rendered with fewer than kReferenceSppFactor times the spp of the deepest run it
// judges is barely cleaner than that run: its own noise is a large part of every error measured
// against it. The warning to print (empty when the reference is deep enough, is not a rendered
// one, or its spp is unknown).
inline constexpr double kReferenceSppFactor = 4;
std::string reference_depth_warning(const BatchResult& result);

// One sentence on how a sized reference chose its spp: the spp, what the target asked for,
// whether max_seconds bound, the predicted reference share and where.
std::string reference_sizing_text(const BatchReference& reference);

// Reads DIR/batch.json and checks that every EXR it names exists in DIR (a missing file is an
// error naming the key path and the file). Throws BatchResultError.
BatchResult read_batch_result(const std::filesystem::path& result_dir);

}  // namespace penumbra
