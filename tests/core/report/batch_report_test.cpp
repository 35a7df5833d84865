// The batch report against a batch result folder built here: three methods rendered locally on a
// tiny scene (one refused) at two spp levels, written per the contract (s2_batch_contract.md).
// Checks: the table's numbers are the metrics of the EXRs, charts and figure exist with their
// sizes, recorded errors that differ from the EXRs are an error, malformed batch.json names the
// key, and report.html renders in headless Chromium with every image loaded.
#include "core/report/batch_report.h"

#include <OpenImageIO/imagebuf.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "core/image/metrics.h"
#include "core/image/noise_corrected_mrse.h"
#include "core/render/local_render.h"
#include "core/report/batch_charts.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "core/report/batch_table.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

// A floor, a floating occluder and a quad light; 48x40 pixels.
const char* kSceneJson = R"({
  "format": "penumbra/scene@1", "name": "report-test",
  "camera": { "position": [0, 1.2, 2.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 50, "width": 48, "height": 40 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] },
                 "shiny": { "type": "phong", "kd": [0.2, 0.2, 0.2], "ks": [0.5, 0.5, 0.5], "exponent": 40 } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "box", "min": [-0.2, 0.4, -0.2], "max": [0.2, 0.45, 0.2], "material": "shiny" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";

const std::map<std::string, Region> kRegions = {{"penumbra", {14, 18, 34, 30}},
                                                {"corner", {0, 30, 12, 40}}};

// One folder per test, and per process for the suite's shared batch: ctest runs this program's
// tests in parallel processes, which must not rewrite or delete each other's files.
fs::path output_root() {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string folder = test ? std::string(test->name()) : "suite-" + std::to_string(::getpid());
  fs::path root = fs::path(PENUMBRA_BINARY_DIR) / "test-output" / "report" / folder;
  fs::create_directories(root);
  return root;
}

std::string read_text(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << text;
}

nlohmann::json errors_json(const Image& image, const Image& reference) {
  nlohmann::json errors = nlohmann::json::array();
  for (const auto& [region, summary] : error_summary(image, reference, kRegions))
    errors.push_back(
        {{"region", region}, {"mrse", summary.mrse}, {"mse", summary.mse}, {"rmse", summary.rmse}});
  return errors;
}

