// libFuzzer target: the method grammar (core/method/method.h). Every input either parses into a
// method within the grammar's limits whose canonical text parses back to the same method, or
// throws FormatError at path "method".

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/method/method.h"
#include "core/scene/scene.h"
#include "fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  std::string_view text(reinterpret_cast<const char*>(data), size);
  MethodSpec method;
  try {
    method = parse_method(text);
  } catch (const FormatError& error) {
    FUZZ_CHECK(error.json_path() == "method");
    return 0;
  }
  FUZZ_CHECK(!method.terms.empty() && int(method.terms.size()) <= kMaxMethodTerms);
  FUZZ_CHECK(method.total_samples() >= 1 && method.total_samples() <= kMaxMethodSamples);
  for (const MethodTerm& term : method.terms) {
    FUZZ_CHECK(term.count >= 1 && term.count <= kMaxTermCount);
    FUZZ_CHECK(is_line_strategy(term.strategy) || term.direction == LineDirection::U);
  }
  std::string canonical = to_string(method);
  FUZZ_CHECK(parse_method(canonical) == method);
  FUZZ_CHECK(to_string(parse_method(canonical)) == canonical);
  return 0;
}
