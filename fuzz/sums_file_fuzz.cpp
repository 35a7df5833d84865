// libFuzzer target: the sums file reader (core/render/sums_file.h), what `penumbra merge` reads.
//
// Invariants: the reader throws std::invalid_argument and nothing else; a file that decodes has
// a whole-image accumulator whose every pixel has the header's pass count, encodes back to a
// file that decodes to the same sums, and merges with itself shifted past its own passes into
// twice the passes.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/render/sums_file.h"
#include "fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  penumbra::RenderSums sums;
  try {
    sums = penumbra::decode_sums(bytes, "fuzz.sums");
  } catch (const std::invalid_argument&) {
    return 0;
  }
  FUZZ_CHECK(sums.width >= 1 && sums.height >= 1);
  FUZZ_CHECK((sums.sums.rect() == penumbra::TileRect{0, 0, sums.width, sums.height}));
  const int64_t pixels = int64_t(sums.width) * sums.height;
  for (int64_t i = 0; i < pixels; ++i) FUZZ_CHECK(sums.sums.count(i) == sums.passes);

  const penumbra::RenderSums again = penumbra::decode_sums(penumbra::encode_sums(sums), "again");
  FUZZ_CHECK(again.sums == sums.sums);
  FUZZ_CHECK(again.passes == sums.passes && again.first_pass == sums.first_pass);
  FUZZ_CHECK(again.metadata == sums.metadata);

  if (sums.passes > 0 && uint64_t(sums.first_pass) + 2 * uint64_t(sums.passes) < (1ull << 31)) {
    penumbra::RenderSums later = sums;
    later.first_pass = sums.first_pass + sums.passes;
    const penumbra::RenderSums merged = penumbra::merge_sums({sums, later}, {"a", "b"});
    FUZZ_CHECK(merged.passes == 2 * sums.passes);
    FUZZ_CHECK(merged.first_pass == sums.first_pass);
    for (int64_t i = 0; i < pixels; ++i) FUZZ_CHECK(merged.sums.count(i) == 2 * sums.passes);
  }
  return 0;
}
