// The penumbra/batch@1 reader: a full spec, defaults, and every refusal naming its field.
#include "core/batch/batch_spec.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace penumbra {
namespace {

const char* kFull = R"({
  "format": "penumbra/batch@1",
  "name": "fig1",
  "scene": "monoliths",
  "methods": [{"method": "line-sa:v", "sampler": "halton", "label": "ours"}, "sa",
              {"method": "bsdf+sa"}],
  "budget": {"seconds": 10, "spp": [64, 16, 64]},
  "reference": {"method": "bsdf+sa", "spp": 256, "seed": 9},
  "regions": {"penumbra": [1, 2, 30, 40]},
  "seed": 7,
  "repeats": 3,
  "strict": true,
  "future": true
})";

TEST(BatchSpec, ReadsEveryField) {
  BatchSpec spec = parse_batch_spec(kFull, "fig1.json");
  EXPECT_EQ(spec.name, "fig1");
  EXPECT_EQ(spec.scene, "monoliths");
  ASSERT_EQ(spec.methods.size(), 3u);
  EXPECT_EQ(spec.methods[0].method, "line-sa:v");
  EXPECT_EQ(spec.methods[0].sampler, "halton");
  EXPECT_EQ(spec.methods[0].label, "ours");
  EXPECT_EQ(spec.methods[1].method, "sa");
  EXPECT_EQ(spec.methods[1].sampler, "stratified");
  EXPECT_EQ(spec.methods[1].label, "sa");
  EXPECT_EQ(spec.methods[2].label, "bsdf+sa");
  ASSERT_TRUE(spec.budget_seconds.has_value());
  EXPECT_DOUBLE_EQ(*spec.budget_seconds, 10.0);
  EXPECT_EQ(spec.budget_spp, (std::vector<uint32_t>{16, 64}));  // sorted, distinct
  EXPECT_EQ(spec.reference.kind, BatchReferenceKind::Auto);
  EXPECT_EQ(spec.reference.spp, 256u);
  EXPECT_FALSE(spec.reference.sized) << "a given spp is not sized";
  EXPECT_EQ(spec.reference.seed, 9u);
  ASSERT_EQ(spec.regions.count("penumbra"), 1u);
  EXPECT_EQ(spec.regions.at("penumbra").x1, 30);
  EXPECT_EQ(spec.seed, 7u);
  EXPECT_EQ(spec.repeats, 3u);
  EXPECT_TRUE(spec.strict);
  ASSERT_EQ(spec.warnings.size(), 1u);
  EXPECT_NE(spec.warnings[0].find("$.future"), std::string::npos);
}

TEST(BatchSpec, DefaultsAndReferenceForms) {
  const char* minimal = R"({"format": "penumbra/batch@1", "scene": "s.json",
    "methods": ["sa"], "budget": {"spp": [4]}})";
  BatchSpec spec = parse_batch_spec(minimal, "dir/my-batch.json");
  EXPECT_EQ(spec.name, "my-batch");
  EXPECT_FALSE(spec.strict) << "scene warnings are printed and carried by default";
  EXPECT_FALSE(spec.budget_seconds.has_value());
  EXPECT_EQ(spec.reference.kind, BatchReferenceKind::Auto);
  EXPECT_EQ(spec.reference.method, "bsdf+sa");
  EXPECT_TRUE(spec.reference.sized) << "the default reference is sized";
  EXPECT_DOUBLE_EQ(spec.reference.target_share, 0.01);
  EXPECT_DOUBLE_EQ(spec.reference.max_seconds, 300);
  EXPECT_EQ(spec.seed, 1u);
  EXPECT_EQ(spec.repeats, 3u);  // intervals need repeats: three by default

  auto with_reference = [](const std::string& reference) {
    return R"({"format": "penumbra/batch@1", "scene": "s", "methods": ["sa"],
      "budget": {"seconds": 1}, "reference": )" +
           reference + "}";
  };
  BatchSpec job = parse_batch_spec(with_reference(R"("job:job-7")"), "b");
  EXPECT_EQ(job.reference.kind, BatchReferenceKind::Job);
  EXPECT_EQ(job.reference.job_id, "job-7");
  BatchSpec sized = parse_batch_spec(with_reference(R"("auto")"), "b");
  EXPECT_EQ(sized.reference.kind, BatchReferenceKind::Auto);
  EXPECT_TRUE(sized.reference.sized);
  BatchSpec tuned = parse_batch_spec(
      with_reference(R"({"method": "sa", "spp": "auto", "target_share": 0.05, "max_seconds": 20})"),
      "b");
  EXPECT_TRUE(tuned.reference.sized);
  EXPECT_EQ(tuned.reference.method, "sa");
  EXPECT_DOUBLE_EQ(tuned.reference.target_share, 0.05);
  EXPECT_DOUBLE_EQ(tuned.reference.max_seconds, 20);
  BatchSpec unsized = parse_batch_spec(with_reference(R"({"spp": 64})"), "b");
  EXPECT_FALSE(unsized.reference.sized);
  EXPECT_EQ(unsized.reference.spp, 64u);
  BatchSpec exr = parse_batch_spec(with_reference(R"("refs/ref.exr")"), "b");
  EXPECT_EQ(exr.reference.kind, BatchReferenceKind::Exr);
  EXPECT_EQ(exr.reference.exr_path, "refs/ref.exr");
}