// Renders the batch result folder once per test program.
class BatchReportTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(batch_dir_.parent_path()); }

  static void SetUpTestSuite() {
    batch_dir_ = output_root() / "batch";
    fs::remove_all(batch_dir_);
    fs::create_directories(batch_dir_ / "runs");
    auto scene = std::make_shared<const Scene>(parse_scene(kSceneJson, "."));

    // Reference: bsdf+sa at 256 spp.
    Renderer reference_renderer(scene, RenderOptions{"bsdf+sa", Pattern::Stratified, 99});
    RenderBudget budget;
    budget.spp = 256;
    LocalRenderResult reference = render_local(reference_renderer, budget, 2);
    write_exr((batch_dir_ / "reference.exr").string(), reference.film.color,
              &reference.film.variance, {});

    nlohmann::json regions = nlohmann::json::array();
    for (const auto& [name, rect] : kRegions)
      regions.push_back({{"name", name}, {"rect", {rect.x0, rect.y0, rect.x1, rect.y1}}});
    nlohmann::json methods = nlohmann::json::array();
    struct MethodPlan {
      std::string label, method;
      int repeats;
    };
    for (const MethodPlan& plan : {MethodPlan{"sa", "sa", 3}, MethodPlan{"bsdf+sa", "bsdf+sa", 2},
                                   MethodPlan{"refused", "no-such-strategy", 1}}) {
      nlohmann::json method = {{"label", plan.label},
                               {"method", plan.method},
                               {"sampler", "stratified"},
                               {"budget_seconds", nullptr},
                               {"runs", nlohmann::json::array()}};
      try {
        for (int repeat = 0; repeat < plan.repeats; ++repeat) {
          uint64_t seed = 1 + uint64_t(repeat);
          Renderer renderer(scene, RenderOptions{plan.method, Pattern::Stratified, seed});
          for (uint32_t spp : {4u, 16u}) {
            // The curve at pass boundaries: the first k passes are a render at k spp.
            nlohmann::json curve = nlohmann::json::array();
            LocalRenderResult run;
            for (uint32_t passes : {spp / 4, spp / 2, spp}) {
              RenderBudget run_budget;
              run_budget.spp = passes;
              run = render_local(renderer, run_budget, 2);
              curve.push_back({{"passes", passes},
                               {"compute_seconds", run.compute_seconds},
                               {"wall_seconds", run.wall_seconds},
                               {"mrse", mrse(run.film.color, reference.film.color)}});
            }
            std::string exr = "runs/" + plan.label + ".s" + std::to_string(spp) + ".r" +
                              std::to_string(repeat) + ".exr";
            write_exr((batch_dir_ / exr).string(), run.film.color, nullptr, {});
            method["runs"].push_back({{"repeat", repeat},
                                      {"seed", seed},
                                      {"job_id", "job-" + std::to_string(methods.size())},
                                      {"exr", exr},
                                      {"spp", spp},
                                      {"compute_seconds", run.compute_seconds},
                                      {"wall_seconds", run.wall_seconds},
                                      {"curve", curve},
                                      {"errors", errors_json(run.film.color, reference.film.color)},
                                      {"a_future_key", 1}});
          }
        }
      } catch (const FormatError& refusal) {
        method["error"] = refusal.what();
      }
      methods.push_back(method);
    }
    nlohmann::json batch = {
        {"format", "penumbra/batch-result@1"},
        {"batch_id", "local"},
        {"name", "report-test-batch"},
        {"spec", {{"format", "penumbra/batch@1"}, {"scene", "report-test"}}},
        {"scene",
         {{"name", scene->name}, {"hash", scene->content_hash}, {"width", 48}, {"height", 40}}},
        {"regions", regions},
        {"reference",
         {{"exr", "reference.exr"},
          {"method", "bsdf+sa"},
          {"sampler", "stratified"},
          {"spp", 256},
          {"job_id", "local"},
          {"cached", false}}},
        {"methods", methods},
        {"unknown_top_level_key", {{"ignored", true}}}};
    write_text(batch_dir_ / "batch.json", batch.dump(2));
  }

  // A copy of the batch folder with batch.json changed by `edit`.
  static fs::path edited_copy(const std::string& name,
                              const std::function<void(nlohmann::json&)>& edit) {
    fs::path copy = output_root() / name;
    fs::remove_all(copy);
    fs::copy(batch_dir_, copy, fs::copy_options::recursive);
    nlohmann::json batch = nlohmann::json::parse(read_text(copy / "batch.json"));
    edit(batch);
    write_text(copy / "batch.json", batch.dump(2));
    return copy;
  }

  static fs::path batch_dir_;
};
fs::path BatchReportTest::batch_dir_;

double relative_difference(double a, double b) {
  double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0 ? std::abs(a - b) / scale : 0.0;
}

