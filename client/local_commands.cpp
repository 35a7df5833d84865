// Local commands: render, probe and demo run in this process with penumbra_core.
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "client/cli_options.h"
#include "client/commands.h"
#include "client/progress.h"
#include "client/read_file.h"
#include "client/scene_checks.h"
#include "core/image/metrics.h"
#include "core/render/local_render.h"
#include "core/render/probe.h"
#include "core/render/sums_file.h"
#include "core/scene/render_settings.h"
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

// The sums file beside an EXR: FILE.sums.
std::string sums_path_for(const std::string& exr_path) {
  std::filesystem::path p(exr_path);
  p.replace_extension(".sums");
  return p.string();
}

struct RenderArgs {
  // Method, sampler and budget left empty/zero take the scene file's own, then Penumbra's
  // defaults (core/scene/render_settings.h).
  std::string scene, method, sampler, output = "out.exr", reference;
  std::string sums;         // the exact sums' file (core/render/sums_file.h), or empty
  uint32_t first_pass = 0;  // the first pass drawn: the rest of an interrupted render
  uint32_t spp = 0;
  double seconds = 0;
  uint64_t seed = 0;
  int threads = 0;
  int tile = 64;
  bool quiet = false;
  bool strict = false, accept_reference_mismatch = false;
};

// Ctrl-C during a local render: the first asks the render to stop at its next pass boundary (the
// partial image is written), the second aborts at once.
std::atomic<bool> stop_render{false};
std::atomic<int> interrupts{0};

extern "C" void on_render_interrupt(int) {
  if (interrupts.fetch_add(1) == 0) {
    stop_render.store(true);
    const char message[] =
        "\npenumbra: stopping at the next pass boundary to write the partial image (Ctrl-C "
        "again to abort)\n";
    (void)!write(STDERR_FILENO, message, sizeof message - 1);
    return;
  }
  const char message[] = "\npenumbra: aborted\n";
  (void)!write(STDERR_FILENO, message, sizeof message - 1);
  signal(SIGINT, SIG_DFL);
  raise(SIGINT);
}

// Installs on_render_interrupt for its lifetime.
class InterruptScope {
 public:
  InterruptScope() {
    stop_render.store(false);
    interrupts.store(0);
    struct sigaction action {};
    action.sa_handler = on_render_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
  }
  ~InterruptScope() { sigaction(SIGINT, &previous_, nullptr); }

 private:
  struct sigaction previous_ {};
};

