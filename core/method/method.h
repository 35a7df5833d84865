#pragma once
// The method grammar of SCENE_FORMAT.md (`penumbra/method@1`):
//
//   METHOD    := TERM ( "+" TERM )* [ "/" COMBINE ]
//   TERM      := [ COUNT "*" ] STRATEGY [ ":" DIR ]
//   STRATEGY  := bsdf | area | sa | psa | ltc | line-area | line-sa | line-bd16
//                (the names of the strategy registry, core/strategies/registry.h)
//   DIR       := u | v | rand          (line strategies only; default u)
//   COMBINE   := balance | power | avg | smooth | smooth-fixed | weighted | clamped-optimal

#include <string>
#include <string_view>
#include <vector>

#include "core/strategies/registry.h"

namespace penumbra {

enum class Combine { Balance, Power, Avg, Smooth, SmoothFixed, Weighted, ClampedOptimal };

struct MethodTerm {
  int count = 1;
  StrategyId strategy = 0;  // a row of the strategy registry (core/strategies/registry.h)
  LineDirection direction = LineDirection::U;  // meaningful for line strategies only
  bool operator==(const MethodTerm&) const = default;
};

struct MethodSpec {
  std::vector<MethodTerm> terms;
  Combine combine = Combine::Balance;
  int total_samples() const;
  bool operator==(const MethodSpec&) const = default;
};

inline constexpr int kMaxTermCount = 4096;      // COUNT of one term
inline constexpr int kMaxMethodSamples = 4096;  // sum of COUNT over the terms
inline constexpr int kMaxMethodTerms = 16;

std::string_view combine_name(Combine combine);
std::string_view direction_name(LineDirection direction);

// Parses the text form. Throws FormatError (core/scene/scene.h) whose path is "method" and whose
// message quotes the text, the character position and what was expected.
MethodSpec parse_method(std::string_view text);
// The canonical text form (parse_method(to_string(m)) == m).
std::string to_string(const MethodSpec& method);

}  // namespace penumbra
