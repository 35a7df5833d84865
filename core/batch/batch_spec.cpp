#include "core/batch/batch_spec.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/method/method.h"
#include "core/sampling/pattern.h"
#include "core/scene/json_node.h"

namespace penumbra {

namespace {

std::string number_text(double x) {
  std::ostringstream out;
  out.precision(12);
  out << x;
  return out.str();
}

class BatchSpecParser {
 public:
  BatchSpecParser(const std::string& source, const BatchLimits& limits)
      : source_(source), limits_(limits) {}

  BatchSpec parse(std::string_view text) {
    if (text.size() > limits_.max_json_bytes)
      throw FormatError("$", "the batch spec has " + std::to_string(text.size()) +
                                 " bytes, more than the limit max_json_bytes = " +
                                 std::to_string(limits_.max_json_bytes) + " (in " + source_ + ")");
    nlohmann::json document = parse_json_document(text, source_, limits_.max_json_depth);
    JsonNode root(document, "$", source_);
    root.expect_object();
    check_format(root.required("format"));
    root.collect_unknown_keys({"format", "name", "description", "scene", "methods", "budget",
                               "reference", "regions", "seed", "repeats", "baseline", "strict"},
                              spec_.warnings);
    if (auto name = root.optional("name")) {
      spec_.name = text_value(*name, "name");
      if (spec_.name.empty()) name->fail("the name must not be empty");
    } else {
      spec_.name = default_name();
    }
    if (auto description = root.optional("description")) text_value(*description, "description");
    spec_.scene = text_value(root.required("scene"), "scene");
    if (spec_.scene.empty()) root.required("scene").fail("the scene must not be empty");
    parse_methods(root.required("methods"));
    parse_budget(root.required("budget"));
    if (auto reference = root.optional("reference")) parse_reference(*reference);
    if (auto regions = root.optional("regions")) parse_regions(*regions);
    if (auto seed = root.optional("seed")) {
      int64_t value = seed->integer();
      if (value < 0)
        seed->fail("the seed must be a non-negative integer, got " + seed->quoted_value());
      spec_.seed = uint64_t(value);
    }
    if (auto baseline = root.optional("baseline")) {
      spec_.baseline = text_value(*baseline, "the baseline");
      bool known = false;
      for (const BatchMethodSpec& method : spec_.methods)
        known = known || method.label == spec_.baseline;
      if (!known)
        baseline->fail("the baseline \"" + spec_.baseline + "\" is not the label of a method");
    }
    if (auto repeats = root.optional("repeats")) {
      int64_t value = repeats->integer();
      if (value < 1 || value > int64_t(limits_.max_repeats))
        repeats->fail("repeats must be an integer in [1, " + std::to_string(limits_.max_repeats) +
                      "] (limit max_repeats), got " + repeats->quoted_value());
      spec_.repeats = uint32_t(value);
    }
    if (auto strict = root.optional("strict")) {
      if (!strict->value().is_boolean())
        strict->fail("strict must be true or false, got " + strict->quoted_value());
      spec_.strict = strict->value().get<bool>();
    }
    return std::move(spec_);
  }

 private:
  std::string default_name() const {
    std::filesystem::path path(source_);
    std::string stem = path.extension() == ".json" ? path.stem().string() : std::string();
    return stem.empty() ? std::string("batch") : stem;
  }

  void check_format(const JsonNode& node) const {
    std::string format = node.string();
    if (format == kBatchFormat) return;
    if (format.rfind("penumbra/batch@", 0) == 0)
      node.fail("unsupported batch format version '" + format + "' (this reader reads " +
                std::string(kBatchFormat) + ")");
    node.fail("not a batch spec: format is '" + format + "', expected '" +
              std::string(kBatchFormat) + "'");
  }

  // A string within the text length limit.
  std::string text_value(const JsonNode& node, const char* what) const {
    std::string text = node.string();
    if (text.size() > limits_.max_text_length)
      node.fail(std::string(what) + " has " + std::to_string(text.size()) +
                " characters, more than the limit max_text_length = " +
                std::to_string(limits_.max_text_length));
    return text;
  }