// Each case: the document, the JSON path its error must name, and a word of the message.
struct BadCase {
  std::string json;
  std::string path;
  std::string words;
};

std::string spec_with(const std::string& replace_key, const std::string& value) {
  std::map<std::string, std::string> fields = {
      {"format", R"("penumbra/batch@1")"},
      {"scene", R"("monoliths")"},
      {"methods", R"(["sa"])"},
      {"budget", R"({"seconds": 2})"},
  };
  if (value.empty())
    fields.erase(replace_key);
  else
    fields[replace_key] = value;
  std::string json = "{";
  for (const auto& [key, text] : fields) {
    if (json.size() > 1) json += ", ";
    json += "\"" + key + "\": " + text;
  }
  return json + "}";
}

TEST(BatchSpec, EveryErrorNamesItsField) {
  std::vector<BadCase> cases = {
      {"{", "$", "invalid JSON"},
      {"[1]", "$", "object"},
      {spec_with("format", ""), "$.format", "missing"},
      {spec_with("format", R"("penumbra/batch@2")"), "$.format", "version"},
      {spec_with("format", R"("penumbra/scene@1")"), "$.format", "not a batch"},
      {spec_with("scene", ""), "$.scene", "missing"},
      {spec_with("strict", "1"), "$.strict", "true or false"},
      {spec_with("scene", "3"), "$.scene", "string"},
      {spec_with("scene", R"("")"), "$.scene", "empty"},
      {spec_with("methods", ""), "$.methods", "missing"},
      {spec_with("methods", "[]"), "$.methods", "at least one"},
      {spec_with("methods", R"(["sa", "nonsense"])"), "$.methods[1]", "not a method"},
      {spec_with("methods", R"([{"sampler": "halton"}])"), "$.methods[0].method", "missing"},
      {spec_with("methods", R"([{"method": "sa", "sampler": "blue"}])"), "$.methods[0].sampler",
       "unknown sampler"},
      {spec_with("methods", R"(["sa", "sa"])"), "$.methods[1]", "used twice"},
      {spec_with("methods",
                 R"([{"method": "sa", "label": "x"}, {"method": "area", "label": "x"}])"),
       "$.methods[1].label", "used twice"},
      {spec_with("methods", R"([{"method": "sa", "label": ""}])"), "$.methods[0].label", "empty"},
      {spec_with("budget", ""), "$.budget", "missing"},
      {spec_with("budget", "{}"), "$.budget", "seconds"},
      {spec_with("budget", R"({"seconds": -1})"), "$.budget.seconds", "positive"},
      {spec_with("budget", R"({"seconds": 0})"), "$.budget.seconds", "positive"},
      {spec_with("budget", R"({"seconds": 1e999})"), "$", "invalid JSON"},
      {spec_with("budget", R"({"seconds": "NaN"})"), "$.budget.seconds", "number"},
      {spec_with("budget", R"({"seconds": 1e9})"), "$.budget.seconds", "max_seconds"},
      {spec_with("budget", R"({"spp": []})"), "$.budget.spp", "empty"},
      {spec_with("budget", R"({"spp": [4, 0]})"), "$.budget.spp[1]", "spp"},
      {spec_with("budget", R"({"spp": [4, 2.5]})"), "$.budget.spp[1]", "integer"},
      {spec_with("budget", R"({"spp": [99999999]})"), "$.budget.spp[0]", "max_spp"},
      {spec_with("reference", "3"), "$.reference", "reference"},
      {spec_with("reference", R"("")"), "$.reference", "reference"},
      {spec_with("reference", R"("job:")"), "$.reference", "job id"},
      {spec_with("reference", R"({"spp": -4})"), "$.reference.spp", "spp"},
      {spec_with("reference", R"({"method": "bogus"})"), "$.reference.method", "not a method"},
      {spec_with("reference", R"({"spp": "many"})"), "$.reference.spp", "\"auto\""},
      {spec_with("reference", R"({"spp": "auto", "target_share": 0})"), "$.reference.target_share",
       "[0.0001, 0.5]"},
      {spec_with("reference", R"({"target_share": 0.9})"), "$.reference.target_share",
       "[0.0001, 0.5]"},
      {spec_with("reference", R"({"target_share": "1%"})"), "$.reference.target_share", "number"},
      {spec_with("reference", R"({"spp": 64, "target_share": 0.01})"), "$.reference.target_share",
       "needs \"spp\": \"auto\""},
      {spec_with("reference", R"({"max_seconds": -5})"), "$.reference.max_seconds", "positive"},
      {spec_with("reference", R"({"max_seconds": 1e7})"), "$.reference.max_seconds", "max_seconds"},
      {spec_with("reference", R"({"spp": 16, "max_seconds": 10})"), "$.reference.max_seconds",
       "caps a sized reference"},
      {spec_with("regions", R"({"image": [0, 0, 1, 1]})"), "$.regions.image", "whole image"},
      {spec_with("regions", R"({"a": [0, 0, 1]})"), "$.regions.a", "[x0, y0, x1, y1]"},
      {spec_with("regions", R"({"a": [5, 0, 1, 1]})"), "$.regions.a", "empty region"},
      {spec_with("regions", R"({"a": [-1, 0, 1, 1]})"), "$.regions.a[0]", "corner"},
      {spec_with("regions", R"([1])"), "$.regions", "object"},
      {spec_with("seed", "-3"), "$.seed", "non-negative"},
      {spec_with("seed", "1.5"), "$.seed", "integer"},
      {spec_with("repeats", "0"), "$.repeats", "repeats"},
      {spec_with("repeats", "1000"), "$.repeats", "max_repeats"},
      {spec_with("name", R"("")"), "$.name", "empty"},
      {spec_with("name", "\"" + std::string(2000, 'x') + "\""), "$.name", "max_text_length"},
      {std::string(1000, '[') + std::string(1000, ']'), "$", "nesting"},
  };
  for (const BadCase& c : cases) {
    try {
      parse_batch_spec(c.json, "bad.json");
      ADD_FAILURE() << "accepted: " << c.json;
    } catch (const FormatError& error) {
      std::string message = error.what();
      EXPECT_EQ(message.rfind(c.path + ":", 0), 0u) << "wanted path " << c.path << ": " << message;
      EXPECT_NE(message.find(c.words), std::string::npos)
          << "wanted '" << c.words << "': " << message;
      EXPECT_NE(message.find("bad.json"), std::string::npos) << message;
    }
  }
}

