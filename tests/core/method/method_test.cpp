#include "core/method/method.h"

#include <gtest/gtest.h>

#include "core/scene/scene.h"

namespace penumbra {
namespace {

TEST(MethodGrammar, ParsesEveryFormOfTheContract) {
  MethodSpec m = parse_method("bsdf+3*line-sa:v");
  ASSERT_EQ(m.terms.size(), 2u);
  EXPECT_EQ(strategy_name(m.terms[0].strategy), "bsdf");
  EXPECT_EQ(m.terms[0].count, 1);
  EXPECT_EQ(strategy_name(m.terms[1].strategy), "line-sa");
  EXPECT_EQ(m.terms[1].count, 3);
  EXPECT_EQ(m.terms[1].direction, LineDirection::V);
  EXPECT_EQ(m.combine, Combine::Balance);  // default with more than one term

  m = parse_method("bsdf+line-sa:v/smooth");
  EXPECT_EQ(m.combine, Combine::Smooth);
  EXPECT_EQ(parse_method("line-area").terms[0].direction, LineDirection::U);  // default u
  EXPECT_EQ(parse_method("line-bd16:rand").terms[0].direction, LineDirection::Rand);
  EXPECT_EQ(parse_method("psa+ltc/clamped-optimal").combine, Combine::ClampedOptimal);
  EXPECT_EQ(parse_method("line-sa:u+line-sa:v/avg").combine, Combine::Avg);
  EXPECT_EQ(parse_method("sa+bsdf/smooth-fixed").combine, Combine::SmoothFixed);
  EXPECT_EQ(parse_method("psa+ltc/weighted").combine, Combine::Weighted);
  EXPECT_EQ(parse_method("area+sa/power").combine, Combine::Power);
}

TEST(MethodGrammar, RoundTripsThroughTheCanonicalText) {
  for (const char* text : {"sa", "bsdf+sa", "bsdf+3*line-sa:v/smooth", "line-bd16:rand", "16*area",
                           "line-area:u+line-area:v/avg", "psa+ltc/weighted"}) {
    MethodSpec m = parse_method(text);
    EXPECT_EQ(parse_method(to_string(m)), m) << text << " -> " << to_string(m);
  }
  EXPECT_EQ(to_string(parse_method("bsdf+sa")), "bsdf+sa/balance");
}

void expect_error(const char* text, const char* fragment) {
  try {
    parse_method(text);
    ADD_FAILURE() << "no error for \"" << text << "\"";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.json_path(), "method");
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << "error for \"" << text << "\": " << e.what();
  }
}

TEST(MethodGrammar, RejectsBadTextWithAClearMessage) {
  expect_error("", "empty");
  expect_error("foo", "unknown strategy \"foo\"");
  expect_error("sa:u", "not a line strategy");
  expect_error("line-sa:w", "unknown line direction");
  expect_error("sa/best", "unknown combination \"best\"");
  expect_error("0*sa", "counts are 1..");
  expect_error("99999999999999999999*sa", "counts are 1..");
  expect_error("3sa", "expected '*'");
  expect_error("sa+", "expected a strategy");
  expect_error("sa bsdf", "unexpected character");
  expect_error("4000*sa+4000*bsdf", "samples per shading point");
  expect_error("sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa+sa", "terms");
}

}  // namespace
}  // namespace penumbra
