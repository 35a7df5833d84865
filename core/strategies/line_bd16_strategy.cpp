#include "core/strategies/line_bd16_strategy.h"

#include <vector>

namespace penumbra {

namespace {

Bd16Direction bd16_direction(LineDirection direction) {
  return direction == LineDirection::U   ? Bd16Direction::U
         : direction == LineDirection::V ? Bd16Direction::V
                                         : Bd16Direction::Random;
}

}  // namespace

std::optional<std::string> LineBd16Strategy::refusal(const Scene& scene, LineDirection) {
  for (size_t l = 0; l < scene.lights.size(); ++l)
    for (const Material& material : scene.materials)
      if (auto why = Bd16LineSampler::unsupported(scene.lights[l], material))
        return "strategy \"line-bd16\" cannot shade light " + std::to_string(l) +
               " on material \"" + material.name + "\": " + *why;
  return std::nullopt;
}

LineBd16Strategy::LineBd16Strategy(const ShadingPoint& sp, const Light& light,
                                   LineDirection direction)
    : sampler_(light, *sp.material, sp.position, sp.normal, sp.wo, bd16_direction(direction)) {}

Rgb LineBd16Strategy::estimate_sum(Pattern pattern, const StreamKey& stream, int n,
                                   const LineQuery& query) const {
  thread_local std::vector<double> offsets;
  offsets.resize(n);
  generate_1d(pattern, stream, offsets);
  // The direction's two numbers come from a counter no pattern sample uses.
  constexpr uint32_t kDirectionSample = 0xffffffffu;
  Vec2 direction_u{random_uniform(stream, kDirectionSample, 0),
                   random_uniform(stream, kDirectionSample, 1)};
  Rgb sum;
  for (double offset : offsets) sum += sampler_.estimate(offset, direction_u, query);
  return sum;
}

}  // namespace penumbra
