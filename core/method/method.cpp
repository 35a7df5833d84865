#include "core/method/method.h"

#include <array>
#include <charconv>
#include <optional>
#include <utility>

#include "core/scene/scene.h"

namespace penumbra {

namespace {

constexpr std::array<std::pair<std::string_view, Combine>, 7> kCombines{{
    {"balance", Combine::Balance},
    {"power", Combine::Power},
    {"avg", Combine::Avg},
    {"smooth", Combine::Smooth},
    {"smooth-fixed", Combine::SmoothFixed},
    {"weighted", Combine::Weighted},
    {"clamped-optimal", Combine::ClampedOptimal},
}};
constexpr std::array<std::pair<std::string_view, LineDirection>, 3> kDirections{{
    {"u", LineDirection::U},
    {"v", LineDirection::V},
    {"rand", LineDirection::Rand},
}};

template <typename Table>
std::string alternatives(const Table& table) {
  std::string out;
  for (const auto& [name, value] : table) {
    if (!out.empty()) out.append(", ");
    out.append(name);
  }
  return out;
}

// The registry's strategy names, for messages.
std::string strategy_alternatives() {
  std::string out;
  for (const StrategyInfo& info : registered_strategy_infos()) {
    if (!out.empty()) out.append(", ");
    out.append(info.name);
  }
  return out;
}

template <typename Table>
auto lookup(const Table& table, std::string_view name) -> const typename Table::value_type* {
  for (const auto& entry : table)
    if (entry.first == name) return &entry;
  return nullptr;
}

// Text quoted in an error message: at most ~60 characters (the message travels as gRPC status
// metadata, which has a size limit), with the elided length said.
std::string excerpt(std::string_view text) {
  constexpr size_t kMax = 60;
  if (text.size() <= kMax) return std::string(text);
  return std::string(text.substr(0, kMax)) + "... (" + std::to_string(text.size()) + " characters)";
}

// A recursive-descent parser over the text with its position, for error messages.
class MethodParser {
 public:
  explicit MethodParser(std::string_view text) : text_(text) {}

  MethodSpec parse() {
    if (text_.empty()) fail("is empty; expected e.g. \"sa\" or \"bsdf+line-sa:v/balance\"");
    MethodSpec method;
    method.terms.push_back(parse_term());
    while (peek() == '+') {
      ++pos_;
      if (int(method.terms.size()) >= kMaxMethodTerms)
        fail("has more than " + std::to_string(kMaxMethodTerms) + " terms");
      method.terms.push_back(parse_term());
    }
    if (peek() == '/') {
      ++pos_;
      std::string_view word = read_word();
      const auto* entry = lookup(kCombines, word);
      if (!entry)
        fail("unknown combination \"" + excerpt(word) + "\"; expected one of " +
             alternatives(kCombines));
      method.combine = entry->second;
    }
    if (pos_ != text_.size()) fail("unexpected character '" + std::string(1, text_[pos_]) + "'");
    if (method.total_samples() > kMaxMethodSamples)
      fail("asks for " + std::to_string(method.total_samples()) +
           " samples per shading point; at most " + std::to_string(kMaxMethodSamples));
    return method;
  }

 private:
  char peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }

  [[noreturn]] void fail(const std::string& what) const {
    throw FormatError("method", "\"" + excerpt(text_) + "\" " + what + " (at character " +
                                    std::to_string(pos_) + ")");
  }

  std::string_view read_word() {
    size_t start = pos_;
    while (pos_ < text_.size() &&
           (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '-'))
      ++pos_;
    return text_.substr(start, pos_ - start);
  }

  MethodTerm parse_term() {
    MethodTerm term;
    if (std::isdigit(static_cast<unsigned char>(peek()))) {
      size_t start = pos_;
      while (std::isdigit(static_cast<unsigned char>(peek()))) ++pos_;
      std::string_view digits = text_.substr(start, pos_ - start);
      long long count = 0;
      auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), count);
      if (ec != std::errc() || count < 1 || count > kMaxTermCount) {
        pos_ = start;
        fail("has count " + excerpt(digits) + "; counts are 1.." + std::to_string(kMaxTermCount));
      }
      term.count = int(count);
      if (peek() != '*') fail("expected '*' after the count");
      ++pos_;
    }
    size_t word_start = pos_;
    std::string_view word = read_word();
    if (word.empty()) fail("expected a strategy (" + strategy_alternatives() + ")");
    std::optional<StrategyId> strategy = find_strategy(word);
    if (!strategy) {
      pos_ = word_start;
      fail("unknown strategy \"" + excerpt(word) + "\"; expected one of " +
           strategy_alternatives());
    }
    term.strategy = *strategy;
    if (peek() == ':') {
      ++pos_;
      if (!is_line_strategy(term.strategy))
        fail("gives a line direction to \"" + std::string(word) +
             "\", which is not a line strategy");
      std::string_view dir = read_word();
      const auto* d = lookup(kDirections, dir);
      if (!d) fail("unknown line direction \"" + std::string(dir) + "\"; expected u, v or rand");
      term.direction = d->second;
    }
    return term;
  }

  std::string_view text_;
  size_t pos_ = 0;
};

}  // namespace

int MethodSpec::total_samples() const {
  int total = 0;
  for (const MethodTerm& term : terms) total += term.count;
  return total;
}

std::string_view combine_name(Combine combine) {
  for (const auto& [name, value] : kCombines)
    if (value == combine) return name;
  return "?";
}
std::string_view direction_name(LineDirection direction) {
  for (const auto& [name, value] : kDirections)
    if (value == direction) return name;
  return "?";
}

MethodSpec parse_method(std::string_view text) {
  return MethodParser(text).parse();
}

std::string to_string(const MethodSpec& method) {
  std::string out;
  for (size_t i = 0; i < method.terms.size(); ++i) {
    const MethodTerm& term = method.terms[i];
    if (i > 0) out.push_back('+');
    if (term.count != 1) {
      out.append(std::to_string(term.count));
      out.push_back('*');
    }
    out.append(strategy_name(term.strategy));
    if (is_line_strategy(term.strategy)) {
      out.push_back(':');
      out.append(direction_name(term.direction));
    }
  }
  if (method.terms.size() > 1 || method.combine != Combine::Balance) {
    out.push_back('/');
    out.append(combine_name(method.combine));
  }
  return out;
}

}  // namespace penumbra
