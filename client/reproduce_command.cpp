// `penumbra stability [-o DIR]`: every method against every adversarial configuration
// (core/analysis/stability.h): the method-by-case table of bias and non-finite counts.
//
// `penumbra reproduce [--quick|--full] [-o DIR]`: reruns the papers' experiments
// (core/analysis/reproduction_suite.h), prints one table (paper figure beside ours, with pass or
// fail), writes one chart per figure (SVG and PNG) and the table as JSON into DIR. Exit code 4
// when a row fails.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>

#include "client/commands.h"
#include "client/progress.h"
#include "core/analysis/reproduction_suite.h"
#include "core/analysis/stability.h"

namespace penumbra {

namespace {

struct ReproduceArgs {
  bool quick = false, full = false;
  std::string output = "reproduce-out";
  std::string scenes = PENUMBRA_SCENES_DIR;
  int threads = 0;
  bool quiet = false;
};

// Progress of the experiments (or stability steps) on standard error: a bar with the steps done,
// their rate and the ETA, and the one running; plain lines, one per step, when not a terminal.
std::function<void(const std::string&, int, int)> step_progress(ProgressReporter& progress) {
  return [&progress](const std::string& what, int done, int total) {
    progress.update(done, total, "steps", done < total ? what : "");
  };
}

void run_reproduce(const ReproduceArgs& args) {
  ReproductionOptions options;
  options.full = args.full;
  options.scenes_dir = args.scenes;
  options.threads = args.threads;
  ProgressReporter progress("reproduce", args.quiet ? ProgressMode::Quiet : ProgressMode::Auto,
                            stderr, 0.0);
  options.progress = step_progress(progress);
  ReproductionReport report = run_reproduction_suite(options);
  progress.finish();

  std::printf("%s", format_reproduction_table(report).c_str());
  std::filesystem::create_directories(args.output);
  std::filesystem::path json_path = std::filesystem::path(args.output) / "reproduce.json";
  {
    std::ofstream out(json_path);
    out << reproduction_json(report) << "\n";
    if (!out) throw std::runtime_error("cannot write " + json_path.string());
  }
  std::filesystem::path details_path = std::filesystem::path(args.output) / "details.txt";
  {
    std::ofstream out(details_path);
    for (const std::string& table : report.details) out << table << "\n";
    if (!out) throw std::runtime_error("cannot write " + details_path.string());
  }
  std::vector<std::string> charts = write_reproduction_charts(report, args.output);
  std::printf("wrote %s, %s and %zu charts to %s\n", json_path.filename().c_str(),
              details_path.filename().c_str(), charts.size(), args.output.c_str());
  if (!report.passed()) set_command_exit_code(4);
}

struct StabilityArgs {
  std::string output = "stability-out";
  int trials = 256, samples = 4;
  bool quiet = false;
};

void run_stability_command(const StabilityArgs& args) {
  StabilityOptions options;
  options.trials = args.trials;
  options.samples = args.samples;
  ProgressReporter progress("stability", args.quiet ? ProgressMode::Quiet : ProgressMode::Auto);
  options.progress = step_progress(progress);
  StabilityTable table = run_stability(options);
  progress.finish();
  std::string markdown = stability_markdown(table);
  std::printf("%s", markdown.c_str());
  std::filesystem::create_directories(args.output);
  for (auto [name, text] :
       {std::pair{"stability.md", markdown}, std::pair{"stability.json", stability_json(table)}}) {
    std::filesystem::path path = std::filesystem::path(args.output) / name;
    std::ofstream out(path);
    out << text << "\n";
    if (!out) throw std::runtime_error("cannot write " + path.string());
  }
  uint64_t nonfinite = 0, inconsistent = 0;
  for (const StabilityCell& cell : table.cells) {
    nonfinite += cell.nonfinite;
    inconsistent += !cell.refused && !cell.consistent && cell.expected_unconverged.empty();
  }
  std::printf(
      "%llu non-finite estimates, %llu inconsistent cells; wrote stability.md and "
      "stability.json to %s\n",
      (unsigned long long)nonfinite, (unsigned long long)inconsistent, args.output.c_str());
  if (nonfinite) set_command_exit_code(4);
}

}  // namespace

void add_reproduce_command(CLI::App& app) {
  auto args = std::make_shared<ReproduceArgs>();
  CLI::App* reproduce = app.add_subcommand(
      "reproduce", "Rerun the papers' experiments: table, charts (SVG, PNG) and JSON");
  auto* quick = reproduce->add_flag("--quick", args->quick, "Quick mode (default; a few minutes)");
  auto* full = reproduce->add_flag("--full", args->full, "Full mode: more trials, pixels and N");
  quick->excludes(full);
  reproduce->add_option("-o,--output", args->output, "Output folder for charts and JSON");
  reproduce->add_option("--scenes", args->scenes, "Folder of the bundled scenes");
  reproduce->add_option("--threads", args->threads, "Threads (0: all cores)")
      ->check(CLI::Range(0, 1024));
  reproduce->add_flag("--quiet,-q", args->quiet, "No progress (a bar on a terminal, else lines)");
  reproduce->callback([args] { run_reproduce(*args); });

  auto stability_args = std::make_shared<StabilityArgs>();
  CLI::App* stability = app.add_subcommand(
      "stability", "Every method against adversarial configurations: bias and NaN/Inf table");
  stability->add_option("-o,--output", stability_args->output, "Output folder (md, json)");
  stability->add_option("--trials", stability_args->trials, "Estimates per method and case")
      ->check(CLI::Range(2, 1 << 20));
  stability->add_option("--samples", stability_args->samples, "Samples per estimate (N)")
      ->check(CLI::Range(1, 1 << 16));
  stability->add_flag("--quiet,-q", stability_args->quiet,
                      "No progress (a bar on a terminal, else lines)");
  stability->callback([stability_args] { run_stability_command(*stability_args); });
}

}  // namespace penumbra