  void parse_methods(const JsonNode& node) {
    node.expect_array();
    if (node.size() == 0) node.fail("a batch needs at least one method");
    if (node.size() > limits_.max_methods)
      node.fail(std::to_string(node.size()) + " methods, more than the limit max_methods = " +
                std::to_string(limits_.max_methods));
    std::map<std::string, std::string> label_paths;
    for (size_t i = 0; i < node.size(); ++i) {
      JsonNode entry = node.at(i);
      BatchMethodSpec method;
      std::optional<JsonNode> label_node;
      if (entry.value().is_string()) {
        method.method = text_value(entry, "the method");
        check_method(entry, method.method);
        method.sampler = "stratified";
      } else {
        entry.expect_object();
        entry.collect_unknown_keys({"method", "sampler", "label"}, spec_.warnings);
        JsonNode method_node = entry.required("method");
        method.method = text_value(method_node, "the method");
        check_method(method_node, method.method);
        method.sampler = "stratified";
        if (auto sampler = entry.optional("sampler")) {
          method.sampler = text_value(*sampler, "the sampler");
          if (!parse_pattern(method.sampler))
            sampler->fail("unknown sampler '" + method.sampler +
                          "' (expected random, stratified, uniform, uniform-jitter, halton, "
                          "sobol or cmj)");
        }
        if (auto label = entry.optional("label")) {
          method.label = text_value(*label, "the label");
          if (method.label.empty()) label->fail("the label must not be empty");
          label_node = label;
        }
      }
      if (method.label.empty()) method.label = method.method;
      std::string path = label_node ? label_node->path() : entry.path();
      auto [it, fresh] = label_paths.emplace(method.label, path);
      if (!fresh)
        (label_node ? *label_node : entry)
            .fail("label '" + method.label + "' is used twice (also at " + it->second +
                  "); give each method a distinct \"label\"");
      spec_.methods.push_back(std::move(method));
    }
  }

  void check_method(const JsonNode& node, const std::string& text) const {
    try {
      parse_method(text);
    } catch (const FormatError& error) {
      node.fail(std::string("not a method: ") + error.what());
    }
  }

  void parse_budget(const JsonNode& node) {
    node.expect_object();
    node.collect_unknown_keys({"seconds", "spp"}, spec_.warnings);
    if (!node.has("seconds") && !node.has("spp"))
      node.fail("a budget needs \"seconds\" (compute seconds per method) and/or \"spp\" (a list)");
    if (auto seconds = node.optional("seconds")) {
      double value = seconds->number();
      if (!(value > 0) || !(value <= limits_.max_seconds))
        seconds->fail("the budget in compute seconds must be positive and at most " +
                      number_text(limits_.max_seconds) + " (limit max_seconds), got " +
                      seconds->quoted_value());
      spec_.budget_seconds = value;
    }
    if (auto spp = node.optional("spp")) {
      spp->expect_array();
      if (spp->size() == 0) spp->fail("the spp list must not be empty");
      if (spp->size() > limits_.max_spp_levels)
        spp->fail(std::to_string(spp->size()) + " spp levels, more than the limit " +
                  "max_spp_levels = " + std::to_string(limits_.max_spp_levels));
      std::set<uint32_t> levels;
      for (size_t i = 0; i < spp->size(); ++i) {
        JsonNode level = spp->at(i);
        levels.insert(spp_value(level));
      }
      spec_.budget_spp.assign(levels.begin(), levels.end());
    }
  }

  uint32_t spp_value(const JsonNode& node) const {
    int64_t value = node.integer();
    if (value < 1 || value > int64_t(limits_.max_spp))
      node.fail("spp must be an integer in [1, " + std::to_string(limits_.max_spp) +
                "] (limit max_spp), got " + node.quoted_value());
    return uint32_t(value);
  }

  void parse_reference(const JsonNode& node) {
    BatchReferenceSpec& reference = spec_.reference;
    if (node.value().is_string()) {
      std::string text = text_value(node, "the reference");
      if (text == "auto") {
        reference.kind = BatchReferenceKind::Auto;
      } else if (text.rfind("job:", 0) == 0) {
        reference.kind = BatchReferenceKind::Job;
        reference.job_id = text.substr(4);
        if (reference.job_id.empty()) node.fail("\"job:\" needs a job id, e.g. \"job:job-7\"");
      } else if (text.empty()) {
        node.fail("the reference must be \"auto\", \"job:<id>\" or the path of an EXR file");
      } else {
        reference.kind = BatchReferenceKind::Exr;
        reference.exr_path = text;
      }
      return;
    }
    if (!node.value().is_object())
      node.fail(
          "the reference must be \"auto\", \"job:<id>\", the path of an EXR file or an "
          "object {\"method\", \"sampler\", \"spp\", \"seed\", \"target_share\", "
          "\"max_seconds\"} or {\"kind\": \"exact\", ...}, got " +
          node.quoted_value());
    if (auto kind = node.optional("kind")) {
      const std::string text = text_value(*kind, "the reference kind");
      if (text == "exact") {
        parse_exact_reference(node);
        return;
      }
      if (text != "auto")
        kind->fail("the reference kind must be \"auto\" or \"exact\", got " + kind->quoted_value());
    }
    node.collect_unknown_keys(
        {"kind", "method", "sampler", "spp", "seed", "target_share", "max_seconds"},
        spec_.warnings);
    reference.kind = BatchReferenceKind::Auto;
    if (auto method = node.optional("method")) {
      reference.method = text_value(*method, "the method");
      check_method(*method, reference.method);
    }
    if (auto sampler = node.optional("sampler")) {
      reference.sampler = text_value(*sampler, "the sampler");
      if (!parse_pattern(reference.sampler))
        sampler->fail("unknown sampler '" + reference.sampler + "'");
    }
    if (auto spp = node.optional("spp")) {
      if (spp->value().is_string()) {
        if (spp->string() != "auto")
          spp->fail("the reference's spp must be \"auto\" (sized) or an integer, got " +
                    spp->quoted_value());
      } else {
        reference.spp = spp_value(*spp);
        reference.sized = false;
      }
    }
    if (auto share = node.optional("target_share")) {
      if (!reference.sized)
        share->fail("target_share sizes the reference; it needs \"spp\": \"auto\", not a count");
      const double value = share->number();
      if (!(value >= 1e-4) || !(value <= 0.5))
        share->fail(
            "target_share must lie in [0.0001, 0.5] (the reference's noise as a share of "
            "the best method's error), got " +
            share->quoted_value());
      reference.target_share = value;
    }
    if (auto seconds = node.optional("max_seconds")) {
      if (!reference.sized)
        seconds->fail("max_seconds caps a sized reference; it needs \"spp\": \"auto\"");
      const double value = seconds->number();
      if (!(value > 0) || !(value <= limits_.max_seconds))
        seconds->fail(
            "max_seconds (compute seconds for the reference) must be positive and at "
            "most " +
            number_text(limits_.max_seconds) + " (limit max_seconds), got " +
            seconds->quoted_value());
      reference.max_seconds = value;
    }
    if (auto seed = node.optional("seed")) {
      int64_t value = seed->integer();
      if (value < 0)
        seed->fail("the seed must be a non-negative integer, got " + seed->quoted_value());
      reference.seed = uint64_t(value);
    }
  }

