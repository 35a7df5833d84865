#include "core/scene/pbrt_parser.h"

#include <algorithm>
#include <deque>
#include <map>
#include <optional>
#include <stdexcept>

#include "core/scene/scene.h"
#include "core/scene/scene_path.h"

namespace penumbra {

namespace {

// The fixed arguments of a statement: 'n' a number, 's' a quoted string, 'w' a bare word,
// 'S' one or two strings (MediumInterface), 'M' a 16-number matrix, bracketed or not; a
// trailing '*' means a parameter list follows.
const std::map<std::string, std::string>& statement_shapes() {
  static const std::map<std::string, std::string> shapes = {{"Accelerator", "s*"},
                                                            {"ActiveTransform", "w"},
                                                            {"AreaLightSource", "s*"},
                                                            {"AttributeBegin", ""},
                                                            {"AttributeEnd", ""},
                                                            {"Camera", "s*"},
                                                            {"ConcatTransform", "M"},
                                                            {"CoordinateSystem", "s"},
                                                            {"CoordSysTransform", "s"},
                                                            {"Film", "s*"},
                                                            {"Identity", ""},
                                                            {"Include", "s"},
                                                            {"Integrator", "s*"},
                                                            {"LightSource", "s*"},
                                                            {"LookAt", "nnnnnnnnn"},
                                                            {"MakeNamedMaterial", "s*"},
                                                            {"MakeNamedMedium", "s*"},
                                                            {"Material", "s*"},
                                                            {"MediumInterface", "S"},
                                                            {"NamedMaterial", "s"},
                                                            {"ObjectBegin", "s"},
                                                            {"ObjectEnd", ""},
                                                            {"ObjectInstance", "s"},
                                                            {"PixelFilter", "s*"},
                                                            {"ReverseOrientation", ""},
                                                            {"Rotate", "nnnn"},
                                                            {"Sampler", "s*"},
                                                            {"Scale", "nnn"},
                                                            {"Shape", "s*"},
                                                            {"Texture", "sss*"},
                                                            {"Transform", "M"},
                                                            {"TransformBegin", ""},
                                                            {"TransformEnd", ""},
                                                            {"TransformTimes", "nn"},
                                                            {"Translate", "nnn"},
                                                            {"WorldBegin", ""},
                                                            {"WorldEnd", ""}};
  return shapes;
}

// Parameter types of pbrt-v3 and whether their values are numbers.
const std::map<std::string, bool>& parameter_types() {
  static const std::map<std::string, bool> types = {
      {"integer", true}, {"float", true},     {"point2", true},   {"vector2", true},
      {"point3", true},  {"vector3", true},   {"normal3", true},  {"point", true},
      {"vector", true},  {"normal", true},    {"rgb", true},      {"color", true},
      {"xyz", true},     {"blackbody", true}, {"spectrum", true}, {"bool", false},
      {"string", false}, {"texture", false}};
  return types;
}

std::string describe(const PbrtToken& token) {
  switch (token.kind) {
    case PbrtTokenKind::Word:
      return "'" + token.text + "'";
    case PbrtTokenKind::String:
      return "the string \"" + token.text + "\"";
    case PbrtTokenKind::Number:
      return "the number " + token.text;
    case PbrtTokenKind::OpenBracket:
      return "'['";
    case PbrtTokenKind::CloseBracket:
      return "']'";
  }
  return "a token";
}

class FileParser {
 public:
  struct Context {
    const PbrtFileReader& read_file;
    const std::function<void(const PbrtStatement&)>& on_statement;
    const std::function<void(const std::string&, const std::string&)>& on_include;
    const PbrtParseLimits& limits;
    std::deque<std::string> file_names;  // stable storage for PbrtLocation::file
    std::vector<std::string> include_stack;
  };

  FileParser(Context& context, std::string_view text, const std::string& file, int depth)
      : context_(context), tokens_(text, file), depth_(depth) {}

  void parse() {
    while (std::optional<PbrtToken> token = take()) {
      if (token->kind != PbrtTokenKind::Word)
        pbrt_fail(token->location,
                  "expected a statement (e.g. Shape, WorldBegin), found " + describe(*token));
      auto shape = statement_shapes().find(token->text);
      if (shape == statement_shapes().end())
        pbrt_fail(token->location,
                  "unknown statement '" + token->text + "'" + suggestion(token->text));
      PbrtStatement statement;
      statement.name = token->text;
      statement.location = token->location;
      read_arguments(statement, shape->second);
      if (statement.name == "Include")
        include(statement);
      else
        context_.on_statement(statement);
    }
  }

