// Numerical stability: every method against every adversarial configuration gives finite
// estimates and agrees with the case's reference (Lambert's closed form, or a converged bsdf+sa
// estimate) within 5 standard errors or 0.1%; point strategies that apply to every light are
// never refused.
#include "core/analysis/stability.h"

#include <gtest/gtest.h>

#include <cmath>

namespace penumbra {
namespace {

const StabilityTable& table() {
  static const StabilityTable t = [] {
    StabilityOptions options;
    options.trials = 128;
    options.samples = 4;
    options.reference_trials = 128;
    options.reference_samples = 512;
    return run_stability(options);
  }();
  return t;
}

TEST(Stability, ProgressCountsEveryStepThenTheEnd) {
  // Two cases (one without a closed form, whose reference is a step of its own) and two methods.
  StabilityOptions options;
  options.trials = 8;
  options.reference_trials = 8;
  options.reference_samples = 4;
  options.methods = {"sa", "bsdf"};
  // The first case with a closed form and the first without, in table order.
  std::string with, without;
  for (const StabilityCase& c : stability_cases()) {
    std::string& slot = c.closed_form ? with : without;
    if (!slot.empty()) continue;
    slot = c.name;
    options.cases.push_back(c.name);
  }
  ASSERT_EQ(options.cases.size(), 2u);
  std::vector<std::string> steps;
  int expected_done = 0;
  options.progress = [&](const std::string& what, int done, int total) {
    EXPECT_EQ(done, expected_done++) << what;
    EXPECT_EQ(total, 1 + 2 * 2) << what;
    steps.push_back(what);
  };
  run_stability(options);
  ASSERT_EQ(steps.size(), 6u);
  EXPECT_EQ(steps[0], "reference for " + without);
  EXPECT_EQ(steps[1], "sa on " + options.cases[0]);
  EXPECT_EQ(steps[5], "done");
}

TEST(Stability, EveryCaseHasAReferenceThatIsFinite) {
  for (const StabilityCase& c : stability_cases()) {
    if (c.closed_form) {
      EXPECT_TRUE(std::isfinite(c.closed_form->x)) << c.name;
      EXPECT_GE(c.closed_form->x, 0) << c.name;
    }
  }
  // The closed forms are not all trivially zero: only the edge-on light is.
  int zero = 0;
  for (const StabilityCase& c : stability_cases())
    if (c.closed_form && c.closed_form->x == 0) ++zero;
  EXPECT_EQ(zero, 1);
}

TEST(Stability, NoMethodProducesNonFiniteEstimates) {
  for (const StabilityCell& cell : table().cells)
    if (!cell.refused) {
      EXPECT_EQ(cell.nonfinite, 0u) << cell.method << " / " << cell.case_name;
    }
}

TEST(Stability, EveryMethodIsConsistentWithTheReference) {
  for (const StabilityCell& cell : table().cells) {
    if (cell.refused || !cell.expected_unconverged.empty()) continue;
    EXPECT_TRUE(cell.consistent) << cell.method << " / " << cell.case_name << ": mean " << cell.mean
                                 << ", reference " << cell.reference << ", relative bias "
                                 << cell.relative_bias << ", " << cell.bias_sigmas
                                 << " standard errors";
  }
}

TEST(Stability, OnlyTheListedPairsAreExpectedNotToConverge) {
  int expected = 0;
  for (const StabilityCell& cell : table().cells) expected += !cell.expected_unconverged.empty();
  EXPECT_EQ(expected, 4 + 3 + 6);
  // A method that converges everywhere else must not be excused anywhere.
  for (const StabilityCase& c : table().cases)
    EXPECT_TRUE(expected_unconverged("bsdf+sa", c.name).empty()) << c.name;
}

TEST(Stability, GeneralPointStrategiesAreNeverRefused) {
  for (const char* method : {"area", "sa", "bsdf", "bsdf+sa"})
    for (const StabilityCase& c : table().cases)
      EXPECT_FALSE(table().cell(method, c.name).refused)
          << method << " / " << c.name << ": " << table().cell(method, c.name).refusal;
}

TEST(Stability, LineSamplesRunOnEveryLambertianRectangleCase) {
  for (const StabilityCase& c : table().cases) {
    if (!c.closed_form) continue;  // the glossy cases may refuse some line estimators
    for (const char* method : {"line-area:u", "line-sa:v", "bsdf+line-sa:v/smooth"})
      EXPECT_FALSE(table().cell(method, c.name).refused)
          << method << " / " << c.name << ": " << table().cell(method, c.name).refusal;
  }
}

TEST(Stability, MarkdownAndJsonNameEveryCell) {
  std::string markdown = stability_markdown(table());
  std::string json = stability_json(table());
  for (const StabilityCase& c : table().cases) {
    EXPECT_NE(markdown.find(c.name), std::string::npos) << c.name;
    EXPECT_NE(json.find(c.name), std::string::npos) << c.name;
  }
  EXPECT_NE(json.find("penumbra/stability@1"), std::string::npos);
}

}  // namespace
}  // namespace penumbra