TEST(BatchSpec, RefusesOversizedDocumentsAndCounts) {
  BatchLimits limits;
  limits.max_json_bytes = 64;
  EXPECT_THROW(parse_batch_spec(std::string(100, ' '), "big.json", limits), FormatError);
  std::string methods = "[";
  for (int i = 0; i < 70; ++i) methods += (i ? ",\"" : "\"") + std::to_string(i + 1) + "*sa\"";
  methods += "]";
  try {
    parse_batch_spec(spec_with("methods", methods), "many.json");
    ADD_FAILURE() << "accepted 70 methods";
  } catch (const FormatError& error) {
    EXPECT_NE(std::string(error.what()).find("max_methods"), std::string::npos) << error.what();
  }
}

TEST(BatchSpec, FileSafeLabels) {
  EXPECT_EQ(file_safe_label("line-sa:v"), "line-sa_v");
  EXPECT_EQ(file_safe_label("bsdf+sa/balance"), "bsdf_sa_balance");
  EXPECT_EQ(file_safe_label(""), "_");
  EXPECT_EQ(file_safe_label(".."), "_..");
  EXPECT_EQ(file_safe_label("../x"), ".._x");
}

// Every bundled batch reads without warnings and names a scene that exists: a bundled scene by
// name, or a file by a path relative to the batch's folder (as the client resolves it). Paths into
// ../shared/peer-scenes are only checked where that folder is present.
TEST(BatchSpec, BundledBatchesRead) {
  const std::filesystem::path source = PENUMBRA_SOURCE_DIR;
  const std::filesystem::path dir = source / "batches";
  const bool peer_scenes = std::filesystem::exists(source / ".." / "shared" / "peer-scenes");
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    BatchSpec spec = parse_batch_spec(text.str(), entry.path().string());
    EXPECT_TRUE(spec.warnings.empty()) << entry.path() << ": " << spec.warnings.front();
    const bool is_path = spec.scene.find('/') != std::string::npos ||
                         spec.scene.ends_with(".json") || spec.scene.ends_with(".pbrt");
    const std::filesystem::path scene =
        is_path ? dir / spec.scene : source / "scenes" / (spec.scene + ".json");
    const bool in_peer_scenes = spec.scene.find("shared/peer-scenes/") != std::string::npos;
    if (!in_peer_scenes || peer_scenes) {
      EXPECT_TRUE(std::filesystem::exists(scene)) << entry.path() << " names " << spec.scene;
    }
    ++count;
  }
  EXPECT_GE(count, 1);
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

