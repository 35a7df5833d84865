#pragma once
// A JSON value together with its path from the document root ("$.lights[2].radius") and the
// name of the file it came from, so that every check can throw a FormatError that says where
// and what. Shared by the readers of the `penumbra/*@1` formats (SCENE_FORMAT.md).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

// Parses JSON text into a document. Refuses nesting deeper than `max_depth` before parsing (so a
// hostile document cannot exhaust the stack) and maps syntax errors to FormatError at path "$"
// with the byte offset. `source` names the file in messages.
nlohmann::json parse_json_document(std::string_view text, const std::string& source, int max_depth);

// The path of a member of the object at `parent`: `$.a.b`, or `$.a["odd key"]`.
std::string json_member_path(const std::string& parent, std::string_view key);

class JsonNode {
 public:
  JsonNode(const nlohmann::json& value, std::string path, const std::string& source)
      : value_(&value), path_(std::move(path)), source_(&source) {}

  const nlohmann::json& value() const { return *value_; }
  const std::string& path() const { return path_; }
  const std::string& source() const { return *source_; }

  // Throws FormatError at this node's path: "<problem> (in <source>)".
  [[noreturn]] void fail(const std::string& problem) const;
  // The value as short JSON text for messages (long values are cut).
  std::string quoted_value() const;

  // Objects.
  void expect_object() const;
  bool has(std::string_view key) const;
  // Throws "missing required key 'k'" (naming a present key that looks like a misspelling).
  JsonNode required(std::string_view key) const;
  std::optional<JsonNode> optional(std::string_view key) const;
  // Keys of this object not in `known`, each reported as "<path>: unknown key ignored".
  void collect_unknown_keys(std::initializer_list<std::string_view> known,
                            std::vector<std::string>& warnings) const;
  std::vector<std::string> keys() const;
  JsonNode member(const std::string& key) const;

  // Arrays.
  void expect_array() const;
  size_t size() const;  // of an array
  JsonNode at(size_t index) const;

  // Scalars; each checks the type and finiteness and names the bad value.
  double number() const;
  int64_t integer() const;  // an integral number (512 or 512.0)
  std::string string() const;
  Vec3 vec3() const;  // [x, y, z]

 private:
  const nlohmann::json* value_;
  std::string path_;
  const std::string* source_;
};

}  // namespace penumbra