void run_render(const RenderArgs& args) {
  // Everything that can be refused is refused before the render: the output, the scene's
  // warnings under --strict, the reference.
  const std::string extension = std::filesystem::path(args.output).extension().string();
  if (extension == ".png" || extension == ".PNG")
    throw std::runtime_error("-o " + args.output +
                             ": the output is an EXR (its PNG preview is written beside it); "
                             "give -o " +
                             std::filesystem::path(args.output).replace_extension(".exr").string() +
                             " to get both");
  check_output_path(args.output, {".exr"}, "-o");
  if (!args.sums.empty()) check_output_path(args.sums, {".sums"}, "--sums");
  auto scene = std::make_shared<const Scene>(load_scene(args.scene));
  report_scene_warnings(*scene, args.strict, args.scene);
  std::optional<CheckedReference> reference;
  if (!args.reference.empty()) {
    reference = check_reference(args.reference, *scene, args.accept_reference_mismatch);
    for (const std::string& warning : reference->warnings)
      std::fprintf(stderr, "penumbra: warning: %s\n", warning.c_str());
  }
  RenderSettings settings =
      choose_render_settings(*scene, {args.method, args.sampler, args.spp, args.seconds});
  if (args.spp > 0 && args.seconds > 0)
    std::fprintf(stderr,
                 "penumbra: note: --seconds %g with --spp %u: renders until either is reached\n",
                 args.seconds, args.spp);
  RenderOptions options{settings.method, sampler_from(settings.sampler), args.seed};
  Renderer renderer(scene, options);
  RenderBudget budget;
  if (settings.seconds > 0) {
    budget.seconds = settings.seconds;
    if (settings.spp > 0) budget.max_spp = settings.spp;
  } else {
    budget.spp = settings.spp;
  }
  budget.first_pass = args.first_pass;
  ProgressReporter progress("render " + scene->name,
                            args.quiet ? ProgressMode::Quiet : ProgressMode::Auto);
  const double pixels = double(scene->camera.width) * scene->camera.height;
  // With a reference, the MRSE of the image so far after every pass block (its whole passes).
  std::string running_mrse;
  std::function<void(std::span<const TileAccumulator>)> measure;
  if (reference && !progress.quiet())
    measure = [&](std::span<const TileAccumulator> tiles) {
      Film film = assemble_film(scene->camera.width, scene->camera.height, tiles);
      char text[48];
      std::snprintf(text, sizeof text, ", MRSE %.4g", mrse(film.color, reference->image));
      running_mrse = text;
    };
  auto report = [&](uint32_t passes, double compute_seconds) {
    const double wall = progress.elapsed();
    const double spp_rate = wall > 0 ? passes / wall : 0;
    char samples[96];
    std::snprintf(samples, sizeof samples, "%.3g Msamples/s%s", spp_rate * pixels * 1e-6,
                  running_mrse.c_str());
    if (budget.spp > 0) {
      progress.update(passes, budget.spp, "spp", samples, spp_rate, "spp/s");
    } else {
      char extra[160];
      std::snprintf(extra, sizeof extra, "%u spp, %s", passes, samples);
      progress.update(compute_seconds, budget.seconds, "s compute", extra,
                      wall > 0 ? compute_seconds / wall : 0.0, "compute s/s");
    }
  };
  // Until the image is written, a first Ctrl-C stops the render and a second one aborts.
  InterruptScope interrupt_scope;
  LocalRenderResult result =
      render_local(renderer, budget, args.threads, args.tile, report, &stop_render, measure);
  progress.finish();
  if (result.stopped && result.spp == 0)
    throw std::runtime_error("render interrupted before its first pass: nothing written");
  if (result.film.nonfinite_samples > 0) {
    std::fprintf(stderr, "penumbra: error: %llu non-finite samples (counted as zero)\n",
                 (unsigned long long)result.film.nonfinite_samples);
    exit_code = 3;
  }
  ImageMetadata metadata = render_metadata(*scene, options, result.spp, result.compute_seconds);
  if (args.first_pass > 0) metadata["penumbra:first_pass"] = std::to_string(args.first_pass);
  if (result.stopped)
    metadata["penumbra:interrupted"] =
        "after " + std::to_string(result.spp) + " whole passes" +
        (budget.spp > 0 ? " of " + std::to_string(budget.spp) : std::string());
  if (reference)
    for (const std::string& warning : reference->warnings)
      metadata["penumbra:warnings"] += warning + "\n";
  write_exr(args.output, result.film.color, &result.film.variance, metadata);
  write_png_preview(png_path_for(args.output), result.film.color);
  // The exact sums, asked for or of an interrupted render (whose remaining passes merge with it).
  const std::string sums_path = !args.sums.empty() ? args.sums
                                : result.stopped   ? sums_path_for(args.output)
                                                   : "";
  if (!sums_path.empty()) {
    RenderSums sums;
    sums.width = scene->camera.width;
    sums.height = scene->camera.height;
    sums.first_pass = args.first_pass;
    sums.passes = result.spp;
    sums.compute_seconds = result.compute_seconds;
    sums.metadata = metadata;
    sums.sums = whole_image_sums(sums.width, sums.height, result.tiles);
    write_sums(sums_path, sums);
  }
  std::printf("%s: %s, %s, %u spp, %.3f s compute, %.3f s wall -> %s (preview %s)\n",
              scene->name.c_str(), settings.method.c_str(), settings.sampler.c_str(), result.spp,
              result.compute_seconds, result.wall_seconds, args.output.c_str(),
              png_path_for(args.output).c_str());
  if (result.stopped) {
    std::printf("render interrupted: the partial image has %u spp (whole passes, unbiased)\n",
                result.spp);
    const uint32_t next = args.first_pass + result.spp;
    std::string rest = budget.spp > 0 ? " --spp " + std::to_string(budget.spp - result.spp) : "";
    std::printf(
        "its exact sums are in %s: render the remaining passes with --first-pass %u%s --sums "
        "REST.sums, then `penumbra merge %s REST.sums -o FULL.exr` gives the image of the whole "
        "render, bit for bit\n",
        sums_path.c_str(), next, rest.c_str(), sums_path.c_str());
    exit_code = 130;
  }
  if (reference) print_errors(error_summary(result.film.color, reference->image, scene->regions));
}

