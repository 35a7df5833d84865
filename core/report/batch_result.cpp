// Reader of the batch result folder's index (s2_batch_contract.md). Every check names the key
// path in the contract's form, "methods[2].runs[0].exr", so a broken batch.json says where.

#include "core/report/batch_result.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

namespace penumbra {

namespace {

// A JSON value with its key path and the file it came from.
class KeyNode {
 public:
  KeyNode(const nlohmann::json& value, std::string path, const std::string& source)
      : value_(value), path_(std::move(path)), source_(source) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw BatchResultError(source_, path_, problem);
  }
  const nlohmann::json& value() const { return value_; }

  KeyNode required(const std::string& key) const {
    expect_object();
    auto it = value_.find(key);
    if (it == value_.end()) throw BatchResultError(source_, member_path(key), "missing");
    return KeyNode(*it, member_path(key), source_);
  }
  // Absent and null are both "not given".
  std::optional<KeyNode> optional(const std::string& key) const {
    expect_object();
    auto it = value_.find(key);
    if (it == value_.end() || it->is_null()) return std::nullopt;
    return KeyNode(*it, member_path(key), source_);
  }
  void expect_object() const {
    if (!value_.is_object()) fail("expected an object, got " + type_name());
  }
  size_t size() const {
    if (!value_.is_array()) fail("expected an array, got " + type_name());
    return value_.size();
  }
  KeyNode at(size_t index) const {
    return KeyNode(value_[index], path_ + "[" + std::to_string(index) + "]", source_);
  }
  std::string string() const {
    if (!value_.is_string()) fail("expected a string, got " + type_name());
    return value_.get<std::string>();
  }
  double number() const {
    if (!value_.is_number()) fail("expected a number, got " + type_name());
    double number = value_.get<double>();
    if (!std::isfinite(number)) fail("not a finite number");
    return number;
  }
  double non_negative() const {
    double value = number();
    if (value < 0) fail("negative (" + std::to_string(value) + ")");
    return value;
  }
  int64_t integer(int64_t min, int64_t max) const {
    if (!value_.is_number()) fail("expected an integer, got " + type_name());
    double number = value_.get<double>();
    if (!std::isfinite(number) || std::floor(number) != number)
      fail("expected an integer, got " + value_.dump());
    if (number < double(min) || number > double(max))
      fail("out of range [" + std::to_string(min) + ", " + std::to_string(max) +
           "]: " + value_.dump());
    if (value_.is_number_unsigned()) return int64_t(value_.get<uint64_t>());
    if (value_.is_number_integer()) return value_.get<int64_t>();
    return int64_t(number);
  }
  uint64_t unsigned_integer() const {
    if (value_.is_number_unsigned()) return value_.get<uint64_t>();
    return uint64_t(integer(0, std::numeric_limits<int64_t>::max()));
  }
  bool boolean() const {
    if (!value_.is_boolean()) fail("expected true or false, got " + type_name());
    return value_.get<bool>();
  }

 private:
  std::string member_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  std::string type_name() const { return value_.type_name(); }

  const nlohmann::json& value_;
  std::string path_;
  const std::string& source_;
};

constexpr int64_t kMaxPixels = 1 << 16;  // per image side
constexpr int64_t kMaxSpp = int64_t(1) << 32;

ErrorSummary parse_error_entry(const KeyNode& node) {
  ErrorSummary summary;
  summary.mrse = node.required("mrse").non_negative();
  summary.mse = node.required("mse").non_negative();
  summary.rmse = node.required("rmse").non_negative();
  return summary;
}

BatchRun parse_run(const KeyNode& node, bool budgeted) {
  BatchRun run;
  run.equal_time = budgeted;
  if (auto equal_time = node.optional("equal_time")) run.equal_time = equal_time->boolean();
  run.repeat = int(node.required("repeat").integer(0, 1 << 20));
  run.seed = node.required("seed").unsigned_integer();
  if (auto job = node.optional("job_id")) run.job_id = job->string();
  run.exr = node.required("exr").string();
  if (run.exr.empty()) node.required("exr").fail("empty file name");
  run.spp = uint32_t(node.required("spp").integer(1, kMaxSpp - 1));
  run.compute_seconds = node.required("compute_seconds").non_negative();
  if (auto wall = node.optional("wall_seconds")) run.wall_seconds = wall->non_negative();
  if (auto curve = node.optional("curve")) {
    for (size_t i = 0; i < curve->size(); ++i) {
      KeyNode point = curve->at(i);
      BatchCurvePoint p;
      p.passes = uint32_t(point.required("passes").integer(1, kMaxSpp - 1));
      p.compute_seconds = point.required("compute_seconds").non_negative();
      if (auto wall = point.optional("wall_seconds")) p.wall_seconds = wall->non_negative();
      p.mrse = point.required("mrse").non_negative();
      if (auto regions = point.optional("regions")) {
        regions->expect_object();
        for (const auto& [name, value] : regions->value().items())
          p.regions[name] = regions->required(name).non_negative();
      }
      run.curve.push_back(p);
    }
  }
  KeyNode errors = node.required("errors");
  for (size_t i = 0; i < errors.size(); ++i) {
    KeyNode entry = errors.at(i);
    std::string region = entry.required("region").string();
    if (run.errors.count(region))
      entry.required("region").fail("duplicate region '" + region + "'");
    run.errors[region] = parse_error_entry(entry);
  }
  return run;
}

BatchMethod parse_method(const KeyNode& node) {
  BatchMethod method;
  method.label = node.required("label").string();
  if (method.label.empty()) node.required("label").fail("empty label");
  method.method = node.required("method").string();
  if (auto sampler = node.optional("sampler")) method.sampler = sampler->string();
  if (auto budget = node.optional("budget_seconds")) method.budget_seconds = budget->non_negative();
  if (auto error = node.optional("error")) method.error = error->string();
  KeyNode runs = node.required("runs");
  for (size_t i = 0; i < runs.size(); ++i)
    method.runs.push_back(parse_run(runs.at(i), method.budget_seconds.has_value()));
  return method;
}

}  // namespace