TEST_F(BatchReportTest, TableNumbersAreTheMetricsOfTheExrs) {
  fs::path out = output_root() / "report-table";
  fs::remove_all(out);
  write_batch_report(batch_dir_, out);

  BatchResult result = read_batch_result(batch_dir_);
  Image reference_variance;
  Image reference = read_exr((batch_dir_ / "reference.exr").string(), nullptr, &reference_variance);
  nlohmann::json table = nlohmann::json::parse(read_text(out / "table.json"));
  EXPECT_EQ(table["baseline"], "sa");
  ASSERT_EQ(table["regions"], nlohmann::json({"image", "corner", "penumbra"}));
  // sa: 2 rows (4 and 16 spp) of 2 repeats; bsdf+sa: 2 rows of 1; refused: 1 row.
  ASSERT_EQ(table["rows"].size(), 5u);
  int rows_checked = 0;
  for (const nlohmann::json& row : table["rows"]) {
    if (row.contains("refusal")) {
      EXPECT_EQ(row["label"], "refused");
      EXPECT_NE(row["refusal"].get<std::string>().find("no-such-strategy"), std::string::npos)
          << row["refusal"];
      continue;
    }
    // The same metrics computed here, straight from the EXRs.
    const BatchMethod* method = nullptr;
    for (const BatchMethod& m : result.methods)
      if (m.label == row["label"]) method = &m;
    ASSERT_NE(method, nullptr);
    uint32_t spp = row["spp_min"];
    std::map<std::string, std::vector<double>> values;
    std::vector<double> seconds;
    for (const BatchRun& run : method->runs) {
      if (run.spp != spp) continue;
      Image image = read_exr((batch_dir_ / run.exr).string());
      values["image"].push_back(mrse(image, reference));
      for (const auto& [name, rect] : kRegions)
        values[name].push_back(mrse(image, reference, rect));
      seconds.push_back(run.compute_seconds);
    }
    ASSERT_EQ(row["repeats"].get<size_t>(), seconds.size());
    EXPECT_EQ(row["repeats"].get<int>(), row["label"] == "sa" ? 3 : 2);
    for (const auto& [region, list] : values) {
      double mean = 0;
      for (double v : list) mean += v;
      mean /= double(list.size());
      double squares = 0;
      for (double v : list) squares += (v - mean) * (v - mean);
      const double std = std::sqrt(squares / double(list.size() - 1));
      EXPECT_LE(relative_difference(row["mrse"][region]["mean"], mean), 1e-12) << region;
      EXPECT_LE(std::abs(row["mrse"][region]["std"].get<double>() - std), 1e-12 * mean) << region;
      EXPECT_GT(mean, 0) << region;
      // Corrected: the plain mean less the reference's term, mean of s^2 / (r^2 + eps).
      const Region rect = region == "image" ? Region{0, 0, 48, 40} : kRegions.at(region);
      const double term = reference_noise_mrse(reference, reference_variance, rect);
      EXPECT_GT(term, 0) << region;
      const nlohmann::json& cell = row["mrse_corrected"][region];
      EXPECT_LE(relative_difference(cell["mean"], mean - term), 1e-9) << region;
      EXPECT_LT(cell["lower"].get<double>(), cell["mean"].get<double>()) << region;
      EXPECT_GT(cell["upper"].get<double>(), cell["mean"].get<double>()) << region;
      double share = 0;
      for (double v : list) share += term / v / double(list.size());
      EXPECT_NEAR(cell["reference_share"].get<double>(), share, 1e-9) << region;
      EXPECT_EQ(cell["reference_flagged"].get<bool>(), share > 0.1) << region;
    }
    double seconds_mean = 0;
    for (double v : seconds) seconds_mean += v / double(seconds.size());
    EXPECT_LE(relative_difference(row["compute_seconds"]["mean"], seconds_mean), 1e-12);
    ++rows_checked;
  }
  EXPECT_EQ(rows_checked, 4);

  // Winners per column within each spp group: marked exactly when the pairwise comparison (3
  // and 2 repeats: 2 pairs) says one row beats the other at 95%.
  for (std::string group : {"4 spp", "16 spp"}) {
    for (std::string region : {"image", "penumbra", "corner"}) {
      std::vector<const nlohmann::json*> rows;
      for (const nlohmann::json& row : table["rows"])
        if (row["comparison_group"] == group) rows.push_back(&row);
      ASSERT_EQ(rows.size(), 2u);
      const nlohmann::json* pair = nullptr;
      for (const nlohmann::json& entry : table["pairwise"])
        if (entry["group"] == group && entry["region"] == region) pair = &entry;
      ASSERT_NE(pair, nullptr) << group << " " << region;
      EXPECT_EQ((*pair)["pairs"], 2);
      auto marked = [&](const nlohmann::json& row) {
        for (const auto& column : row["best"])
          if (column == "mrse:" + region) return true;
        return false;
      };
      for (const nlohmann::json* row : rows) {
        EXPECT_EQ(marked(*row), (*pair)["better"] == (*row)["label"]) << group << " " << region;
      }
    }
  }
  // Efficiency relative to the baseline (sa): exactly 1 for sa itself.
  for (const nlohmann::json& row : table["rows"]) {
    if (row["label"] != "sa") continue;
    EXPECT_DOUBLE_EQ(row["efficiency"]["mean"].get<double>(), 1.0);
  }

  // The CSV holds the same numbers (full precision) and the refusal.
  std::string csv = read_text(out / "table.csv");
  std::istringstream lines(csv);
  std::string header, line;
  std::getline(lines, header);
  EXPECT_EQ(header.rfind("label,method,sampler,", 0), 0u) << header;
  int csv_rows = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json& row = table["rows"][size_t(csv_rows)];
    if (row.contains("refusal")) {
      EXPECT_NE(line.find("no-such-strategy"), std::string::npos) << line;
    } else {
      char expected[40];
      std::snprintf(expected, sizeof(expected), "%.17g",
                    row["mrse"]["image"]["mean"].get<double>());
      EXPECT_NE(line.find(expected), std::string::npos) << line;
    }
    ++csv_rows;
  }
  EXPECT_EQ(csv_rows, 5);

  // The page holds the table, the refusal and no problems.
  std::string html = read_text(out / "report.html");
  EXPECT_NE(html.find("id=\"batch-table\""), std::string::npos);
  EXPECT_NE(html.find("refused: "), std::string::npos);
  EXPECT_EQ(html.find("<h2>Problems</h2>"), std::string::npos);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
}