TEST(BatchSpec, ExactReferenceAndBaseline) {
  BatchSpec spec = parse_batch_spec(
      R"({"format": "penumbra/batch@1", "scene": "s", "methods": ["sa", "area"],
          "budget": {"seconds": 1}, "baseline": "area",
          "reference": {"kind": "exact", "camera_samples": 9, "fallback": "bsdf",
                        "fallback_samples": 32}})",
      "b");
  EXPECT_EQ(spec.reference.kind, BatchReferenceKind::Exact);
  EXPECT_EQ(spec.reference.camera_samples, 9u);
  EXPECT_EQ(spec.reference.fallback_method, "bsdf");
  EXPECT_EQ(spec.reference.fallback_samples, 32u);
  EXPECT_EQ(spec.baseline, "area");
  auto fails_at = [](const std::string& text, const std::string& path) {
    try {
      parse_batch_spec(text, "b");
      ADD_FAILURE() << "accepted " << text;
    } catch (const FormatError& error) {
      EXPECT_EQ(error.json_path(), path) << error.what();
    }
  };
  const std::string head =
      R"({"format": "penumbra/batch@1", "scene": "s", "methods": ["sa"], "budget": {"spp": [2]}, )";
  fails_at(head + R"("baseline": "nope"})", "$.baseline");
  fails_at(head + R"("reference": {"kind": "magic"}})", "$.reference.kind");
  fails_at(head + R"("reference": {"kind": "exact", "camera_samples": 0}})",
           "$.reference.camera_samples");
  fails_at(head + R"("reference": {"kind": "exact", "fallback": "no-such"}})",
           "$.reference.fallback");
}

}  // namespace
}  // namespace penumbra