 private:
  std::optional<PbrtToken> take() {
    if (lookahead_) {
      std::optional<PbrtToken> token = std::move(lookahead_);
      lookahead_.reset();
      return token;
    }
    return tokens_.next();
  }
  const std::optional<PbrtToken>& peek() {
    if (!lookahead_) lookahead_ = tokens_.next();
    return lookahead_;
  }
  PbrtToken expect(PbrtTokenKind kind, const std::string& what, const PbrtStatement& statement) {
    std::optional<PbrtToken> token = take();
    if (!token)
      pbrt_fail(tokens_.here(), "unexpected end of file: " + statement.name + " needs " + what);
    if (token->kind != kind)
      pbrt_fail(token->location, statement.name + " needs " + what + ", found " + describe(*token));
    return *token;
  }

  static std::string suggestion(const std::string& word) {
    for (const auto& [name, unused] : statement_shapes()) {
      std::string a = name, b = word;
      std::transform(a.begin(), a.end(), a.begin(), ::tolower);
      std::transform(b.begin(), b.end(), b.begin(), ::tolower);
      if (a == b) return " (did you mean '" + name + "'?)";
    }
    return "";
  }

  void read_arguments(PbrtStatement& statement, const std::string& shape) {
    for (char kind : shape) {
      switch (kind) {
        case 'n':
          statement.arguments.push_back(expect(PbrtTokenKind::Number, "a number", statement));
          break;
        case 's':
          statement.arguments.push_back(
              expect(PbrtTokenKind::String, "a quoted string", statement));
          break;
        case 'w':
          statement.arguments.push_back(expect(PbrtTokenKind::Word, "a word", statement));
          break;
        case 'S':
          statement.arguments.push_back(
              expect(PbrtTokenKind::String, "a quoted string", statement));
          if (peek() && peek()->kind == PbrtTokenKind::String &&
              !looks_like_parameter(peek()->text))
            statement.arguments.push_back(*take());
          break;
        case 'M':
          read_matrix(statement);
          break;
        case '*':
          read_parameters(statement);
          break;
      }
    }
  }

  // A matrix: 16 numbers, in brackets or bare (pbrt-v3 accepts both).
  void read_matrix(PbrtStatement& statement) {
    bool bracketed = peek() && peek()->kind == PbrtTokenKind::OpenBracket;
    if (bracketed) take();
    for (int i = 0; i < 16; ++i) {
      if (bracketed && peek() && peek()->kind == PbrtTokenKind::CloseBracket)
        pbrt_fail(peek()->location,
                  statement.name + " needs 16 numbers, found " + std::to_string(i));
      statement.arguments.push_back(expect(PbrtTokenKind::Number, "16 numbers", statement));
    }
    if (bracketed) {
      if (peek() && peek()->kind == PbrtTokenKind::Number)
        pbrt_fail(peek()->location, statement.name + " needs exactly 16 numbers, found more");
      expect(PbrtTokenKind::CloseBracket, "']' after its 16 numbers", statement);
    }
  }

  static bool looks_like_parameter(const std::string& text) {
    return text.find(' ') != std::string::npos || text.find('\t') != std::string::npos;
  }

  void read_parameters(PbrtStatement& statement) {
    while (peek() && peek()->kind == PbrtTokenKind::String) {
      PbrtToken declaration = *take();
      PbrtParameter parameter;
      parameter.location = declaration.location;
      // "type name": two words separated by white space.
      size_t type_begin = declaration.text.find_first_not_of(" \t");
      size_t type_end = declaration.text.find_first_of(" \t", type_begin);
      size_t name_begin = type_end == std::string::npos
                              ? std::string::npos
                              : declaration.text.find_first_not_of(" \t", type_end);
      size_t name_end = name_begin == std::string::npos
                            ? std::string::npos
                            : declaration.text.find_first_of(" \t", name_begin);
      if (type_begin == std::string::npos || name_begin == std::string::npos ||
          (name_end != std::string::npos &&
           declaration.text.find_first_not_of(" \t", name_end) != std::string::npos))
        pbrt_fail(declaration.location, "parameter declaration \"" + declaration.text + "\" of " +
                                            statement.name +
                                            " is not \"type name\" (e.g. \"float fov\")");
      parameter.type = declaration.text.substr(type_begin, type_end - type_begin);
      parameter.name = declaration.text.substr(
          name_begin, name_end == std::string::npos ? std::string::npos : name_end - name_begin);
      auto type = parameter_types().find(parameter.type);
      if (type == parameter_types().end())
        pbrt_fail(declaration.location, "unknown parameter type '" + parameter.type + "' in \"" +
                                            declaration.text +
                                            "\" (expected integer, float, point2, vector2, point3, "
                                            "vector3, normal, rgb, xyz, blackbody, spectrum, bool, "
                                            "string or texture)");
      for (const PbrtParameter& other : statement.parameters)
        if (other.name == parameter.name)
          pbrt_fail(declaration.location, "parameter '" + parameter.name + "' given twice to " +
                                              statement.name + " (first at " +
                                              other.location.str() + ")");
      read_values(statement, parameter, type->second);
      statement.parameters.push_back(std::move(parameter));
    }
  }