TEST_F(BatchReportTest, ChartsAndFigureExistWithTheirSizes) {
  fs::path out = output_root() / "report-files";
  fs::remove_all(out);
  BatchReportOptions options;
  options.chart_width = 640;
  options.chart_height = 480;
  write_batch_report(batch_dir_, out, options);
  for (const char* stem :
       {"mrse_time", "mrse_spp_image", "mrse_spp_region_penumbra", "mrse_spp_region_corner"}) {
    fs::path svg = out / "charts" / (std::string(stem) + ".svg");
    fs::path png = out / "charts" / (std::string(stem) + ".png");
    ASSERT_TRUE(fs::exists(svg)) << svg;
    EXPECT_NE(read_text(svg).find("<svg"), std::string::npos) << svg;
    OIIO::ImageBuf chart(png.string());
    ASSERT_TRUE(chart.init_spec(png.string(), 0, 0)) << png;
    EXPECT_EQ(chart.spec().width, 640) << png;
    EXPECT_EQ(chart.spec().height, 480) << png;
  }
  // The spp charts fit each method's points: the least-squares log-log slope (metrics.h), which
  // falls with spp (MRSE of an unbiased estimator ~ spp^-1 without stratification gains).
  BatchResult result = read_batch_result(batch_dir_);
  RecomputedErrors recomputed = recompute_batch_errors(result, batch_dir_);
  for (std::string region : {"image", "penumbra", "corner"}) {
    ChartSpec spec = mrse_spp_chart(result, recomputed, region);
    ASSERT_EQ(spec.series.size(), 2u) << region;  // the refused method has no series
    for (const ChartSeries& series : spec.series) {
      ASSERT_EQ(series.x, (std::vector<double>{4, 16})) << region << " " << series.name;
      ASSERT_TRUE(series.fit.has_value());
      EXPECT_NEAR(series.fit->slope, log_log_slope(series.x, series.y), 1e-9)
          << region << " " << series.name;
      EXPECT_LT(series.fit->slope, 0) << region << " " << series.name;
      EXPECT_FALSE(series.y_error.empty());  // three and two repeats: 95% intervals
    }
  }
  ChartSpec time_chart = mrse_time_chart(result, recomputed);
  ASSERT_EQ(time_chart.series.size(), 2u);
  EXPECT_EQ(time_chart.series[0].x.size(), 5u);  // curve points at 1, 2, 4 (twice), 8, 16 passes
  EXPECT_EQ(time_chart.series[1].x.size(), 5u);

  // The figure: reference plus three method columns of 256 pixels.
  fs::path figure_path = output_root() / "figure-direct.png";
  BatchFigureInfo info = write_batch_figure(result, recomputed, batch_dir_, figure_path, options);
  EXPECT_GE(info.width, 4 * options.figure_column_width);
  // Full image 256x213, two crops (20x12 -> x12, 12x10 -> x21), error map, labels.
  EXPECT_GE(info.height, 213 * 2 + 12 * 12 + 10 * 21);
  EXPECT_EQ(info.shown_runs, (std::vector<int>{1, 1, -1}));  // 16 spp, repeat 0
  for (const fs::path& path : {figure_path, out / "figure.png"}) {
    OIIO::ImageBuf figure(path.string());
    ASSERT_TRUE(figure.init_spec(path.string(), 0, 0)) << path;
    EXPECT_EQ(figure.spec().width, info.width);
    EXPECT_EQ(figure.spec().height, info.height);
  }
  // The reference's tonemapped image is in the first column: not all white or all black.
  OIIO::ImageBuf figure(figure_path.string());
  int lit = 0, dark = 0;
  for (int y = 80; y < 200; ++y)
    for (int x = 20; x < 260; ++x) {
      float pixel[3];
      figure.getpixel(x, y, pixel, 3);
      lit += pixel[0] > 0.3f;
      dark += pixel[0] < 0.1f;
    }
  EXPECT_GT(lit, 100);
  EXPECT_GT(dark, 100);
}

