#pragma once
// The strategies of the method grammar (`bsdf`, `area`, `sa`, `psa`, `ltc`, `line-area`,
// `line-sa`, `line-bd16`), registered once: the list in registered_strategies.h has one row per
// strategy class, and everything else (the names the grammar accepts, the family a term belongs
// to, the strata it draws on, whether it can run on a scene, its preparation and its sampling
// and density entry points) is read from the rows. Adding a strategy is one file and one row.
//
// This header is the light view of the registry (names and properties by id) for code that
// only needs to name strategies, such as the method grammar; core/strategies/
// registered_strategies.h has the strategy types themselves, for the estimator.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/scene/scene.h"

namespace penumbra {

// A line strategy's direction: along the light's edge1 (u), edge2 (v), or random per shading
// point (rand).
enum class LineDirection { U, V, Rand };

// How the estimator runs a strategy (strategy.h describes each family's shape):
//   Point         draws points with an area density and evaluates that density anywhere (MIS)
//   Line          draws points on traced lines (visible by construction); its density at a point
//                 needs the line through that point (a line query)
//   AnalyticLine  integrates whole lines in closed form: an estimate per line, no point density
enum class StrategyFamily { Point, Line, AnalyticLine };

// A row of the registry, by its position (the grammar's order).
using StrategyId = uint8_t;

struct StrategyInfo {
  std::string_view name;
  StrategyFamily family = StrategyFamily::Point;
  // Draws on the light's rectangle (u along edge1, v along edge2): strata of the quad's aspect.
  bool rectangle_strata = false;
};

// Every row, in registry order.
std::span<const StrategyInfo> registered_strategy_infos();
const StrategyInfo& strategy_info(StrategyId id);
std::optional<StrategyId> find_strategy(std::string_view name);

std::string_view strategy_name(StrategyId id);
// Line and analytic-line strategies (the ones that take a direction in the grammar).
bool is_line_strategy(StrategyId id);

// Why the strategy cannot run on this scene with this line direction (which light or material,
// and why), empty when it can.
std::optional<std::string> strategy_refusal(StrategyId id, const Scene& scene,
                                            LineDirection direction);

}  // namespace penumbra