  void parse_exact_reference(const JsonNode& node) {
    BatchReferenceSpec& reference = spec_.reference;
    node.collect_unknown_keys({"kind", "camera_samples", "fallback", "fallback_samples", "seed"},
                              spec_.warnings);
    reference.kind = BatchReferenceKind::Exact;
    reference.exr_path = "(the exact reference the client renders)";
    if (auto samples = node.optional("camera_samples"))
      reference.camera_samples = spp_value(*samples);
    if (auto fallback = node.optional("fallback")) {
      reference.fallback_method = text_value(*fallback, "the fallback method");
      check_method(*fallback, reference.fallback_method);
    }
    if (auto samples = node.optional("fallback_samples"))
      reference.fallback_samples = spp_value(*samples);
    if (auto seed = node.optional("seed")) {
      int64_t value = seed->integer();
      if (value < 0)
        seed->fail("the seed must be a non-negative integer, got " + seed->quoted_value());
      reference.seed = uint64_t(value);
    }
  }

  void parse_regions(const JsonNode& node) {
    node.expect_object();
    std::vector<std::string> names = node.keys();
    if (names.size() > limits_.max_regions)
      node.fail(std::to_string(names.size()) + " regions, more than the limit max_regions = " +
                std::to_string(limits_.max_regions));
    for (const std::string& name : names) {
      JsonNode entry = node.member(name);
      if (name.empty() || name.size() > limits_.max_text_length)
        entry.fail("a region name must have 1 to " + std::to_string(limits_.max_text_length) +
                   " characters");
      if (name == "image") entry.fail("\"image\" names the whole image and cannot be a region");
      if (!entry.value().is_array() || entry.value().size() != 4)
        entry.fail("a region is [x0, y0, x1, y1], got " + entry.quoted_value());
      int64_t c[4];
      for (size_t k = 0; k < 4; ++k) {
        JsonNode corner = entry.at(k);
        c[k] = corner.integer();
        if (c[k] < 0 || c[k] > limits_.max_coordinate)
          corner.fail("a region corner must lie in [0, " + std::to_string(limits_.max_coordinate) +
                      "], got " + corner.quoted_value());
      }
      if (c[0] >= c[2] || c[1] >= c[3])
        entry.fail("empty region " + entry.quoted_value() + " (needs x0 < x1 and y0 < y1)");
      spec_.regions[name] = Region{static_cast<int>(c[0]), static_cast<int>(c[1]),
                                   static_cast<int>(c[2]), static_cast<int>(c[3])};
    }
  }

  const std::string& source_;
  const BatchLimits& limits_;
  BatchSpec spec_;
};

}  // namespace

BatchSpec parse_batch_spec(std::string_view json, std::string_view source_name,
                           const BatchLimits& limits) {
  std::string source(source_name.empty() ? std::string_view("<batch>") : source_name);
  try {
    return BatchSpecParser(source, limits).parse(json);
  } catch (const FormatError&) {
    throw;
  } catch (const std::exception& error) {
    // nlohmann or the standard library on input we did not foresee: still a format error.
    throw FormatError(
        "$", std::string("cannot read the batch spec: ") + error.what() + " (in " + source + ")");
  }
}

std::string file_safe_label(std::string_view label) {
  std::string safe;
  safe.reserve(label.size());
  for (char c : label) {
    bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                c == '.' || c == '_' || c == '-';
    safe.push_back(keep ? c : '_');
  }
  if (safe.empty() || safe == "." || safe == "..") safe = "_" + safe;
  if (safe.size() > 128) safe.resize(128);
  return safe;
}

}  // namespace penumbra