TEST_F(BatchReportTest, RecordedErrorsThatDifferFromTheExrsAreAnError) {
  fs::path copy = edited_copy("batch-mismatch", [](nlohmann::json& batch) {
    nlohmann::json& entry = batch["methods"][0]["runs"][1]["errors"][2];
    entry["mrse"] = entry["mrse"].get<double>() * (1 + 1e-7);
  });
  try {
    write_batch_report(copy, output_root() / "report-mismatch");
    FAIL() << "a changed recorded MRSE was accepted";
  } catch (const std::runtime_error& error) {
    std::string message = error.what();
    EXPECT_NE(message.find("methods[0].runs[1]"), std::string::npos) << message;
    EXPECT_NE(message.find("mrse recorded"), std::string::npos) << message;
    EXPECT_EQ(message.find("methods[1]"), std::string::npos) << message;
  }
  // A change within the tolerance (1e-9 relative) is not a mismatch.
  fs::path close = edited_copy("batch-close", [](nlohmann::json& batch) {
    nlohmann::json& entry = batch["methods"][0]["runs"][1]["errors"][2];
    entry["mrse"] = entry["mrse"].get<double>() * (1 + 1e-11);
  });
  EXPECT_NO_THROW(write_batch_report(close, output_root() / "report-close"));
  // Allowed: the report is written and lists the problem.
  BatchReportOptions options;
  options.allow_error_mismatch = true;
  write_batch_report(copy, output_root() / "report-mismatch", options);
  std::string html = read_text(output_root() / "report-mismatch" / "report.html");
  EXPECT_NE(html.find("<h2>Problems</h2>"), std::string::npos);
}

TEST_F(BatchReportTest, MalformedBatchJsonNamesTheKey) {
  struct Case {
    std::string name;
    std::function<void(nlohmann::json&)> edit;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"missing-exr", [](nlohmann::json& b) { b["methods"][1]["runs"][0].erase("exr"); },
       "batch.json: methods[1].runs[0].exr: missing"},
      {"bad-width", [](nlohmann::json& b) { b["scene"]["width"] = "wide"; },
       "batch.json: scene.width: expected an integer"},
      {"bad-format", [](nlohmann::json& b) { b["format"] = "penumbra/batch-result@9"; },
       "batch.json: format: expected"},
      {"no-methods", [](nlohmann::json& b) { b.erase("methods"); }, "batch.json: methods: missing"},
      {"curve-mrse", [](nlohmann::json& b) { b["methods"][0]["runs"][1]["curve"][2]["mrse"] = -1; },
       "batch.json: methods[0].runs[1].curve[2].mrse: negative"},
      {"region-rect",
       [](nlohmann::json& b) {
         b["regions"][1]["rect"] = {4, 4, 2, 8};
       },
       "batch.json: regions[1].rect: empty rectangle"},
      {"region-errors", [](nlohmann::json& b) { b["methods"][1]["runs"][1]["errors"].erase(1); },
       "batch.json: methods[1].runs[1].errors: no entry for region"},
      {"exr-file", [](nlohmann::json& b) { b["methods"][0]["runs"][3]["exr"] = "runs/gone.exr"; },
       "batch.json: methods[0].runs[3].exr: file not found"},
      {"exr-escape", [](nlohmann::json& b) { b["reference"]["exr"] = "../reference.exr"; },
       "batch.json: reference.exr: path leaves the folder"},
  };
  for (const Case& c : cases) {
    fs::path copy = edited_copy("batch-malformed-" + c.name, c.edit);
    try {
      write_batch_report(copy, output_root() / ("report-malformed-" + c.name));
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const BatchResultError& error) {
      EXPECT_EQ(std::string(error.what()).rfind(c.expected, 0), 0u)
          << c.name << ": " << error.what();
    }
    fs::remove_all(copy);
  }
  EXPECT_THROW(parse_batch_result("{\"format\": "), BatchResultError);
}

