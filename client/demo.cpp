// `penumbra demo`: the bundled comparison on cornell-occluders. Every method renders for the
// same compute time; a reference renders for longer; the folder gets EXRs, PNG previews and a
// report (report.md, summary.json) with MRSE over the image and its regions.
//
// With the farm built, the demo runs on an embedded farm: a coordinator on a loopback port and
// local worker daemons in this process, every render a job through the gRPC API. Without it, the
// same renders run locally.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "client/commands.h"
#include "core/image/metrics.h"
#include "core/method/direct_lighting.h"
#include "core/method/method.h"
#include "core/render/local_render.h"
#include "core/scene/scene.h"

#ifdef PENUMBRA_WITH_FARM
#include "proto/support/scene_packing.h"
#include "server/embedded_farm.h"
#endif

#ifndef PENUMBRA_SCENES_DIR
#define PENUMBRA_SCENES_DIR "scenes"
#endif

namespace penumbra {

std::string bundled_scene_path(const std::string& name) {
  const char* env = std::getenv("PENUMBRA_SCENES");
  std::filesystem::path dir = env ? env : PENUMBRA_SCENES_DIR;
  return (dir / (name + ".json")).string();
}

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
#ifdef PENUMBRA_WITH_FARM
    int cores = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
    farm::EmbeddedFarmOptions options;
    options.workers = cores;
    options.threads_per_worker = 1;
    farm_ = std::make_unique<farm::EmbeddedFarm>(options);
    package_ = farm::pack_scene_file(scene_path);
    std::printf("demo: embedded farm at %s with %d worker(s)\n", farm_->address().c_str(), cores);
#else
    (void)scene_path;
#endif
  }

  DemoRender render(const DemoEntry& entry, double seconds, uint64_t seed) {
    // Refuse what the estimator cannot run before it reaches a worker (FormatError).
    DirectLighting check(*scene_, parse_method(entry.method));
    DemoRender out;
#ifdef PENUMBRA_WITH_FARM
    v1::JobSpec spec;
    *spec.mutable_scene() = package_;
    spec.set_method(entry.method);
    spec.set_sampler(entry.sampler);
    spec.set_seed(seed);
    spec.set_compute_seconds(seconds);
    spec.set_passes_per_task(1);  // stop close to the budget: one pass per task
    spec.set_name("demo " + entry.method);
    std::string id = farm_->submit(spec);
    v1::JobStatus status = farm_->wait(id);
    if (status.state() != v1::JOB_STATE_DONE)
      throw std::runtime_error("demo job " + id + " (" + entry.method + ") ended " +
                               v1::JobState_Name(status.state()) + ": " + status.error());
    out.film = farm_->film(id);
    out.spp = status.passes_complete();
    out.compute_seconds = status.compute_seconds();
#else
    Renderer renderer(scene_, RenderOptions{entry.method, *parse_pattern(entry.sampler), seed});
    RenderBudget budget;
    budget.seconds = seconds;
    LocalRenderResult result = render_local(renderer, budget, threads_);
    out.film = std::move(result.film);
    out.spp = result.spp;
    out.compute_seconds = result.compute_seconds;
#endif
    return out;
  }

 private:
  std::shared_ptr<const Scene> scene_;
  int threads_;
#ifdef PENUMBRA_WITH_FARM
  std::unique_ptr<farm::EmbeddedFarm> farm_;
  v1::ScenePackage package_;
#endif
};

}  // namespace

void run_local_demo(const std::string& out_dir, double seconds, int threads) {
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

}  // namespace penumbra
