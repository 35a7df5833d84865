// The registry's scene checks, apart from its names and properties (registry.cpp): those need only
// the rows' compile-time members, so the method grammar (and its fuzzer) link them without the
// strategies' code; a refusal calls into each strategy's own check.
#include "core/strategies/registered_strategies.h"
#include "core/strategies/registry.h"

namespace penumbra {

std::optional<std::string> strategy_refusal(StrategyId id, const Scene& scene,
                                            LineDirection direction) {
  std::optional<std::string> why;
  RegisteredStrategies::visit_row(id, [&]<typename T>() { why = T::refusal(scene, direction); });
  return why;
}

}  // namespace penumbra
