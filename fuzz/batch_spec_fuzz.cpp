// libFuzzer target: the batch reader (core/batch/batch_spec.h) on arbitrary JSON text. Every
// input either parses into a spec within its limits or throws FormatError (and nothing else).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string_view>

#include "core/batch/batch_spec.h"
#include "fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  static const BatchLimits limits;
  std::string_view json(reinterpret_cast<const char*>(data), size);
  BatchSpec spec;
  try {
    spec = parse_batch_spec(json, "fuzz-batch.json", limits);
  } catch (const FormatError&) {
    return 0;
  }
  FUZZ_CHECK(!spec.methods.empty() && spec.methods.size() <= limits.max_methods);
  std::set<std::string> labels;
  for (const auto& method : spec.methods) {
    FUZZ_CHECK(!method.method.empty() && !method.label.empty());
    FUZZ_CHECK(labels.insert(method.label).second);
    std::string safe = file_safe_label(method.label);
    FUZZ_CHECK(!safe.empty() && safe != "." && safe != "..");
    FUZZ_CHECK(safe.find('/') == std::string::npos);
  }
  FUZZ_CHECK(spec.budget_seconds || !spec.budget_spp.empty());
  if (spec.budget_seconds)
    FUZZ_CHECK(std::isfinite(*spec.budget_seconds) && *spec.budget_seconds > 0 &&
               *spec.budget_seconds <= limits.max_seconds);
  FUZZ_CHECK(spec.budget_spp.size() <= limits.max_spp_levels);
  for (size_t i = 0; i < spec.budget_spp.size(); ++i) {
    FUZZ_CHECK(spec.budget_spp[i] >= 1 && spec.budget_spp[i] <= limits.max_spp);
    if (i > 0) FUZZ_CHECK(spec.budget_spp[i - 1] < spec.budget_spp[i]);
  }
  if (spec.reference.kind == BatchReferenceKind::Auto && spec.reference.sized)
    FUZZ_CHECK(spec.reference.target_share >= 1e-4 && spec.reference.target_share <= 0.5 &&
               spec.reference.max_seconds > 0 && spec.reference.max_seconds <= limits.max_seconds);
  if (spec.reference.kind == BatchReferenceKind::Auto && !spec.reference.sized)
    FUZZ_CHECK(spec.reference.spp >= 1 && spec.reference.spp <= limits.max_spp);
  FUZZ_CHECK(spec.repeats >= 1 && spec.repeats <= limits.max_repeats);
  FUZZ_CHECK(spec.regions.size() <= limits.max_regions && !spec.regions.count("image"));
  for (const auto& [name, region] : spec.regions)
    FUZZ_CHECK(region.x0 >= 0 && region.y0 >= 0 && region.x0 < region.x1 && region.y0 < region.y1);
  // The same text parses to the same spec.
  BatchSpec again = parse_batch_spec(json, "fuzz-batch.json", limits);
  FUZZ_CHECK(again.methods.size() == spec.methods.size() && again.name == spec.name);
  return 0;
}
