// Local commands: render, probe and demo run in this process with penumbra_core.
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "client/commands.h"
#include "client/read_file.h"
#include "core/image/metrics.h"
#include "core/render/local_render.h"
#include "core/render/probe.h"
#include "core/scene/scene.h"

namespace penumbra {

namespace {

std::atomic<int> exit_code{0};

Pattern sampler_from(const std::string& name) {
  std::optional<Pattern> pattern = parse_pattern(name);
  if (!pattern)
    throw FormatError("sampler", "unknown sampler \"" + name +
                                     "\"; expected random, stratified, uniform, uniform-jitter, "
                                     "halton, sobol or cmj");
  return *pattern;
}

void print_errors(const std::map<std::string, ErrorSummary>& errors) {
  for (const auto& [name, e] : errors)
    std::printf("  %-16s MRSE %.6g  RMSE %.6g\n", name.c_str(), e.mrse, e.rmse);
}

std::string png_path_for(const std::string& exr_path) {
  std::filesystem::path p(exr_path);
  p.replace_extension(".png");
  return p.string();
}

struct RenderArgs {
  std::string scene, method = "sa", sampler = "stratified", output = "out.exr", reference;
  uint32_t spp = 16;
  double seconds = 0;
  uint64_t seed = 0;
  int threads = 0;
  int tile = 64;
};

void run_render(const RenderArgs& args) {
  auto scene = std::make_shared<const Scene>(load_scene(args.scene));
  RenderOptions options{args.method, sampler_from(args.sampler), args.seed};
  Renderer renderer(scene, options);
  RenderBudget budget;
  if (args.seconds > 0)
    budget.seconds = args.seconds;
  else
    budget.spp = args.spp;
  LocalRenderResult result = render_local(renderer, budget, args.threads, args.tile);
  if (result.film.nonfinite_samples > 0) {
    std::fprintf(stderr, "penumbra: error: %llu non-finite samples (counted as zero)\n",
                 (unsigned long long)result.film.nonfinite_samples);
    exit_code = 3;
  }
  ImageMetadata metadata = render_metadata(*scene, options, result.spp, result.compute_seconds);
  write_exr(args.output, result.film.color, &result.film.variance, metadata);
  write_png_preview(png_path_for(args.output), result.film.color);
  std::printf("%s: %s, %s, %u spp, %.3f s compute, %.3f s wall -> %s\n", scene->name.c_str(),
              args.method.c_str(), args.sampler.c_str(), result.spp, result.compute_seconds,
              result.wall_seconds, args.output.c_str());
  if (!args.reference.empty()) {
    Image reference = read_exr(args.reference);
    print_errors(error_summary(result.film.color, reference, scene->regions));
  }
}

std::vector<int> parse_counts(const std::string& text) {
  std::vector<int> counts;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      long value = std::stol(item, &used);
      if (used != item.size() || value < 1 || value > (1 << 20)) throw std::out_of_range(item);
      counts.push_back(int(value));
    } catch (const std::exception&) {
      throw FormatError("samples", "\"" + item + "\" is not a sample count in 1..1048576");
    }
  }
  if (counts.empty()) throw FormatError("samples", "give at least one sample count");
  return counts;
}

}  // namespace

int command_exit_code() {
  return exit_code.load();
}
void set_command_exit_code(int code) {
  exit_code.store(code);
}

void run_local_demo(const std::string& out_dir, double seconds_per_method, int threads);

void add_local_commands(CLI::App& app) {
  // render
  auto args = std::make_shared<RenderArgs>();
  CLI::App* render =
      app.add_subcommand("render", "Render a scene locally to an EXR (+ PNG preview)");
  render->add_option("scene", args->scene, "Scene file (penumbra/scene@1)")->required();
  render->add_option("--method,-m", args->method, "Method, e.g. sa or bsdf+sa/balance");
  render->add_option("--sampler,-s", args->sampler, "Sample pattern");
  render->add_option("--spp", args->spp, "Samples (passes) per pixel")
      ->check(CLI::Range(1u, 1u << 20));
  render->add_option("--seconds", args->seconds, "Render progressively for this much compute time")
      ->check(CLI::PositiveNumber);
  render->add_option("--seed", args->seed, "Seed");
  render->add_option("--threads", args->threads, "Threads (0: all cores)")
      ->check(CLI::Range(0, 1024));
  render->add_option("--tile", args->tile, "Tile size")->check(CLI::Range(1, 4096));
  render->add_option("-o,--output", args->output, "Output EXR");
  render->add_option("--reference", args->reference, "Reference EXR: print MRSE, per region too");
  render->callback([args] { run_render(*args); });

  // probe
  struct ProbeArgs {
    std::string scene, probe, method = "sa", sampler = "stratified", samples = "1,2,4,8,16", output;
    int trials = 64;
    uint64_t seed = 0;
  };
  auto pargs = std::make_shared<ProbeArgs>();
  CLI::App* probe = app.add_subcommand("probe", "Estimator statistics at fixed shading points");
  probe->add_option("scene", pargs->scene, "Scene file")->required();
  probe->add_option("probe", pargs->probe, "Probe file (penumbra/probe@1)")->required();
  probe->add_option("--method,-m", pargs->method, "Method");
  probe->add_option("--sampler,-s", pargs->sampler, "Sample pattern");
  probe->add_option("--samples", pargs->samples, "Sample counts N, comma-separated");
  probe->add_option("--trials", pargs->trials, "Independent estimates per N")
      ->check(CLI::Range(2, 1 << 24));
  probe->add_option("--seed", pargs->seed, "Seed");
  probe->add_option("--json", pargs->output, "Output file (default: standard output)");
  probe->callback([pargs] {
    auto scene = std::make_shared<const Scene>(load_scene(pargs->scene));
    ProbeSpec spec = parse_probe(read_file(pargs->probe), pargs->probe);
    std::vector<int> counts = parse_counts(pargs->samples);
    ProbeResult result = run_probe(scene, spec, pargs->method, sampler_from(pargs->sampler), counts,
                                   pargs->trials, pargs->seed);
    std::string text = probe_result_json(result);
    if (pargs->output.empty()) {
      std::printf("%s\n", text.c_str());
    } else {
      std::ofstream out(pargs->output);
      out << text << "\n";
      if (!out) throw std::runtime_error("cannot write " + pargs->output);
    }
  });

  // demo
  struct DemoArgs {
    std::string output = "demo-out";
    double seconds = 4;
    int threads = 0;
  };
  auto dargs = std::make_shared<DemoArgs>();
  CLI::App* demo = app.add_subcommand(
      "demo", "Render the bundled comparison on cornell-occluders at equal time, with a report");
  demo->add_option("-o,--output", dargs->output, "Output folder");
  demo->add_option("--seconds", dargs->seconds, "Compute seconds per method")
      ->check(CLI::PositiveNumber);
  demo->add_option("--threads", dargs->threads, "Threads (0: all cores)");
  demo->callback([dargs] { run_local_demo(dargs->output, dargs->seconds, dargs->threads); });
  add_reproduce_command(app);
}

}  // namespace penumbra
