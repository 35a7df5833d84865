#pragma once
// The lexical layer of the pbrt-v3 scene format: comments, quoted strings with escapes, numbers,
// brackets and bare words (statement names, `true`/`false`), each with the file, line and column
// it starts at, so that every later error can name where it is.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace penumbra {

// Where a token starts: 1-based line and column (columns count bytes) in `file`.
struct PbrtLocation {
  const std::string* file = nullptr;
  int line = 1;
  int column = 1;
  // "file:line:column", the prefix of every pbrt error message.
  std::string str() const;
};

// Throws FormatError whose path is location.str() and whose message is `problem`.
[[noreturn]] void pbrt_fail(const PbrtLocation& location, const std::string& problem);

enum class PbrtTokenKind { Word, String, Number, OpenBracket, CloseBracket };

struct PbrtToken {
  PbrtTokenKind kind = PbrtTokenKind::Word;
  // Word: the word; String: the unescaped contents; Number: the number's text.
  std::string text;
  double number = 0;  // Number only: the value, parsed as a double (pbrt-v3 reads floats; we keep
                      // every digit the file gives)
  PbrtLocation location;
};

// Splits one file's text into tokens. The text and the file name must outlive the tokenizer.
class PbrtTokenizer {
 public:
  PbrtTokenizer(std::string_view text, const std::string& file) : text_(text), file_(&file) {}

  // The next token, or empty at the end of the text. Throws FormatError (with the location) for
  // an unterminated string, a newline in a string, an unknown escape, a malformed number or a
  // character that starts no token.
  std::optional<PbrtToken> next();
  // The location of the next character (for "unexpected end of file" errors).
  PbrtLocation here() const { return {file_, line_, column_}; }

 private:
  char peek(size_t ahead = 0) const {
    return position_ + ahead < text_.size() ? text_[position_ + ahead] : '\0';
  }
  bool at_end() const { return position_ >= text_.size(); }
  void advance();
  void skip_space_and_comments();
  PbrtToken read_string();
  PbrtToken read_number();
  PbrtToken read_word();

  std::string_view text_;
  const std::string* file_;
  size_t position_ = 0;
  int line_ = 1;
  int column_ = 1;
};

}  // namespace penumbra
