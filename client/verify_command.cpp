// `penumbra verify SCENE --method M`: k independent runs z-tested per pixel block against an
// exact reference (or an EXR reference); exit code 4 when a block is biased beyond the
// threshold (core/analysis/verify.h, core/analysis/bias_check.h).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>

#include "client/cli_options.h"
#include "client/commands.h"
#include "client/scene_checks.h"
#include "core/analysis/verify.h"
#include "core/image/image.h"
#include "core/scene/render_settings.h"

namespace penumbra {

namespace {

struct VerifyArgs {
  std::string scene, method, sampler, reference, output, fallback = "bsdf+sa", reference_method;
  uint32_t reference_spp = 1024;
  int runs = 4, width = 128, block = 8, threads = 0, fallback_samples = 64;
  uint32_t spp = 0, camera_samples = 64;
  double seconds = 0, sigma = 5;
  uint64_t seed = 1, reference_seed = 0x5eed;
  bool strict = false, accept_reference_mismatch = false;
};

void run_verify(const VerifyArgs& args) {
  if (!args.output.empty()) check_output_path(args.output, {}, "--json");
  if (!args.reference.empty() && !args.reference_method.empty())
    throw std::runtime_error("--reference and --reference-method: give one reference");
  Scene loaded = load_scene(args.scene);
  report_scene_warnings(loaded, args.strict, args.scene);
  RenderSettings settings = choose_render_settings(loaded, {args.method, args.sampler, 0, 0});
  std::optional<Pattern> sampler = parse_pattern(settings.sampler);
  if (!sampler) throw FormatError("sampler", "unknown sampler \"" + settings.sampler + "\"");

  // The reference: an EXR at its own resolution, or the exact reference at --width.
  VerifyReference reference;
  std::shared_ptr<const Scene> scene;
  if (!args.reference.empty()) {
    Image variance;
    ImageMetadata metadata;
    Image color = read_exr(args.reference, &metadata, &variance);
    Scene sized = color.width == loaded.camera.width ? loaded : scene_at_width(loaded, color.width);
    if (sized.camera.height != color.height)
      throw std::runtime_error(args.reference + ": " + std::to_string(color.width) + "x" +
                               std::to_string(color.height) + " is not the scene's aspect (" +
                               std::to_string(loaded.camera.width) + "x" +
                               std::to_string(loaded.camera.height) + ")");
    for (const std::string& warning :
         check_reference(args.reference, sized, args.accept_reference_mismatch).warnings)
      std::fprintf(stderr, "penumbra: warning: %s\n", warning.c_str());
    if (variance.width == 0) {
      std::fprintf(stderr,
                   "penumbra: warning: %s has no variance layer: its noise is taken as zero, so "
                   "its own noise can be flagged as bias\n",
                   args.reference.c_str());
      variance = Image(color.width, color.height);
    }
    reference.film.color = std::move(color);
    reference.film.variance = std::move(variance);
    reference.description = args.reference;
    // Its seed, when it states one, must not be a run's.
    reference.seed = metadata.count("penumbra:seed")
                         ? std::strtoull(metadata["penumbra:seed"].c_str(), nullptr, 10)
                         : ~uint64_t(0);
    scene = std::make_shared<const Scene>(std::move(sized));
  } else if (!args.reference_method.empty()) {
    scene =
        std::make_shared<const Scene>(args.width > 0 ? scene_at_width(loaded, args.width) : loaded);
    reference = render_deep_reference(scene, args.reference_method, *sampler, args.reference_spp,
                                      args.reference_seed, args.threads);
  } else {
    scene =
        std::make_shared<const Scene>(args.width > 0 ? scene_at_width(loaded, args.width) : loaded);
    ExactReferenceOptions options;
    options.camera_samples = args.camera_samples;
    options.shading.fallback_method = args.fallback;
    options.shading.fallback_samples = args.fallback_samples;
    options.seed = args.reference_seed;
    options.threads = args.threads;
    reference = render_verify_reference(scene, options);
  }

  RenderBudget budget;
  if (args.seconds > 0) {
    budget.seconds = args.seconds;
    if (args.spp > 0) budget.max_spp = args.spp;
  } else {
    budget.spp = args.spp > 0 ? args.spp : 16;
  }
  RunRenderer render = method_run_renderer(scene, settings.method, *sampler, budget, args.threads);
  BiasCheckOptions check;
  check.block_size = args.block;
  check.sigma = args.sigma;
  VerifyResult result = verify_runs(reference, args.runs, args.seed, render, check);

  std::string spp;
  for (uint32_t s : result.spp) spp += (spp.empty() ? "" : ",") + std::to_string(s);
  std::printf("verify %s on %s (%s sampler), %d runs of %s spp (seeds %llu..%llu)\n",
              settings.method.c_str(), scene->name.c_str(), settings.sampler.c_str(), args.runs,
              spp.c_str(), (unsigned long long)args.seed,
              (unsigned long long)(args.seed + uint64_t(args.runs) - 1));
  std::printf("reference: %s\n", reference.description.c_str());
  std::printf("%s", bias_check_text(result.check, settings.method).c_str());
  if (!args.output.empty()) {
    std::ofstream out(args.output);
    out << bias_check_json(result.check, scene->name, settings.method) << "\n";
    if (!out) throw std::runtime_error("cannot write " + args.output);
  }
  if (!result.check.passed()) set_command_exit_code(4);
}

}  // namespace

void add_verify_command(CLI::App& app) {
  auto args = std::make_shared<VerifyArgs>();
  CLI::App* verify = app.add_subcommand(
      "verify",
      "Bias check: k independent runs of a method z-tested per pixel block against an exact "
      "reference (exit code 4 when a block is biased beyond --sigma)");
  verify->add_option("scene", args->scene, "Scene file (penumbra/scene@1 or pbrt-v3)")->required();
  verify->add_option("--method,-m", args->method, "Method (default: the scene's own, else sa)");
  verify->add_option("--sampler,-s", args->sampler,
                     "Sample pattern (default: the scene's own, else stratified)");
  verify->add_option("--runs,-k", args->runs, "Independent runs")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  verify
      ->add_option("--spp", args->spp,
                   "Samples per pixel per run (default 16); with --seconds, the most a run renders")
      ->check(CLI::Range(1u, 1u << 20));
  verify->add_option("--seconds", args->seconds, "Compute seconds per run instead of --spp")
      ->check(CLI::Range(1e-3, 1e7));
  verify->add_option("--seed", args->seed, "Seed of the first run (run r uses seed + r)")
      ->check(seed_check())
      ->capture_default_str();
  verify
      ->add_option("--width", args->width,
                   "Render at this many pixels across, the same view (0: the scene's own)")
      ->check(CLI::Range(0, 1 << 16))
      ->capture_default_str();
  verify->add_option("--block", args->block, "Block size in pixels")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  verify->add_option("--sigma", args->sigma, "Flag blocks with |z| above this")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  verify->add_option("--reference", args->reference,
                     "Reference EXR with a variance layer, instead of the exact reference (its "
                     "resolution sets the runs')");
  verify->add_option("--reference-method", args->reference_method,
                     "A deep render of this method as the reference, instead of the exact one "
                     "(scenes whose exact reference is costly)");
  verify->add_option("--reference-spp", args->reference_spp, "Samples per pixel of the deep render")
      ->check(CLI::Range(1u, 1u << 20))
      ->capture_default_str();
  verify->add_flag("--accept-reference-mismatch", args->accept_reference_mismatch,
                   "Use a reference of another scene (scene_hash differs): warn");
  verify
      ->add_option("--camera-samples", args->camera_samples,
                   "Camera rays per pixel of the exact reference")
      ->check(CLI::Range(1u, 1u << 20))
      ->capture_default_str();
  verify
      ->add_option("--fallback", args->fallback,
                   "The exact reference's method where no closed form applies")
      ->capture_default_str();
  verify
      ->add_option("--fallback-samples", args->fallback_samples,
                   "Samples per term of the fallback per camera sample")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  verify->add_option("--reference-seed", args->reference_seed, "Seed of the exact reference")
      ->check(seed_check())
      ->capture_default_str();
  verify->add_option("--threads", args->threads, "Threads (0: all cores)")
      ->check(CLI::Range(0, 1024));
  verify->add_option("--json", args->output, "Also write the result as JSON");
  verify->add_flag("--strict", args->strict, "Refuse the scene when its reader warns");
  verify->callback([args] { run_verify(*args); });
}

}  // namespace penumbra
