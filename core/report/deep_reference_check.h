#pragma once
// Are a batch's reported numbers real? Each table cell's corrected MRSE (the mean over its
// repeats, measured against the batch's own reference with that reference's noise removed,
// core/image/noise_corrected_mrse.h) recomputed against a deeper reference of the same scene
// (16x the samples, or an exact one): the cell passes when the two agree within `tolerance`
// (10%: "each reported MRSE within 10% of the same run's MRSE against a 16x deeper reference").
// `penumbra check-depth DIR --deep DEEP.exr` prints it; tools/check_reference_depth.sh renders
// the deep reference and runs it over the bundled batches.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/report/batch_result.h"

namespace penumbra {

struct DeepCheckCell {
  std::string label;   // the row's method label
  std::string budget;  // "equal time" or "N spp"
  std::string region;  // "image" or a region's name
  int repeats = 0;
  double reported = 0;  // mean corrected MRSE against the batch's reference
  double deep = 0;      // the same runs' mean corrected MRSE against the deep reference
  double reported_plain = 0;
  double deep_plain = 0;
  double ratio = 0;  // reported / deep
  bool within = false;
};

struct DeepCheck {
  std::filesystem::path deep_reference;
  uint32_t reference_spp = 0,
           deep_spp = 0;  // from the batch and the deep EXR's metadata (0: unknown)
  double tolerance = 0.10;
  std::vector<DeepCheckCell> cells;
  bool passed() const;
  double worst_deviation() const;  // max |ratio - 1| over the cells
};

// Reads the folder's runs and both references. Throws std::runtime_error (unreadable EXRs, a deep
// reference of another size) or BatchResultError.
DeepCheck check_against_deep_reference(const std::filesystem::path& result_dir,
                                       const std::filesystem::path& deep_reference,
                                       double tolerance = 0.10);

// A text table (one line per cell, the failing ones marked) and the summary line.
std::string deep_check_text(const DeepCheck& check);
nlohmann::json deep_check_json(const DeepCheck& check);

}  // namespace penumbra
