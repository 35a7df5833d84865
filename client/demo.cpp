// `penumbra demo`: the bundled comparison on cornell-occluders.
//
// With the farm built, the demo is the batch batches/demo.json (penumbra/batch@1) run on an
// embedded farm (a coordinator on a loopback port and local worker daemons in this process):
// a cached reference, a calibration of every method's cost per pass, then every method for the
// same compute time, interleaved round-robin. The folder gets the batch result folder
// (batch.json, reference.exr, runs/*.exr) and its report (report.html, table.csv, charts,
// figure.png); the summary table is printed. --seconds replaces the batch's budget.
//
// Without the farm, the same methods render locally (EXRs, PNG previews, report.md,
// summary.json).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "client/batch_commands.h"
#include "client/commands.h"
#include "core/image/metrics.h"
#include "core/method/method_check.h"
#include "core/method/method.h"
#include "core/render/local_render.h"
#include "core/scene/scene.h"

namespace penumbra {

#ifdef PENUMBRA_WITH_FARM

void run_local_demo(const std::string& out_dir, double seconds, int threads) {
  std::string path = bundled_batch_path("demo");
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the demo batch " + path);
  nlohmann::json spec = nlohmann::json::parse(in);
  if (seconds > 0) spec["budget"]["seconds"] = seconds;
  std::printf("demo: batch %s (%s), %.2f s of compute per method and repeat, %d repeats\n",
              path.c_str(), spec.value("scene", std::string()).c_str(),
              spec["budget"].value("seconds", 0.0), spec.value("repeats", 3));
  BatchRunSettings settings;
  settings.workers = threads;
  run_batch(spec.dump(2), path, std::filesystem::path(path).parent_path().string(), out_dir,
            settings);
  std::printf("demo: wrote %s/report.html\n", out_dir.c_str());
}

#else

namespace {

struct DemoEntry {
  std::string method;
  std::string sampler = "stratified";
};

// The comparison: point strategies, their MIS, and line strategies when they are available.
const std::vector<DemoEntry> kDemoMethods{
    {"area"},
    {"sa"},
    {"bsdf"},
    {"bsdf+sa"},
    {"line-sa:v"},
    {"bsdf+line-sa:v/balance"},
    {"bsdf+line-sa:v/smooth"},
    {"line-bd16:rand"},
    {"psa"},
};
const DemoEntry kReference{"bsdf+sa", "stratified"};

struct DemoRender {
  Film film;
  uint32_t spp = 0;
  double compute_seconds = 0;
};

// Renders one method for a compute-time budget: on the embedded farm when it is built.
class DemoRenderer {
 public:
  DemoRenderer(std::shared_ptr<const Scene> scene, const std::string& scene_path, int threads)
      : scene_(std::move(scene)), threads_(threads) {
    (void)scene_path;
  }

  DemoRender render(const DemoEntry& entry, double seconds, uint64_t seed) {
    // Refuse what the estimator cannot run before it reaches a worker (FormatError).
    check_method_runs_on(*scene_, parse_method(entry.method));
    DemoRender out;
    Renderer renderer(scene_, RenderOptions{entry.method, *parse_pattern(entry.sampler), seed});
    RenderBudget budget;
    budget.seconds = seconds;
    LocalRenderResult result = render_local(renderer, budget, threads_);
    out.film = std::move(result.film);
    out.spp = result.spp;
    out.compute_seconds = result.compute_seconds;
    return out;
  }

