#pragma once
// What makes a batch's table trustworthy: every MRSE with the reference's noise removed
// (core/image/noise_corrected_mrse.h), a 95% interval over the repeats that includes the
// reference's shared error (core/report/significance.h), the reference's share of each cell's
// error (cells above kReferenceShareFlag are flagged), winners marked only where the lowest row
// beats every other row of its group at 95% (paired by repeat), the pairwise comparisons, and
// each run's efficiency 1 / (MRSE x compute seconds) relative to a baseline method.
//
// The reference's term mean(s^2 / (R^2 + eps)) depends on the reference alone, so it corrects
// every error measured against that reference, also the farm's MRSE curves at pass boundaries
// (which cannot be recomputed from the final EXRs).

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image/noise_corrected_mrse.h"
#include "core/report/batch_charts.h"
#include "core/report/batch_result.h"
#include "core/report/batch_table.h"

namespace penumbra {

// A cell whose reference noise is more than this share of its plain MRSE is flagged.
inline constexpr double kReferenceShareFlag = 0.10;

// The reference's noise per region ("image" and every region): its term and deviation
// (NoiseCorrectedError.reference_term, .reference_deviation; plain and corrected unused).
struct ReferenceNoise {
  bool has_variance = false;  // the reference EXR has a variance layer
  std::map<std::string, NoiseCorrectedError> regions;
  // An exact reference's exact.mask channel (core/exact/exact_reference.h: per pixel the share
  // of camera samples the fallback shaded), summarised per region: the share of pixels with a
  // fallback sample, and the mean mask (the share of camera samples). Empty without the channel.
  struct MaskShare {
    double pixels = 0, samples = 0;
  };
  std::map<std::string, MaskShare> fallback;
  // The plain MRSE of a run (or curve point) in `region` with the reference's term removed.
  double corrected(const std::string& region, double plain) const;
  double term(const std::string& region) const;
  double deviation(const std::string& region) const;
};

// Reads the result folder's reference.exr with its variance layer.
ReferenceNoise read_reference_noise(const BatchResult& result,
                                    const std::filesystem::path& result_dir);

// "Does row A beat row B in this region?", paired by repeat.
struct PairwiseComparison {
  std::string group, region;
  size_t row_a = 0, row_b = 0;  // indices into the table's rows
  double ratio = 0;             // mean corrected MRSE of A over that of B (0 when B's is <= 0)
  PairedDifference difference;  // of A's corrected MRSE minus B's; sign -1: A beats B
};

struct BatchComparison {
  std::string baseline;  // the label efficiencies are relative to ("" when none ran)
  std::vector<PairwiseComparison> pairwise;
};

// The label of the baseline: the spec's "baseline" key when it names a method that ran, else
// the first method that ran.
std::string choose_baseline(const BatchResult& result);

// Fills each row's cells (corrected MRSE with intervals, plain, reference shares and flags) and
// efficiency, replaces `best` by the significant winners ("mrse:<region>"), and returns the
// pairwise comparisons of every group of two or more rows.
BatchComparison compare_batch_rows(BatchTable& table, const BatchResult& result,
                                   const RecomputedErrors& recomputed, const ReferenceNoise& noise);

// A copy of the batch result whose MRSE curves carry corrected values, and of the recomputed
// errors whose mrse is corrected: what the charts draw.
BatchResult corrected_curves(const BatchResult& result, const ReferenceNoise& noise);
RecomputedErrors corrected_errors(const RecomputedErrors& recomputed, const ReferenceNoise& noise);

// The charts' notes: "corrected" on the y axis, and "[ref > 10%]" after a method whose
// reference share is flagged in a region (any of its rows).
ChartAnnotations chart_annotations(const BatchTable& table, const ReferenceNoise& noise);

// Adds to table.json: per row "cells" (region -> corrected mean, lower, upper, plain mean,
// reference_share, reference_flagged) and "efficiency", and at the top "baseline",
// "reference_noise" (region -> term, deviation) and "pairwise".
void add_comparison_json(nlohmann::json& table_json, const BatchTable& table,
                         const BatchComparison& comparison, const ReferenceNoise& noise);

}  // namespace penumbra
