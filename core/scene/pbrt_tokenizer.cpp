#include "core/scene/pbrt_tokenizer.h"

#include <cctype>
#include <charconv>
#include <cmath>

#include "core/scene/scene.h"

namespace penumbra {

std::string PbrtLocation::str() const {
  return (file ? *file : std::string("<pbrt>")) + ":" + std::to_string(line) + ":" +
         std::to_string(column);
}

void pbrt_fail(const PbrtLocation& location, const std::string& problem) {
  throw FormatError(location.str(), problem);
}

namespace {

bool starts_number(char c, char next) {
  if (std::isdigit(static_cast<unsigned char>(c))) return true;
  if (c == '.') return std::isdigit(static_cast<unsigned char>(next));
  return (c == '-' || c == '+') && (std::isdigit(static_cast<unsigned char>(next)) || next == '.');
}

bool word_character(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
}

// A printable form of a byte for messages: 'x' or a hex code.
std::string show_byte(char c) {
  unsigned char u = static_cast<unsigned char>(c);
  if (u >= 0x21 && u < 0x7f) return std::string("'") + c + "'";
  static constexpr char kHex[] = "0123456789abcdef";
  return std::string("byte 0x") + kHex[u >> 4] + kHex[u & 0xf];
}

}  // namespace

void PbrtTokenizer::advance() {
  if (at_end()) return;
  if (text_[position_] == '\n') {
    ++line_;
    column_ = 1;
  } else {
    ++column_;
  }
  ++position_;
}

void PbrtTokenizer::skip_space_and_comments() {
  while (!at_end()) {
    char c = peek();
    if (c == '#') {
      while (!at_end() && peek() != '\n') advance();
    } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') {
      advance();
    } else {
      return;
    }
  }
}

std::optional<PbrtToken> PbrtTokenizer::next() {
  skip_space_and_comments();
  if (at_end()) return std::nullopt;
  char c = peek();
  if (c == '"') return read_string();
  if (c == '[' || c == ']') {
    PbrtToken token;
    token.kind = c == '[' ? PbrtTokenKind::OpenBracket : PbrtTokenKind::CloseBracket;
    token.text = std::string(1, c);
    token.location = here();
    advance();
    return token;
  }
  if (starts_number(c, peek(1))) return read_number();
  if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return read_word();
  pbrt_fail(here(), "unexpected " + show_byte(c) +
                        " (expected a statement, a quoted string, a number or a bracket)");
}

PbrtToken PbrtTokenizer::read_string() {
  PbrtToken token;
  token.kind = PbrtTokenKind::String;
  token.location = here();
  advance();  // the opening quote
  while (true) {
    if (at_end()) pbrt_fail(token.location, "unterminated string (no closing '\"')");
    char c = peek();
    if (c == '"') {
      advance();
      return token;
    }
    if (c == '\n') pbrt_fail(here(), "newline in a string (strings end on the line they start)");
    if (c == '\\') {
      PbrtLocation escape = here();
      advance();
      if (at_end()) pbrt_fail(token.location, "unterminated string (ends in a backslash)");
      char e = peek();
      switch (e) {
        case 'n':
          token.text.push_back('\n');
          break;
        case 't':
          token.text.push_back('\t');
          break;
        case 'r':
          token.text.push_back('\r');
          break;
        case 'b':
          token.text.push_back('\b');
          break;
        case 'f':
          token.text.push_back('\f');
          break;
        case '\\':
          token.text.push_back('\\');
          break;
        case '\'':
          token.text.push_back('\'');
          break;
        case '"':
          token.text.push_back('"');
          break;
        default:
          pbrt_fail(escape, "unknown escape \\" + std::string(1, e) + " in a string");
      }
      advance();
      continue;
    }
    token.text.push_back(c);
    advance();
  }
}

PbrtToken PbrtTokenizer::read_number() {
  PbrtToken token;
  token.kind = PbrtTokenKind::Number;
  token.location = here();
  size_t start = position_;
  // The longest run that could belong to a number; from_chars then decides.
  while (!at_end() && (word_character(peek()) || peek() == '+' ||
                       ((peek() == '-') && position_ > start &&
                        (text_[position_ - 1] == 'e' || text_[position_ - 1] == 'E'))))
    advance();
  token.text = std::string(text_.substr(start, position_ - start));
  const char* first = token.text.data();
  const char* last = first + token.text.size();
  if (*first == '+') ++first;  // from_chars takes no leading '+'
  auto [end, error] = std::from_chars(first, last, token.number);
  if (error == std::errc::result_out_of_range || (end == last && !std::isfinite(token.number)))
    pbrt_fail(token.location, "number " + token.text + " is out of range");
  if (error != std::errc() || end != last)
    pbrt_fail(token.location, "malformed number '" + token.text + "'");
  return token;
}

PbrtToken PbrtTokenizer::read_word() {
  PbrtToken token;
  token.kind = PbrtTokenKind::Word;
  token.location = here();
  while (!at_end() && (std::isalnum(static_cast<unsigned char>(peek())) || peek() == '_'))
    token.text.push_back(peek()), advance();
  return token;
}

}  // namespace penumbra