std::map<std::string, Region> BatchResult::region_map() const {
  std::map<std::string, Region> map;
  for (const BatchRegion& region : regions) map[region.name] = region.rect;
  return map;
}

BatchResult parse_batch_result(const std::string& json_text, const std::string& source) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& error) {
    throw BatchResultError(source, "", std::string("not valid JSON: ") + error.what());
  }
  KeyNode root(document, "", source);
  root.expect_object();

  BatchResult result;
  std::string format = root.required("format").string();
  if (format != kBatchResultFormat)
    root.required("format").fail("expected \"" + std::string(kBatchResultFormat) + "\", got \"" +
                                 format + "\"");
  result.batch_id = root.required("batch_id").string();
  if (auto name = root.optional("name")) result.name = name->string();
  if (auto spec = root.optional("spec")) result.spec_json = spec->value().dump(2);

  KeyNode scene = root.required("scene");
  result.scene.name = scene.required("name").string();
  if (auto hash = scene.optional("hash")) result.scene.hash = hash->string();
  result.scene.width = int(scene.required("width").integer(1, kMaxPixels));
  result.scene.height = int(scene.required("height").integer(1, kMaxPixels));

  if (auto regions = root.optional("regions")) {
    for (size_t i = 0; i < regions->size(); ++i) {
      KeyNode node = regions->at(i);
      BatchRegion region;
      region.name = node.required("name").string();
      if (region.name.empty() || region.name == "image")
        node.required("name").fail("\"" + region.name +
                                   "\" cannot name a region (\"image\" is implicit)");
      for (const BatchRegion& other : result.regions)
        if (other.name == region.name) node.required("name").fail("duplicate region name");
      KeyNode rect = node.required("rect");
      if (rect.size() != 4) rect.fail("expected [x0, y0, x1, y1]");
      int corners[4];
      for (size_t k = 0; k < 4; ++k) corners[k] = int(rect.at(k).integer(0, kMaxPixels));
      region.rect = Region{corners[0], corners[1], corners[2], corners[3]};
      if (region.rect.x1 <= region.rect.x0 || region.rect.y1 <= region.rect.y0)
        rect.fail("empty rectangle (needs x0 < x1 and y0 < y1)");
      if (region.rect.x0 >= result.scene.width || region.rect.y0 >= result.scene.height)
        rect.fail("outside the " + std::to_string(result.scene.width) + "x" +
                  std::to_string(result.scene.height) + " image");
      result.regions.push_back(region);
    }
  }

  KeyNode reference = root.required("reference");
  result.reference.exr = reference.required("exr").string();
  if (auto method = reference.optional("method")) result.reference.method = method->string();
  if (auto sampler = reference.optional("sampler")) result.reference.sampler = sampler->string();
  if (auto spp = reference.optional("spp"))
    result.reference.spp = uint32_t(spp->integer(0, kMaxSpp - 1));
  if (auto job = reference.optional("job_id")) result.reference.job_id = job->string();
  if (auto cached = reference.optional("cached")) result.reference.cached = cached->boolean();
  if (auto kind = reference.optional("kind")) result.reference.kind = kind->string();
  if (auto node = reference.optional("sizing")) {
    BatchReferenceSizing sizing;
    sizing.probe_spp = uint32_t(node->required("probe_spp").integer(0, kMaxSpp - 1));
    sizing.target_share = node->required("target_share").non_negative();
    sizing.max_seconds = node->required("max_seconds").non_negative();
    sizing.seconds_per_pass = node->required("seconds_per_pass").non_negative();
    sizing.required_spp = node->required("required_spp").non_negative();
    sizing.capped = node->required("capped").boolean();
    sizing.predicted_share = node->required("predicted_share").non_negative();
    sizing.predicted_seconds = node->required("predicted_seconds").non_negative();
    sizing.deciding_region = node->required("deciding_region").string();
    sizing.best_method = node->required("best_method").string();
    result.reference.sizing = sizing;
  }

  KeyNode methods = root.required("methods");
  for (size_t i = 0; i < methods.size(); ++i) {
    KeyNode node = methods.at(i);
    BatchMethod method = parse_method(node);
    for (const BatchMethod& other : result.methods)
      if (other.label == method.label)
        node.required("label").fail("duplicate label \"" + method.label + "\"");
    // Every ran method's errors name "image" and each region.
    for (size_t r = 0; r < method.runs.size(); ++r) {
      const BatchRun& run = method.runs[r];
      std::string path =
          "methods[" + std::to_string(i) + "].runs[" + std::to_string(r) + "].errors";
      if (!run.errors.count("image"))
        throw BatchResultError(source, path, "no entry for region \"image\"");
      for (const BatchRegion& region : result.regions)
        if (!run.errors.count(region.name))
          throw BatchResultError(source, path, "no entry for region \"" + region.name + "\"");
    }
    result.methods.push_back(std::move(method));
  }
  return result;
}

