// `penumbra exact SCENE PROBE --json OUT`: exact direct illumination at a probe's pixels and
// points (core/exact/exact_probe.h); `penumbra exact-reference SCENE -o OUT.exr`: an exact
// reference image (core/exact/exact_reference.h).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "client/cli_options.h"
#include "client/commands.h"
#include "client/read_file.h"
#include "client/scene_checks.h"
#include "core/exact/exact_probe.h"
#include "core/exact/exact_reference.h"
#include "core/image/image.h"

namespace penumbra {

void add_exact_commands(CLI::App& app) {
  struct ExactArgs {
    std::string scene, probe, output, fallback = "bsdf+sa";
    int fallback_samples = 256;
    uint64_t seed = 0x5eed;
    bool strict = false;
  };
  auto args = std::make_shared<ExactArgs>();
  CLI::App* exact = app.add_subcommand(
      "exact",
      "Exact direct illumination at a probe's pixels and points (Lambertian receivers, "
      "constant polygonal lights; else a converged estimate, marked \"exact\": false)");
  exact->add_option("scene", args->scene, "Scene file")->required();
  exact->add_option("probe", args->probe, "Probe file (penumbra/probe@1)")->required();
  exact->add_option("--json", args->output, "Output file (default: standard output)");
  exact->add_option("--fallback", args->fallback, "Method where no closed form applies");
  exact
      ->add_option("--fallback-samples", args->fallback_samples,
                   "Samples per term of the fallback method")
      ->check(CLI::Range(1, 1 << 24));
  exact->add_option("--seed", args->seed, "Seed of the fallback estimates")
      ->check(seed_check())
      ->capture_default_str();
  exact->add_flag("--strict", args->strict, "Refuse the scene when its reader warns");
  exact->callback([args] {
    if (!args->output.empty()) check_output_path(args->output, {}, "--json");
    auto scene = std::make_shared<const Scene>(load_scene(args->scene));
    report_scene_warnings(*scene, args->strict, args->scene);
    ProbeSpec probe = parse_probe(read_file(args->probe), args->probe);
    ExactShadingOptions options;
    options.fallback_method = args->fallback;
    options.fallback_samples = args->fallback_samples;
    const std::string text = exact_probe_json(scene, probe, options, args->seed);
    if (args->output.empty()) {
      std::printf("%s\n", text.c_str());
      return;
    }
    std::ofstream out(args->output);
    out << text << "\n";
    if (!out) throw std::runtime_error("cannot write " + args->output);
    const nlohmann::json doc = nlohmann::json::parse(text);
    std::printf("%s: %zu points, %.1f%% exact (%d by the fallback %s)\n", args->output.c_str(),
                doc["points"].size(), 100.0 * doc["exact_share"].get<double>(),
                doc["fallback_points"].get<int>(), args->fallback.c_str());
  });

  struct ReferenceArgs {
    std::string scene, output, fallback = "bsdf+sa";
    int fallback_samples = 64, threads = 0;
    uint32_t camera_samples = 16;
    uint64_t seed = 0x5eed;
    bool strict = false;
  };
  auto rargs = std::make_shared<ReferenceArgs>();
  CLI::App* reference = app.add_subcommand(
      "exact-reference", "Render an exact reference image (closed form per camera sample)");
  reference->add_option("scene", rargs->scene, "Scene file")->required();
  reference->add_option("-o,--output", rargs->output, "Output EXR")->required();
  reference->add_option("--camera-samples", rargs->camera_samples, "Camera rays per pixel")
      ->check(CLI::Range(1, 1 << 20));
  reference->add_option("--fallback", rargs->fallback, "Method where no closed form applies");
  reference
      ->add_option("--fallback-samples", rargs->fallback_samples,
                   "Samples per term of the fallback method per camera sample")
      ->check(CLI::Range(1, 1 << 24));
  reference->add_option("--seed", rargs->seed, "Seed")->check(seed_check())->capture_default_str();
  reference->add_option("--threads", rargs->threads, "Threads (0: all cores)");
  reference->add_flag("--strict", rargs->strict, "Refuse the scene when its reader warns");
  reference->callback([rargs] {
    check_output_path(rargs->output, {".exr"}, "-o");
    auto scene = std::make_shared<const Scene>(load_scene(rargs->scene));
    report_scene_warnings(*scene, rargs->strict, rargs->scene);
    ExactReferenceOptions options;
    options.camera_samples = rargs->camera_samples;
    options.shading.fallback_method = rargs->fallback;
    options.shading.fallback_samples = rargs->fallback_samples;
    options.seed = rargs->seed;
    options.threads = rargs->threads;
    ExactReferenceImage image = render_exact_reference(scene, options);
    write_exr(rargs->output, image.film.color, &image.film.variance,
              exact_reference_metadata(*scene, options, image),
              {ExrChannel{kExactMaskChannel, image.fallback_mask()}});
    const double total = double(image.exact_samples + image.fallback_samples);
    std::printf(
        "%s: %u camera samples per pixel, %.1f%% exact (%.1f%% of the pixels have a %s sample, "
        "marked in the EXR's %s channel), %.2f s compute (%.2f s wall), %.2f us per camera "
        "sample; %.1f candidate occluders per exact point\n",
        rargs->output.c_str(), options.camera_samples, 100.0 * double(image.exact_samples) / total,
        100.0 * image.fallback_pixel_share(), options.shading.fallback_method.c_str(),
        kExactMaskChannel, image.compute_seconds, image.wall_seconds,
        1e6 * image.compute_seconds / total,
        image.exact_samples ? double(image.stats.candidates) / double(image.exact_samples) : 0.0);
  });
}

}  // namespace penumbra