  void read_values(const PbrtStatement& statement, PbrtParameter& parameter, bool numeric) {
    std::optional<PbrtToken> first = take();
    const std::string what = "a value for \"" + parameter.type + " " + parameter.name + "\"";
    if (!first)
      pbrt_fail(tokens_.here(), "unexpected end of file: " + statement.name + " needs " + what);
    std::vector<PbrtToken> values;
    if (first->kind == PbrtTokenKind::OpenBracket) {
      while (true) {
        std::optional<PbrtToken> token = take();
        if (!token)
          pbrt_fail(first->location, "unterminated '[' (no closing ']') in the value of \"" +
                                         parameter.type + " " + parameter.name + "\"");
        if (token->kind == PbrtTokenKind::CloseBracket) break;
        if (token->kind == PbrtTokenKind::OpenBracket)
          pbrt_fail(token->location,
                    "nested '[' in the value of \"" + parameter.type + " " + parameter.name + "\"");
        values.push_back(std::move(*token));
      }
    } else {
      values.push_back(std::move(*first));
    }
    // pbrt-v3 spectra may also be a file name; everything else is numbers or strings.
    bool strings = !numeric || (parameter.type == "spectrum" && !values.empty() &&
                                values[0].kind == PbrtTokenKind::String);
    for (PbrtToken& value : values) {
      bool is_bare_bool =
          value.kind == PbrtTokenKind::Word && (value.text == "true" || value.text == "false");
      if (strings) {
        if (value.kind == PbrtTokenKind::String || (parameter.type == "bool" && is_bare_bool)) {
          parameter.strings.push_back(std::move(value.text));
          continue;
        }
      } else if (value.kind == PbrtTokenKind::Number) {
        parameter.numbers.push_back(value.number);
        continue;
      }
      pbrt_fail(value.location, "\"" + parameter.type + " " + parameter.name + "\" takes " +
                                    (strings ? "quoted strings" : "numbers") + ", found " +
                                    describe(value));
    }
    if (values.empty())
      pbrt_fail(first->location,
                "empty value for \"" + parameter.type + " " + parameter.name + "\"");
    if (parameter.type == "bool")
      for (const std::string& value : parameter.strings)
        if (value != "true" && value != "false")
          pbrt_fail(first->location, "\"bool " + parameter.name +
                                         "\" must be \"true\" or \"false\", found \"" + value +
                                         "\"");
  }

  void include(const PbrtStatement& statement) {
    const PbrtToken& name = statement.arguments[0];
    if (depth_ + 1 > context_.limits.max_include_depth)
      pbrt_fail(name.location, "Include nested deeper than " +
                                   std::to_string(context_.limits.max_include_depth) + " files");
    std::string relative;
    try {
      relative = normalize_scene_relative_path(name.text);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(name.location, std::string("refused Include path: ") + error.what());
    }
    for (const std::string& open : context_.include_stack)
      if (open == relative)
        pbrt_fail(name.location, "Include of '" + relative + "' includes itself (a cycle)");
    std::string bytes;
    try {
      bytes = context_.read_file(relative);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(name.location, std::string("Include file cannot be read: ") + error.what());
    }
    if (bytes.size() > context_.limits.max_file_bytes)
      pbrt_fail(name.location, "Include file '" + relative +
                                   "' exceeds the limit max_file_bytes = " +
                                   std::to_string(context_.limits.max_file_bytes));
    context_.on_include(relative, bytes);
    context_.file_names.push_back(relative);
    context_.include_stack.push_back(relative);
    FileParser(context_, bytes, context_.file_names.back(), depth_ + 1).parse();
    context_.include_stack.pop_back();
  }

  Context& context_;
  PbrtTokenizer tokens_;
  std::optional<PbrtToken> lookahead_;
  int depth_;
};

}  // namespace

void parse_pbrt(const std::string& text, const std::string& source, const PbrtFileReader& read_file,
                const std::function<void(const PbrtStatement&)>& on_statement,
                const std::function<void(const std::string&, const std::string&)>& on_include,
                const PbrtParseLimits& limits) {
  FileParser::Context context{read_file, on_statement, on_include, limits, {}, {}};
  context.file_names.push_back(source);
  FileParser(context, text, context.file_names.back(), 0).parse();
}

const std::vector<std::string>& pbrt_statement_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& [name, unused] : statement_shapes()) out.push_back(name);
    return out;
  }();
  return names;
}

}  // namespace penumbra