BatchResult read_batch_result(const std::filesystem::path& result_dir) {
  std::filesystem::path index = result_dir / "batch.json";
  std::ifstream file(index, std::ios::binary);
  if (!file) throw BatchResultError(index.string(), "", "cannot open");
  std::stringstream text;
  text << file.rdbuf();
  BatchResult result = parse_batch_result(text.str(), "batch.json");

  // Every EXR named must be inside the folder (no absolute paths, no "..") and exist.
  auto check_file = [&](const std::string& relative, const std::string& key_path) {
    std::filesystem::path path(relative);
    if (path.is_absolute())
      throw BatchResultError("batch.json", key_path, "absolute path \"" + relative + "\"");
    for (const auto& part : path)
      if (part == "..")
        throw BatchResultError("batch.json", key_path,
                               "path leaves the folder: \"" + relative + "\"");
    if (!std::filesystem::is_regular_file(result_dir / path))
      throw BatchResultError("batch.json", key_path,
                             "file not found: " + (result_dir / path).string());
  };
  check_file(result.reference.exr, "reference.exr");
  for (size_t i = 0; i < result.methods.size(); ++i)
    for (size_t r = 0; r < result.methods[i].runs.size(); ++r)
      check_file(result.methods[i].runs[r].exr,
                 "methods[" + std::to_string(i) + "].runs[" + std::to_string(r) + "].exr");
  return result;
}

std::string reference_depth_warning(const BatchResult& result) {
  const BatchReference& reference = result.reference;
  // An exact reference's spp counts camera samples of closed-form shading, not noisy passes.
  if (reference.spp == 0 || reference.method.rfind("exact", 0) == 0) return "";
  // A sized reference was sized by its noise, which is what this rule of thumb stands in for.
  if (reference.sizing) return "";
  uint32_t deepest = 0;
  std::string label;
  for (const BatchMethod& method : result.methods)
    for (const BatchRun& run : method.runs)
      if (run.spp > deepest) {
        deepest = run.spp;
        label = method.label;
      }
  if (deepest == 0 || double(reference.spp) >= kReferenceSppFactor * deepest) return "";
  char ratio[32];
  std::snprintf(ratio, sizeof ratio, "%.2g", double(reference.spp) / deepest);
  return "the reference has " + std::to_string(reference.spp) + " spp, only " + ratio + "x the " +
         std::to_string(deepest) + " spp of " + label +
         "'s runs: it is barely cleaner than what it judges, and its noise is a large part of "
         "every error (give the reference " +
         std::to_string(uint32_t(kReferenceSppFactor) * deepest) + " spp or more)";
}

std::string reference_sizing_text(const BatchReference& reference) {
  if (!reference.sizing) return "";
  const BatchReferenceSizing& sizing = *reference.sizing;
  char text[512];
  if (sizing.capped)
    std::snprintf(text, sizeof text,
                  "sized from %u-spp probes: %u spp, capped by max_seconds = %g compute s (the "
                  "%g%% target asked for %.0f spp); predicted reference share %.2f%% in \"%s\" "
                  "(best method there: %s)",
                  sizing.probe_spp, reference.spp, sizing.max_seconds, 100 * sizing.target_share,
                  std::ceil(sizing.required_spp), 100 * sizing.predicted_share,
                  sizing.deciding_region.c_str(), sizing.best_method.c_str());
  else
    std::snprintf(text, sizeof text,
                  "sized from %u-spp probes: %u spp for a %g%% target (%.0f asked for, rounded up "
                  "to a quarter octave; cap max_seconds = %g not reached, %.1f compute s "
                  "predicted); predicted reference share %.2f%% in \"%s\" (best method there: %s)",
                  sizing.probe_spp, reference.spp, 100 * sizing.target_share,
                  std::ceil(sizing.required_spp), sizing.max_seconds, sizing.predicted_seconds,
                  100 * sizing.predicted_share, sizing.deciding_region.c_str(),
                  sizing.best_method.c_str());
  return text;
}

}  // namespace penumbra