TEST(BatchReportParts, Base64AndEscaping) {
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64_encode(std::string("\xff\x00\x80", 3)), "/wCA");
  EXPECT_EQ(html_escape("<a href=\"x\">&'"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
}

TEST(BatchReportParts, RelativeErrorMapAndColourMap) {
  Image reference(2, 1), image(2, 1);
  reference.set(0, 0, {1, 0, 0.5});
  image.set(0, 0, {1.5, 0.02, 0.5});
  reference.set(1, 0, {0, 0, 0});
  image.set(1, 0, {0, 0, 0});
  Image map = relative_error_map(image, reference);
  EXPECT_NEAR(map.at(0, 0).x, (0.5 / 1.01 + 0.02 / 0.01 + 0) / 3, 1e-6);  // float pixels
  EXPECT_EQ(map.at(1, 0).x, 0.0);
  Rgb low = viridis(0), high = viridis(1), mid = viridis(0.5);
  EXPECT_NEAR(low.x, 0x44 / 255.0, 1e-12);
  EXPECT_NEAR(high.y, 0xe7 / 255.0, 1e-12);
  EXPECT_NEAR(mid.z, 0x8c / 255.0, 1e-12);
  EXPECT_EQ(viridis(-3).x, low.x);
  EXPECT_EQ(viridis(NAN).x, low.x);
  EXPECT_EQ(viridis(INFINITY).x, high.x);
  MeanStd stats = mean_std({1, 2, 3, 4});
  EXPECT_DOUBLE_EQ(stats.mean, 2.5);
  EXPECT_DOUBLE_EQ(stats.std, std::sqrt(5.0 / 3.0));
}

// Runs a command through the shell; returns its exit status.
int run_command(const std::string& command) {
  int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(BatchReportTest, HtmlRendersInHeadlessChromium) {
  const fs::path chromium = "/usr/bin/chromium";
  if (!fs::exists(chromium)) GTEST_SKIP() << "chromium is not installed (/usr/bin/chromium)";
  fs::path out = output_root() / "report-chromium";
  fs::remove_all(out);
  write_batch_report(batch_dir_, out);

  // A copy of the page with a script that counts the images that did not load.
  std::string html = read_text(out / "report.html");
  const std::string check_script = R"(<script>
window.addEventListener('load', function () {
  var images = document.images, broken = 0;
  for (var i = 0; i < images.length; ++i)
    if (!images[i].complete || images[i].naturalWidth === 0) ++broken;
  document.body.setAttribute('data-images', String(images.length));
  document.body.setAttribute('data-broken-images', String(broken));
});
</script>
)";
  size_t body_end = html.rfind("</body>");
  ASSERT_NE(body_end, std::string::npos);
  html.insert(body_end, check_script);
  fs::path checked = out / "report_checked.html";
  write_text(checked, html);

  fs::path screenshot = out / "report.png";
  fs::path dom = out / "report_dom.html";
  std::string common = "timeout 120 " + chromium.string() +
                       " --headless=new --no-sandbox --disable-gpu --no-first-run"
                       " --user-data-dir=" +
                       (out / "chromium-profile").string() +
                       " --virtual-time-budget=10000 --window-size=1400,3000 ";
  std::string url = "file://" + fs::absolute(checked).string();
  std::string log = " >>" + (out / "chromium.log").string() + " 2>&1";
  ASSERT_EQ(run_command(common + "--screenshot=" + screenshot.string() + " " + url + log), 0)
      << "see " << (out / "chromium.log");
  ASSERT_EQ(run_command(common + "--dump-dom " + url + " >" + dom.string() + " 2>>" +
                        (out / "chromium.log").string()),
            0);
  std::cout << "report screenshot: " << screenshot.string() << std::endl;

  // Every image loaded: the four charts and the figure.
  std::string dumped = read_text(dom);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(dumped, match, std::regex("data-images=\"(\\d+)\"")))
      << "the check script did not run; DOM in " << dom;
  EXPECT_EQ(std::stoi(match[1]), 5);
  ASSERT_TRUE(std::regex_search(dumped, match, std::regex("data-broken-images=\"(\\d+)\"")));
  EXPECT_EQ(std::stoi(match[1]), 0);

  // The screenshot is not blank: many non-white pixels and some colour (charts, figure).
  OIIO::ImageBuf shot(screenshot.string());
  ASSERT_TRUE(shot.init_spec(screenshot.string(), 0, 0)) << screenshot;
  EXPECT_EQ(shot.spec().width, 1400);
  int non_white = 0, coloured = 0, total = 0;
  for (int y = 0; y < shot.spec().height; y += 3)
    for (int x = 0; x < shot.spec().width; x += 3) {
      float pixel[4] = {1, 1, 1, 1};
      shot.getpixel(x, y, pixel, 4);
      ++total;
      non_white += pixel[0] + pixel[1] + pixel[2] < 2.7f;
      coloured +=
          std::max({pixel[0], pixel[1], pixel[2]}) - std::min({pixel[0], pixel[1], pixel[2]}) >
          0.2f;
    }
  EXPECT_GT(non_white, total / 50) << screenshot;
  EXPECT_GT(coloured, total / 500) << screenshot;
}

}  // namespace
}  // namespace penumbra
