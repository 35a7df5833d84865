#include "core/scene/json_node.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace penumbra {

namespace {

// Levenshtein distance with an early cap, for "did you mean" hints on missing keys.
size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> previous(b.size() + 1), current(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

bool is_plain_identifier(std::string_view key) {
  if (key.empty() || !(std::isalpha(static_cast<unsigned char>(key[0])) || key[0] == '_'))
    return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

// "string \"512\"", "array [1,2]", "null": the type and, when it says more, the value.
std::string describe(const nlohmann::json& value, const std::string& quoted) {
  std::string type = value.is_number() ? "number" : value.type_name();
  return value.is_null() ? type : type + " " + quoted;
}

}  // namespace

nlohmann::json parse_json_document(std::string_view text, const std::string& source,
                                   int max_depth) {
  // Refuse deep nesting before the parser sees it: count brackets outside strings.
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;  // skip the escaped character
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth)
        throw FormatError("$", "JSON nesting deeper than " + std::to_string(max_depth) +
                                   " levels at byte " + std::to_string(i) + " (in " + source + ")");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  try {
    return nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::exception& error) {
    throw FormatError("$", std::string("invalid JSON: ") + error.what() + " (in " + source + ")");
  }
}

std::string json_member_path(const std::string& parent, std::string_view key) {
  if (is_plain_identifier(key)) return parent + "." + std::string(key);
  return parent + "[" + nlohmann::json(std::string(key)).dump() + "]";
}

void JsonNode::fail(const std::string& problem) const {
  throw FormatError(path_, problem + " (in " + *source_ + ")");
}

std::string JsonNode::quoted_value() const {
  std::string text = value_->dump();
  constexpr size_t kMaxShown = 60;
  if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
  return text;
}

void JsonNode::expect_object() const {
  if (!value_->is_object()) fail("expected an object, got " + describe(*value_, quoted_value()));
}

bool JsonNode::has(std::string_view key) const {
  return value_->is_object() && value_->contains(key);
}

JsonNode JsonNode::required(std::string_view key) const {
  expect_object();
  auto found = value_->find(key);
  if (found != value_->end()) return {*found, json_member_path(path_, key), *source_};
  std::string hint;
  for (const auto& [present, unused] : value_->items()) {
    if (edit_distance(present, key) <= 2) {
      hint = " (found '" + present + "': misspelled?)";
      break;
    }
  }
  throw FormatError(json_member_path(path_, key), "missing required key '" + std::string(key) +
                                                      "'" + hint + " (in " + *source_ + ")");
}

std::optional<JsonNode> JsonNode::optional(std::string_view key) const {
  expect_object();
  auto found = value_->find(key);
  if (found == value_->end()) return std::nullopt;
  return JsonNode(*found, json_member_path(path_, key), *source_);
}

void JsonNode::collect_unknown_keys(std::initializer_list<std::string_view> known,
                                    std::vector<std::string>& warnings) const {
  for (const auto& [key, unused] : value_->items()) {
    if (std::find(known.begin(), known.end(), key) == known.end())
      warnings.push_back(json_member_path(path_, key) + ": unknown key ignored");
  }
}

std::vector<std::string> JsonNode::keys() const {
  expect_object();
  std::vector<std::string> out;
  for (const auto& [key, unused] : value_->items()) out.push_back(key);
  return out;
}

JsonNode JsonNode::member(const std::string& key) const {
  return {value_->at(key), json_member_path(path_, key), *source_};
}

void JsonNode::expect_array() const {
  if (!value_->is_array()) fail("expected an array, got " + describe(*value_, quoted_value()));
}

size_t JsonNode::size() const {
  expect_array();
  return value_->size();
}

JsonNode JsonNode::at(size_t index) const {
  expect_array();
  return {(*value_)[index], path_ + "[" + std::to_string(index) + "]", *source_};
}

double JsonNode::number() const {
  if (!value_->is_number()) fail("expected a number, got " + describe(*value_, quoted_value()));
  double x = value_->get<double>();
  if (!std::isfinite(x)) fail("number is not finite: " + quoted_value());
  return x;
}

int64_t JsonNode::integer() const {
  if (value_->is_number_integer()) {
    if (value_->is_number_unsigned() && value_->get<uint64_t>() > static_cast<uint64_t>(INT64_MAX))
      fail("integer out of range: " + quoted_value());
    return value_->get<int64_t>();
  }
  double x = number();
  if (x != std::floor(x) || std::abs(x) > 9.0e15)
    fail("expected an integer, got " + quoted_value());
  return static_cast<int64_t>(x);
}

std::string JsonNode::string() const {
  if (!value_->is_string()) fail("expected a string, got " + describe(*value_, quoted_value()));
  return value_->get<std::string>();
}

Vec3 JsonNode::vec3() const {
  if (!value_->is_array() || value_->size() != 3)
    fail("expected an array of 3 numbers [x, y, z], got " + quoted_value());
  return {at(0).number(), at(1).number(), at(2).number()};
}

}  // namespace penumbra
