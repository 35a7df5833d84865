#pragma once
// The statement layer of the pbrt-v3 scene format: each statement with its fixed arguments and
// its parameter list ("float fov" [ 45 ]), `Include` followed into the included file, and the
// file, line and column of every piece for error messages. What the statements mean is the scene
// builder's business (pbrt_scene_builder.h); this layer knows only their shapes.

#include <functional>
#include <string>
#include <vector>

#include "core/scene/pbrt_tokenizer.h"

namespace penumbra {

// One entry of a parameter list: `"rgb Kd" [ 0.5 0.5 0.5 ]`.
struct PbrtParameter {
  std::string type;  // as written: integer, float, point3 (or point), rgb (or color), bool, ...
  std::string name;
  std::vector<double> numbers;       // numeric types
  std::vector<std::string> strings;  // string, texture, bool ("true"/"false"), spectrum files
  PbrtLocation location;             // of the "type name" string
  bool numeric() const { return strings.empty(); }
};

struct PbrtStatement {
  std::string name;  // e.g. "Shape"
  PbrtLocation location;
  std::vector<PbrtToken> arguments;  // the fixed arguments before the parameter list
  std::vector<PbrtParameter> parameters;
};

// Returns the bytes of a file named by its normalized path relative to the main scene file's
// folder (pbrt-v3 resolves Include and every file name against that folder); throws
// std::invalid_argument saying why it cannot.
using PbrtFileReader = std::function<std::string(const std::string& relative_path)>;

struct PbrtParseLimits {
  int max_include_depth = 32;
  size_t max_file_bytes = size_t{1} << 30;
};

// Parses `text` (the main file, named `source` in messages) and calls `on_statement` for each
// statement in order, following Include statements through `read_file` (the included file's
// statements come in place of the Include). `on_include` is told of each included file (its
// normalized relative path and bytes) so the caller can hash it. Throws FormatError naming
// file:line:column for every syntax error, an unknown statement, a wrong argument, a missing,
// cyclic or too deeply nested Include.
void parse_pbrt(const std::string& text, const std::string& source, const PbrtFileReader& read_file,
                const std::function<void(const PbrtStatement&)>& on_statement,
                const std::function<void(const std::string&, const std::string&)>& on_include,
                const PbrtParseLimits& limits = {});

// The pbrt-v3 statements this parser knows (every statement of the format).
const std::vector<std::string>& pbrt_statement_names();

}  // namespace penumbra
