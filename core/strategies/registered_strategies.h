#pragma once
// THE registry of strategies: one row per strategy class, in the order the method grammar lists
// them (core/strategies/registry.h for what a row provides). A row is a class with
//
//   static constexpr std::string_view name();            // its name in the method grammar
//   static constexpr StrategyFamily kFamily;             // how the estimator runs it
//   static constexpr bool kRectangleStrata;              // strata of the quad's aspect
//   static std::optional<std::string> refusal(const Scene&, LineDirection);   // can it run?
//
// and the constructor and entry points of its family (strategy.h):
//   Point         T(sp, light); sample(u) -> optional<LightPoint>; pdf(point)
//   Line          T(sp, light, LineAxis, const LineQuery&); sample(u, line, t); pdf(line, t, point)
//   AnalyticLine  T(sp, light, LineDirection); estimate_sum(pattern, stream, n, query)

#include <cstddef>
#include <type_traits>
#include <utility>
#include <variant>

#include "core/strategies/area_strategy.h"
#include "core/strategies/bsdf_strategy.h"
#include "core/strategies/line_area_strategy.h"
#include "core/strategies/line_bd16_strategy.h"
#include "core/strategies/line_solid_angle_strategy.h"
#include "core/strategies/ltc_strategy.h"
#include "core/strategies/psa_strategy.h"
#include "core/strategies/registry.h"
#include "core/strategies/solid_angle_strategy.h"

namespace penumbra {

template <typename... Strategies>
struct StrategyList {
  static constexpr size_t size = sizeof...(Strategies);
  // A prepared strategy of any row; monostate: not prepared (never sampled or evaluated).
  using Prepared = std::variant<std::monostate, Strategies...>;

  // Calls f.template operator()<T>() for the row `id` (nothing for an id past the end).
  template <typename F>
  static void visit_row(StrategyId id, F&& f) {
    size_t row = 0;
    ((row++ == id ? f.template operator()<Strategies>() : void()), ...);
  }
  // Calls f.template operator()<T>() for every row, in order.
  template <typename F>
  static void for_each_row(F&& f) {
    (f.template operator()<Strategies>(), ...);
  }
  template <typename T>
  static constexpr StrategyId id_of() {
    size_t row = 0, found = size;
    ((std::is_same_v<T, Strategies> ? (found = row, ++row) : ++row), ...);
    static_assert(((std::is_same_v<T, Strategies> ? 1 : 0) + ...) == 1, "not a registered row");
    return StrategyId(found);
  }
};

using RegisteredStrategies =
    StrategyList<BsdfStrategy, AreaStrategy, SolidAngleStrategy, ProjectedSolidAngleStrategy,
                 LtcStrategy, LineAreaStrategy, LineSolidAngleStrategy, LineBd16Strategy>;

template <typename T>
inline constexpr StrategyId strategy_id = RegisteredStrategies::id_of<T>();

using PreparedStrategy = RegisteredStrategies::Prepared;

// The edge a line direction follows (rand has no fixed edge; line strategies refuse it).
inline LineAxis line_axis(LineDirection direction) {
  return direction == LineDirection::V ? LineAxis::Edge2 : LineAxis::Edge1;
}

}  // namespace penumbra
