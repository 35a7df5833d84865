#include "core/scene/pbrt_params.h"

#include <cmath>

namespace penumbra {

PbrtParams::PbrtParams(const PbrtStatement& statement)
    : statement_(&statement), used_(statement.parameters.size(), false) {}

std::string PbrtParams::what() const {
  if (statement_->arguments.empty()) return statement_->name;
  return statement_->name + " \"" + statement_->arguments[0].text + "\"";
}

const PbrtParameter* PbrtParams::find(const std::string& name) {
  for (size_t i = 0; i < statement_->parameters.size(); ++i)
    if (statement_->parameters[i].name == name) {
      used_[i] = true;
      return &statement_->parameters[i];
    }
  return nullptr;
}

bool PbrtParams::has(const std::string& name) const {
  for (const PbrtParameter& parameter : statement_->parameters)
    if (parameter.name == name) return true;
  return false;
}

void PbrtParams::ignore(const std::string& name) {
  find(name);
}

void PbrtParams::fail(const PbrtParameter& parameter, const std::string& problem) const {
  pbrt_fail(parameter.location,
            what() + ": \"" + parameter.type + " " + parameter.name + "\": " + problem);
}

void PbrtParams::fail(const std::string& problem) const {
  pbrt_fail(statement_->location, what() + ": " + problem);
}

void PbrtParams::check_type(const PbrtParameter& parameter,
                            std::initializer_list<const char*> types) const {
  std::string expected;
  for (const char* type : types) {
    if (parameter.type == type) return;
    expected += (expected.empty() ? "" : " or ") + std::string(type);
  }
  fail(parameter, "wrong type: expected " + expected);
}

const PbrtParameter& PbrtParams::single(const PbrtParameter& parameter) const {
  size_t count = parameter.numeric() ? parameter.numbers.size() : parameter.strings.size();
  if (count != 1) fail(parameter, "expected one value, got " + std::to_string(count));
  return parameter;
}

double PbrtParams::number(const std::string& name, double fallback) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return fallback;
  check_type(*parameter, {"float"});
  return single(*parameter).numbers[0];
}

int64_t PbrtParams::integer(const std::string& name, int64_t fallback) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return fallback;
  check_type(*parameter, {"integer"});
  double value = single(*parameter).numbers[0];
  if (value != std::floor(value) || std::abs(value) > 9.0e15) fail(*parameter, "not an integer");
  return static_cast<int64_t>(value);
}

std::string PbrtParams::string(const std::string& name, const std::string& fallback) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return fallback;
  check_type(*parameter, {"string"});
  return single(*parameter).strings[0];
}

bool PbrtParams::boolean(const std::string& name, bool fallback) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return fallback;
  check_type(*parameter, {"bool"});
  return single(*parameter).strings[0] == "true";
}

std::optional<Vec3> PbrtParams::triple(const std::string& name,
                                       std::initializer_list<const char*> types, const char* what) {
  const std::vector<double>* values = numbers(name, types, 3);
  if (!values) return std::nullopt;
  if (values->size() != 3) fail(*find(name), std::string("expected one ") + what + " (3 numbers)");
  return Vec3((*values)[0], (*values)[1], (*values)[2]);
}

std::optional<Vec3> PbrtParams::point3(const std::string& name) {
  return triple(name, {"point3", "point"}, "point");
}

std::optional<Vec3> PbrtParams::vector3(const std::string& name) {
  return triple(name, {"vector3", "vector"}, "vector");
}

std::optional<Rgb> PbrtParams::color(const std::string& name) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return std::nullopt;
  if (parameter->type == "spectrum" || parameter->type == "blackbody")
    fail(*parameter,
         "spectral and blackbody values are not modelled (Penumbra renders RGB): "
         "give \"rgb " +
             parameter->name + "\"");
  check_type(*parameter, {"rgb", "color", "xyz"});
  if (parameter->numbers.size() != 3)
    fail(*parameter, "expected 3 numbers, got " + std::to_string(parameter->numbers.size()));
  Vec3 c(parameter->numbers[0], parameter->numbers[1], parameter->numbers[2]);
  if (parameter->type == "xyz")
    // CIE XYZ to linear sRGB (D65), the matrix of pbrt-v3's XYZToRGB.
    c = Vec3(3.240479 * c.x - 1.537150 * c.y - 0.498535 * c.z,
             -0.969256 * c.x + 1.875991 * c.y + 0.041556 * c.z,
             0.055648 * c.x - 0.204043 * c.y + 1.057311 * c.z);
  return c;
}

const std::vector<double>* PbrtParams::numbers(const std::string& name,
                                               std::initializer_list<const char*> types,
                                               size_t group) {
  const PbrtParameter* parameter = find(name);
  if (!parameter) return nullptr;
  check_type(*parameter, types);
  if (parameter->numbers.size() % group != 0)
    fail(*parameter, "expected a multiple of " + std::to_string(group) + " numbers, got " +
                         std::to_string(parameter->numbers.size()));
  return &parameter->numbers;
}

void PbrtParams::report_unused(std::vector<std::string>& warnings) const {
  for (size_t i = 0; i < statement_->parameters.size(); ++i)
    if (!used_[i]) {
      const PbrtParameter& parameter = statement_->parameters[i];
      warnings.push_back(parameter.location.str() + ": parameter \"" + parameter.type + " " +
                         parameter.name + "\" of " + what() + " ignored (not used by Penumbra)");
    }
}

}  // namespace penumbra
