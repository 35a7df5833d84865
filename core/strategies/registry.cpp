#include "core/strategies/registry.h"

#include <array>

#include "core/strategies/registered_strategies.h"

namespace penumbra {

namespace {

// The light view of every row, read from the rows themselves.
const std::array<StrategyInfo, RegisteredStrategies::size>& infos() {
  static const std::array<StrategyInfo, RegisteredStrategies::size> table = [] {
    std::array<StrategyInfo, RegisteredStrategies::size> out{};
    size_t row = 0;
    RegisteredStrategies::for_each_row([&]<typename T>() {
      out[row++] = StrategyInfo{T::name(), T::kFamily, T::kRectangleStrata};
    });
    return out;
  }();
  return table;
}

}  // namespace

std::span<const StrategyInfo> registered_strategy_infos() {
  return infos();
}

const StrategyInfo& strategy_info(StrategyId id) {
  return infos().at(id);
}

std::optional<StrategyId> find_strategy(std::string_view name) {
  const auto& table = infos();
  for (size_t i = 0; i < table.size(); ++i)
    if (table[i].name == name) return StrategyId(i);
  return std::nullopt;
}

std::string_view strategy_name(StrategyId id) {
  return id < infos().size() ? infos()[id].name : std::string_view("?");
}

bool is_line_strategy(StrategyId id) {
  return strategy_info(id).family != StrategyFamily::Point;
}

}  // namespace penumbra