 private:
  std::shared_ptr<const Scene> scene_;
  int threads_;
};

}  // namespace

void run_local_demo(const std::string& out_dir, double seconds, int threads) {
  if (!(seconds > 0)) seconds = 4;
  std::filesystem::create_directories(out_dir);
  const std::string scene_path = bundled_scene_path("cornell-occluders");
  auto scene = std::make_shared<const Scene>(load_scene(scene_path));
  std::printf("demo: %s (%dx%d), %.1f s of compute per method, reference %.1f s\n",
              scene->name.c_str(), scene->camera.width, scene->camera.height, seconds, seconds * 8);

  DemoRenderer renderer(scene, scene_path, threads);
  auto render_one = [&](const DemoEntry& entry, double budget_seconds, uint64_t seed,
                        const std::string& file_stem) {
    RenderOptions options{entry.method, *parse_pattern(entry.sampler), seed};
    DemoRender result = renderer.render(entry, budget_seconds, seed);
    std::string exr = (std::filesystem::path(out_dir) / (file_stem + ".exr")).string();
    write_exr(exr, result.film.color, &result.film.variance,
              render_metadata(*scene, options, result.spp, result.compute_seconds));
    write_png_preview((std::filesystem::path(out_dir) / (file_stem + ".png")).string(),
                      result.film.color);
    return result;
  };

  DemoRender reference = render_one(kReference, seconds * 8, 0xC0FFEE, "reference");
  std::printf("  reference %-26s %6u spp %8.2f s\n", kReference.method.c_str(), reference.spp,
              reference.compute_seconds);

  nlohmann::json summary;
  summary["scene"] = scene->name;
  summary["scene_hash"] = scene->content_hash;
  summary["seconds_per_method"] = seconds;
  summary["reference"] = {{"method", kReference.method},
                          {"spp", reference.spp},
                          {"compute_seconds", reference.compute_seconds}};
  summary["methods"] = nlohmann::json::array();
  std::string table = "| method | sampler | spp | compute s | MRSE image |";
  for (const auto& [name, region] : scene->regions) table += " MRSE " + name + " |";
  table += "\n|---|---|---|---|---|";
  for (size_t i = 0; i < scene->regions.size(); ++i) table += "---|";
  table += "\n";
  std::string skipped;
  for (const DemoEntry& entry : kDemoMethods) {
    std::string stem = entry.method;
    for (char& c : stem)
      if (c == '/' || c == ':' || c == '*' || c == '+') c = '_';
    DemoRender result;
    try {
      result = render_one(entry, seconds, 1, stem);
    } catch (const FormatError& e) {
      std::printf("  skipped   %-26s (%s)\n", entry.method.c_str(), e.what());
      skipped += "- `" + entry.method + "`: " + e.what() + "\n";
      continue;
    }
    auto errors = error_summary(result.film.color, reference.film.color, scene->regions);
    std::printf("  %-35s %6u spp %8.2f s  MRSE %.5g\n", entry.method.c_str(), result.spp,
                result.compute_seconds, errors["image"].mrse);
    nlohmann::json row{{"method", entry.method},
                       {"sampler", entry.sampler},
                       {"spp", result.spp},
                       {"compute_seconds", result.compute_seconds},
                       {"image", stem + ".exr"}};
    char cell[64];
    table +=
        "| `" + entry.method + "` | " + entry.sampler + " | " + std::to_string(result.spp) + " | ";
    std::snprintf(cell, sizeof cell, "%.2f", result.compute_seconds);
    table += cell;
    for (const auto& [name, e] : errors) {
      row["mrse"][name] = e.mrse;
    }
    std::snprintf(cell, sizeof cell, " | %.4g |", errors["image"].mrse);
    table += cell;
    for (const auto& [name, region] : scene->regions) {
      std::snprintf(cell, sizeof cell, " %.4g |", errors[name].mrse);
      table += cell;
    }
    table += "\n";
    summary["methods"].push_back(row);
  }
  std::ofstream(std::filesystem::path(out_dir) / "summary.json") << summary.dump(2) << "\n";
  std::ofstream report(std::filesystem::path(out_dir) / "report.md");
  report << "# Penumbra demo: " << scene->name << "\n\n"
         << "Equal compute time per method (" << seconds << " s); reference `" << kReference.method
         << "` at " << reference.spp << " spp. MRSE (epsilon 1e-6) against "
         << "the reference over the image and the scene's regions.\n\n"
         << table << "\n";
  if (!skipped.empty())
    report << "Not run (refused by the estimator for this scene):\n\n" << skipped;
  std::printf("demo: wrote %s/report.md\n", out_dir.c_str());
}

#endif  // PENUMBRA_WITH_FARM

}  // namespace penumbra
