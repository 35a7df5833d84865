#include "core/sampling/counter_random.h"
#include "core/sampling/pattern.h"

namespace penumbra {

uint64_t random_bits(const StreamKey& key, uint32_t sample, uint32_t dimension) {
  return StreamRandom(key).bits(sample, dimension);
}

double random_uniform(const StreamKey& key, uint32_t sample, uint32_t dimension) {
  return StreamRandom(key).uniform(sample, dimension);
}

}  // namespace penumbra
