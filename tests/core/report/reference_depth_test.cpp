// The warning for a reference barely cleaner than the runs it judges (its spp against the
// deepest run's): given below 4x, not from 4x on, never for an exact reference.
#include <gtest/gtest.h>

#include "core/report/batch_result.h"

namespace penumbra {
namespace {

BatchResult batch(uint32_t reference_spp, std::vector<uint32_t> run_spp) {
  BatchResult result;
  result.reference.method = "bsdf+sa";
  result.reference.spp = reference_spp;
  BatchMethod method;
  method.label = "sa";
  for (uint32_t spp : run_spp) {
    BatchRun run;
    run.spp = spp;
    method.runs.push_back(run);
  }
  result.methods.push_back(method);
  return result;
}

TEST(ReferenceDepth, WarnsWhenTheReferenceIsBarelyCleanerThanTheRuns) {
  const std::string warning = reference_depth_warning(batch(16, {5, 6}));
  EXPECT_NE(warning.find("16 spp"), std::string::npos) << warning;
  EXPECT_NE(warning.find("2.7x the 6 spp of sa"), std::string::npos) << warning;
  EXPECT_NE(warning.find("24 spp or more"), std::string::npos) << warning;
  EXPECT_EQ(reference_depth_warning(batch(24, {5, 6})), "");
  EXPECT_EQ(reference_depth_warning(batch(1024, {6})), "");
  EXPECT_EQ(reference_depth_warning(batch(0, {6})), "") << "unknown reference spp";
  BatchResult exact = batch(16, {64});
  exact.reference.method = "exact (fallback bsdf+sa)";
  EXPECT_EQ(reference_depth_warning(exact), "");
}

}  // namespace
}  // namespace penumbra
