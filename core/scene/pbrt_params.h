#pragma once
// Typed access to a pbrt-v3 statement's parameter list, with pbrt-v3's defaults and type rules;
// every parameter not read is reported as ignored, so nothing a file says is dropped silently.

#include <optional>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/pbrt_parser.h"
#include "core/scene/scene.h"

namespace penumbra {

class PbrtParams {
 public:
  explicit PbrtParams(const PbrtStatement& statement);

  // Where the statement is ("file:line:column") and what it is ("Shape \"sphere\"").
  const PbrtStatement& statement() const { return *statement_; }
  std::string what() const;

  // The parameter called `name`, marked as read; empty when the file does not give it.
  const PbrtParameter* find(const std::string& name);
  bool has(const std::string& name) const;

  // Single values; each checks the declared type (e.g. "float") and the count, and throws
  // FormatError at the parameter's location when they are wrong.
  double number(const std::string& name, double fallback);     // float
  int64_t integer(const std::string& name, int64_t fallback);  // integer
  std::string string(const std::string& name, const std::string& fallback);
  bool boolean(const std::string& name, bool fallback);
  std::optional<Vec3> point3(const std::string& name);   // point3 / point
  std::optional<Vec3> vector3(const std::string& name);  // vector3 / vector
  // A colour: rgb / color, or xyz (converted to linear sRGB as pbrt-v3 does); spectral samples
  // and blackbody are refused.
  std::optional<Rgb> color(const std::string& name);
  // Arrays of a declared type family ("float", "integer", "point3", "normal", "point2", ...),
  // with the length checked to be a multiple of `group`.
  const std::vector<double>* numbers(const std::string& name,
                                     std::initializer_list<const char*> types, size_t group);

  [[noreturn]] void fail(const PbrtParameter& parameter, const std::string& problem) const;
  [[noreturn]] void fail(const std::string& problem) const;

  // Warnings for every parameter nobody read ("...: parameter \"float foo\" of Shape \"x\"
  // ignored (not used by Penumbra)").
  void report_unused(std::vector<std::string>& warnings) const;
  // Marks a parameter as read without reading it (known to have no effect).
  void ignore(const std::string& name);

 private:
  const PbrtParameter& single(const PbrtParameter& parameter) const;
  std::optional<Vec3> triple(const std::string& name, std::initializer_list<const char*> types,
                             const char* what);
  void check_type(const PbrtParameter& parameter, std::initializer_list<const char*> types) const;

  const PbrtStatement* statement_;
  std::vector<bool> used_;
};

}  // namespace penumbra