// `penumbra merge`: the sums of disjoint pass ranges added (core/render/sums_file.h), written as
// the EXR (and PNG preview) one render of all those passes writes.
void run_merge(const std::vector<std::string>& inputs, const std::string& output,
               const std::string& sums_output) {
  check_output_path(output, {".exr"}, "-o");
  if (!sums_output.empty()) check_output_path(sums_output, {".sums"}, "--sums");
  std::vector<RenderSums> parts;
  std::vector<std::string> names;
  for (const std::string& input : inputs) {
    std::string path = input;
    const std::string extension = std::filesystem::path(input).extension().string();
    if (extension == ".exr" || extension == ".EXR") {
      path = sums_path_for(input);
      if (!std::filesystem::exists(path))
        throw std::runtime_error(input + ": no sums beside it (" + path +
                                 "); an EXR holds means, which do not merge exactly: render with "
                                 "--sums FILE.sums");
    }
    parts.push_back(read_sums(path));
    names.push_back(path);
  }
  RenderSums merged = merge_sums(parts, names);
  Film film = sums_film(merged);
  if (film.nonfinite_samples > 0) {
    std::fprintf(stderr, "penumbra: error: %llu non-finite samples (counted as zero)\n",
                 (unsigned long long)film.nonfinite_samples);
    exit_code = 3;
  }
  write_exr(output, film.color, &film.variance, merged.metadata);
  write_png_preview(png_path_for(output), film.color);
  if (!sums_output.empty()) write_sums(sums_output, merged);
  std::printf("merged %zu part(s): passes %u..%llu (%u spp), %.3f s compute -> %s (preview %s)\n",
              parts.size(), merged.first_pass,
              (unsigned long long)(uint64_t(merged.first_pass) + merged.passes), merged.passes,
              merged.compute_seconds, output.c_str(), png_path_for(output).c_str());
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
  render->add_option("scene", args->scene, "Scene file (penumbra/scene@1 or pbrt-v3)")->required();
  render->add_option("--method,-m", args->method,
                     "Method, e.g. sa or bsdf+sa/balance (default: the scene's own, else sa)");
  render->add_option("--sampler,-s", args->sampler,
                     "Sample pattern (default: the scene's own, else stratified)");
  render
      ->add_option("--spp", args->spp,
                   "Samples (passes) per pixel (default: the scene's, else 16); with --seconds, "
                   "the most it renders")
      ->check(CLI::Range(1u, 1u << 20));
  render
      ->add_option("--seconds", args->seconds,
                   "Render progressively for this much compute time (seconds)")
      ->check(CLI::Range(1e-3, 1e7));
  render->add_option("--seed", args->seed, "Seed")->check(seed_check())->capture_default_str();
  render->add_option("--threads", args->threads, "Threads (0: all cores)")
      ->check(CLI::Range(0, 1024));
  render->add_option("--tile", args->tile, "Tile size")->check(CLI::Range(1, 4096));
  render
      ->add_option("-o,--output", args->output,
                   "Output EXR; its PNG preview goes beside it (FILE.png)")
      ->capture_default_str();
  render->add_option("--reference", args->reference,
                     "Reference EXR of the same scene and resolution: print MRSE, per region too");
  render->add_flag("--accept-reference-mismatch", args->accept_reference_mismatch,
                   "Use a reference of another scene (scene_hash differs): warn and record it");
  render->add_flag("--strict", args->strict,
                   "Refuse the scene when its reader warns (unknown keys, ignored parameters)");
  render->add_flag("--quiet,-q", args->quiet, "No progress (a bar on a terminal, else lines)");
  render
      ->add_option("--first-pass", args->first_pass,
                   "Index of the first pass drawn (default 0): the remaining passes of an "
                   "interrupted render, to merge with its sums")
      ->check(CLI::Range(0u, 1u << 30));
  render->add_option("--sums", args->sums,
                     "Also write the exact per-pixel sums (FILE.sums) for `penumbra merge`; an "
                     "interrupted render writes them beside its EXR");
  render->callback([args] { run_render(*args); });

  // merge
  struct MergeArgs {
    std::vector<std::string> inputs;
    std::string output, sums;
  };
  auto margs = std::make_shared<MergeArgs>();
  CLI::App* merge = app.add_subcommand(
      "merge", "Merge renders of disjoint passes of one render (their sums) into one EXR");
  merge
      ->add_option("inputs", margs->inputs,
                   "Sums files (FILE.sums), or EXRs with their sums beside them")
      ->required();
  merge->add_option("-o,--output", margs->output, "Output EXR; its PNG preview goes beside it")
      ->required();
  merge->add_option("--sums", margs->sums, "Also write the merged sums (FILE.sums)");
  merge->callback([margs] { run_merge(margs->inputs, margs->output, margs->sums); });

  // probe
  struct ProbeArgs {
    std::string scene, probe, method = "sa", sampler = "stratified", samples = "1,2,4,8,16", output;
    int trials = 64;
    uint64_t seed = 0;
    bool strict = false;
  };
  auto pargs = std::make_shared<ProbeArgs>();
  CLI::App* probe = app.add_subcommand("probe", "Estimator statistics at fixed shading points");
  probe->add_option("scene", pargs->scene, "Scene file")->required();
  probe->add_option("probe", pargs->probe, "Probe file (penumbra/probe@1)")->required();
  probe->add_option("--method,-m", pargs->method, "Method")->capture_default_str();
  probe->add_option("--sampler,-s", pargs->sampler, "Sample pattern")->capture_default_str();
  probe->add_option("--samples", pargs->samples, "Sample counts N, comma-separated")
      ->capture_default_str();
  probe->add_option("--trials", pargs->trials, "Independent estimates per N")
      ->check(CLI::Range(2, 1 << 24))
      ->capture_default_str();
  probe->add_option("--seed", pargs->seed, "Seed")->check(seed_check())->capture_default_str();
  probe->add_option("--json", pargs->output, "Output file (default: standard output)");
  probe->add_flag("--strict", pargs->strict, "Refuse the scene when its reader warns");
  probe->callback([pargs] {
    if (!pargs->output.empty()) check_output_path(pargs->output, {}, "--json");
    auto scene = std::make_shared<const Scene>(load_scene(pargs->scene));
    report_scene_warnings(*scene, pargs->strict, pargs->scene);
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
    double seconds = 0;  // 0: the batch's budget
    int threads = 0;
  };
  auto dargs = std::make_shared<DemoArgs>();
  CLI::App* demo = app.add_subcommand(
      "demo", "Render the bundled comparison on cornell-occluders at equal time, with a report");
  demo->add_option("-o,--output", dargs->output, "Output folder");
  demo->add_option("--seconds", dargs->seconds,
                   "Compute seconds per method and repeat (default: the batch's)")
      ->check(CLI::Range(0.0, 1e7));
  demo->add_option("--threads", dargs->threads, "Threads (0: all cores)");
  demo->callback([dargs] { run_local_demo(dargs->output, dargs->seconds, dargs->threads); });
  add_reproduce_command(app);
}

}  // namespace penumbra
