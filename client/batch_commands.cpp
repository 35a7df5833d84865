// The client's batch commands: `penumbra batch submit|watch|status|list|cancel|fetch|
// run` and `penumbra report`. They talk to the coordinator's Batches service
// (proto/support/batch_client.h) named by --coordinator or PENUMBRA_COORDINATOR, with TLS and a
// token as the farm commands take them; `batch run` without --coordinator starts an embedded
// farm (server/embedded_farm.h) with --workers local workers.
#include "client/batch_commands.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "client/batch_summary.h"
#include "client/commands.h"
#include "client/progress.h"
#include "client/read_file.h"
#include "client/scene_checks.h"
#include "core/report/batch_result.h"

#ifdef PENUMBRA_WITH_FARM
#include "client/connection_options.h"
#include "client/exact_reference_cache.h"
#include "core/batch/batch_spec.h"
#include "core/report/batch_report.h"
#include "core/report/deep_reference_check.h"
#include "proto/support/batch_client.h"
#include "proto/support/scene_packing.h"
#include "proto/support/state_names.h"
#include "server/embedded_farm.h"
#endif

#ifndef PENUMBRA_SCENES_DIR
#define PENUMBRA_SCENES_DIR "scenes"
#endif

namespace penumbra {

std::string bundled_scene_path(const std::string& name) {
  const char* env = std::getenv("PENUMBRA_SCENES");
  std::filesystem::path dir = env && *env ? env : PENUMBRA_SCENES_DIR;
  return (dir / (name + ".json")).string();
}

std::string bundled_batch_path(const std::string& name) {
  const char* env = std::getenv("PENUMBRA_BATCHES");
  std::filesystem::path dir =
      env && *env ? std::filesystem::path(env)
                  : std::filesystem::path(PENUMBRA_SCENES_DIR).parent_path() / "batches";
  return (dir / (name + ".json")).string();
}

#ifdef PENUMBRA_WITH_FARM

namespace {

using farm::state_name;

std::string progress_line(const v1::BatchStatus& status) {
  char text[256];
  std::snprintf(text, sizeof text, "%s %-11s jobs %u/%u  compute %.1f s  wall %.1f s",
                status.batch_id().c_str(), state_name(status.state()).c_str(), status.jobs_done(),
                status.jobs_total(), status.compute_seconds(), status.wall_seconds());
  return text;
}

// Follows the batch: a bar of jobs done with their rate and the ETA and the running jobs' MRSE,
// redrawn in place on a terminal; plain lines (at most one per 2 s, and one per phase)
// otherwise; nothing with `quiet`.
v1::BatchStatus watch_batch(farm::BatchClient& client, const std::string& batch_id,
                            bool quiet = false) {
  ProgressReporter progress(batch_id, quiet ? ProgressMode::Quiet : ProgressMode::Auto, stdout);
  std::string phase;
  v1::BatchStatus final_status = client.watch(batch_id, [&](const v1::BatchStatus& status) {
    char text[160];
    std::snprintf(text, sizeof text, "%s, compute %.1f s, wall %.1f s",
                  state_name(status.state()).c_str(), status.compute_seconds(),
                  status.wall_seconds());
    std::string extra = text;
    std::vector<std::pair<std::string, double>> running;
    for (const v1::BatchMethodStatus& method : status.methods())
      for (const v1::BatchRun& run : method.runs())
        if (run.job().state() == v1::JOB_STATE_RUNNING && run.job().has_mrse())
          running.emplace_back(method.label(), run.job().mrse());
    if (!running.empty()) extra += ", " + running_mrse_text(running);
    if (state_name(status.state()) != phase) {
      if (!phase.empty()) progress.note(batch_id + ": " + state_name(status.state()));
      phase = state_name(status.state());
    }
    // Jobs per wall second of the batch itself (it may have started before this watch).
    double rate = status.wall_seconds() > 0 ? status.jobs_done() / status.wall_seconds() : 0;
    progress.update(status.jobs_done(), status.jobs_total(), "jobs", extra, rate, "jobs/s",
                    status.wall_seconds());
  });
  progress.finish();
  return final_status;
}

void print_status(const v1::BatchStatus& status) {
  std::printf("batch      %s  %s\n", status.batch_id().c_str(), status.name().c_str());
  std::printf("state      %s%s%s\n", state_name(status.state()).c_str(),
              status.error().empty() ? "" : ": ", status.error().c_str());
  std::printf("scene      %s (%ux%u, %s)\n", status.scene_name().c_str(), status.width(),
              status.height(), status.scene_hash().substr(0, 12).c_str());
  const v1::BatchReferenceStatus& reference = status.reference();
  std::printf("reference  %s %s%s%s %s at %u spp%s\n", reference.kind().c_str(),
              reference.job_id().c_str(), reference.job_id().empty() ? "" : " ",
              reference.method().c_str(), reference.sampler().c_str(), reference.spp(),
              reference.cached() ? " (cached)" : "");
  if (reference.sizing().sized()) {
    const v1::BatchReferenceSizing& sizing = reference.sizing();
    std::printf(
        "           sized: the %g%% target asked for %.0f spp%s; predicted reference share "
        "%.2f%% in \"%s\"\n",
        100 * sizing.target_share(), std::ceil(sizing.required_spp()),
        sizing.capped()
            ? (", capped by max_seconds = " + std::to_string(sizing.max_seconds())).c_str()
            : "",
        100 * sizing.predicted_share(), sizing.deciding_region().c_str());
  } else if (reference.sizing().probe_jobs_size() > 0) {
    std::printf("           sizing from %d probes of %u spp\n",
                reference.sizing().probe_jobs_size(), reference.sizing().probe_spp());
  }
  std::printf("jobs       %u/%u done; %.2f compute s, %.2f wall s\n", status.jobs_done(),
              status.jobs_total(), status.compute_seconds(), status.wall_seconds());
  std::printf("%-32s %-10s %8s %10s %10s %10s\n", "label", "run", "spp", "compute s", "wall s",
              "MRSE");
  for (const v1::BatchMethodStatus& method : status.methods()) {
    if (!method.error().empty()) {
      std::printf("%-32s refused: %s\n", method.label().c_str(), method.error().c_str());
      continue;
    }
    if (method.runs_size() == 0)
      std::printf("%-32s %s\n", method.label().c_str(),
                  method.seconds_per_pass() > 0 ? "calibrated" : "waiting");
    for (const v1::BatchRun& run : method.runs()) {
      std::string name =
          (run.equal_time() ? std::string("equal") : std::to_string(run.spp_planned()) + "spp") +
          ".r" + std::to_string(run.repeat());
      std::printf("%-32s %-10s %8u %10.2f %10.2f %10s\n", method.label().c_str(), name.c_str(),
                  run.job().passes_complete(), run.job().compute_seconds(),
                  run.job().wall_seconds(),
                  run.job().has_mrse() ? std::to_string(run.job().mrse()).c_str() : "-");
    }
  }
}

// The summary table from a written result folder (client/batch_summary.h), after the warning
// for a reference barely cleaner than the runs.
void print_summary(const std::filesystem::path& dir) {
  std::ifstream in(dir / "batch.json");
  nlohmann::json index = nlohmann::json::parse(in);
  try {
    const BatchResult result = read_batch_result(dir);
    if (result.reference.sizing)
      std::printf("reference: %s\n", reference_sizing_text(result.reference).c_str());
    if (std::string warning = reference_depth_warning(result); !warning.empty())
      std::fprintf(stderr, "penumbra: warning: %s\n", warning.c_str());
  } catch (const std::exception&) {
    // The table below still prints; the report reads the folder again and names any problem.
  }
  std::fputs(batch_summary_table(index).c_str(), stdout);
}

std::string folder_of(const std::string& path) {
  std::string folder = std::filesystem::path(path).parent_path().string();
  return folder.empty() ? "." : folder;
}

// The scene's warnings printed (refused when the spec says "strict": true) before anything is
// sent; a batch whose reference is exact: rendered (or read from the cache) here and uploaded
// with the batch like an EXR reference. Returns the scene's content hash.
std::string attach_exact_reference(v1::SubmitBatchRequest& request) {
  BatchSpec spec = parse_batch_spec(request.spec_json(), request.source_name());
  const Scene scene = farm::parse_wire_package(request.scene());
  report_scene_warnings(scene, spec.strict, spec.scene);
  if (spec.reference.kind != BatchReferenceKind::Exact) return scene.content_hash;
  std::printf("batch: exact reference for %s (%u camera samples per pixel)...\n",
              scene.name.c_str(), spec.reference.camera_samples);
  std::fflush(stdout);
  CachedExactReference reference = exact_reference_for(scene, spec.reference);
  if (reference.cached)
    std::printf(
        "batch: exact reference read from the cache %s (%.1f%% of camera samples exact; %.1f%% of "
        "the pixels have a fallback sample, marked in its exact.mask channel)\n",
        reference.path.string().c_str(), 100 * reference.exact_share,
        100 * reference.fallback_pixel_share);
  else
    std::printf(
        "batch: exact reference rendered in %.1f compute s (%.1f%% of camera samples exact; "
        "%.1f%% of the pixels have a fallback sample, marked in its exact.mask channel), cached "
        "as %s\n",
        reference.compute_seconds, 100 * reference.exact_share,
        100 * reference.fallback_pixel_share, reference.path.string().c_str());
  request.set_reference_exr(std::move(reference.exr));
  return scene.content_hash;
}

struct SpecArguments {
  std::string spec;
  std::string output;
  ConnectionArguments connection;
  bool coordinator_given = false;
  int workers = 0;
  bool no_report = false;
  bool quiet = false;
};

struct IdArguments {
  std::string id;
  std::string output;
  ConnectionArguments connection;
  bool quiet = false;  // watch: no progress
};

}  // namespace

std::string run_batch(const std::string& spec_text, const std::string& source_name,
                      const std::string& base_dir, const std::filesystem::path& out_dir,
                      const BatchRunSettings& settings) {
  v1::SubmitBatchRequest request =
      farm::make_batch_request_from_text(spec_text, source_name, base_dir, bundled_scene_path);
  const std::string scene_hash = attach_exact_reference(request);
  std::unique_ptr<farm::EmbeddedFarm> embedded;
  farm::FarmConnection connection;
  if (settings.coordinator.empty()) {
    farm::EmbeddedFarmOptions options;
    options.workers = settings.workers > 0 ? settings.workers
                                           : int(std::max(1u, std::thread::hardware_concurrency()));
    options.threads_per_worker = std::max(1, settings.threads_per_worker);
    // The embedded coordinator and workers log at warn and above: the batch prints its own
    // progress. PENUMBRA_LOG_LEVEL=info (or debug, trace) shows theirs.
    const char* level = std::getenv("PENUMBRA_LOG_LEVEL");
    spdlog::set_level(level ? spdlog::level::from_str(level) : spdlog::level::warn);
    embedded = std::make_unique<farm::EmbeddedFarm>(options);
    std::printf("batch: embedded farm at %s with %d worker(s)\n", embedded->address().c_str(),
                options.workers);
    connection.address = embedded->address();
  } else {
    connection.address = settings.coordinator;
    connection.tls_ca = settings.tls_ca;
    connection.tls_cert = settings.tls_cert;
    connection.tls_key = settings.tls_key;
    connection.token = settings.token;
  }
  farm::BatchClient client(connection);
  v1::SubmitBatchResponse response = client.upload_and_submit(request, scene_hash);
  std::printf("%s submitted (scene %s)\n", response.batch_id().c_str(),
              response.scene_hash().substr(0, 12).c_str());
  std::fflush(stdout);
  v1::BatchStatus status = watch_batch(client, response.batch_id(), settings.quiet);
  if (status.state() != v1::BATCH_STATE_DONE)
    throw std::runtime_error(response.batch_id() + " ended " + state_name(status.state()) +
                             (status.error().empty() ? std::string() : ": " + status.error()));
  farm::write_batch_result(client, status, out_dir);
  std::printf("batch: wrote the result folder %s (%.1f s wall, %.1f s compute)\n",
              out_dir.string().c_str(), status.wall_seconds(), status.compute_seconds());
  if (settings.print_table) print_summary(out_dir);
  if (settings.write_report) {
    write_batch_report(out_dir, out_dir);
    std::printf("batch: wrote the report %s\n", (out_dir / "report.html").string().c_str());
  }
  return response.batch_id();
}

void add_batch_commands(CLI::App& app) {
  CLI::App* batch =
      app.add_subcommand("batch", "Equal-time comparison batches (penumbra/batch@1) on the farm");
  batch->require_subcommand(1);

  auto run_arguments = std::make_shared<SpecArguments>();
  CLI::App* run = batch->add_subcommand(
      "run", "Submit a batch, watch it, fetch its result folder and write its report into DIR");
  run->add_option("spec", run_arguments->spec, "Batch spec file, or a bundled batch's name")
      ->required();
  run->add_option("-o,--output", run_arguments->output, "Output folder")->required();
  add_connection_options(run, run_arguments->connection);
  run->add_option("--workers", run_arguments->workers,
                  "Without --coordinator: local workers of the embedded farm (0: one per core)");
  run->add_flag("--no-report", run_arguments->no_report, "Write the result folder only");
  run->add_flag("--quiet,-q", run_arguments->quiet,
                "No progress (a bar on a terminal, else lines)");
  run->callback([run, run_arguments] {
    std::string path = run_arguments->spec;
    if (!std::filesystem::exists(path) && path.find('/') == std::string::npos)
      path = bundled_batch_path(path);
    BatchRunSettings settings;
    if (run->get_option("--coordinator")->count() > 0) {
      settings.coordinator = run_arguments->connection.coordinator;
      farm::FarmConnection connection = connection_of(run_arguments->connection);
      settings.tls_ca = connection.tls_ca;
      settings.tls_cert = connection.tls_cert;
      settings.tls_key = connection.tls_key;
      settings.token = connection.token;
    }
    settings.workers = run_arguments->workers;
    settings.write_report = !run_arguments->no_report;
    settings.quiet = run_arguments->quiet;
    run_batch(read_file(path), path, folder_of(path), run_arguments->output, settings);
  });

  auto submit_arguments = std::make_shared<SpecArguments>();
  CLI::App* submit = batch->add_subcommand("submit", "Submit a batch; prints its id");
  submit->add_option("spec", submit_arguments->spec, "Batch spec file")->required();
  add_connection_options(submit, submit_arguments->connection);
  submit->callback([submit_arguments] {
    std::string path = submit_arguments->spec;
    if (!std::filesystem::exists(path) && path.find('/') == std::string::npos)
      path = bundled_batch_path(path);
    farm::BatchClient client(connection_of(submit_arguments->connection));
    v1::SubmitBatchRequest request = farm::make_batch_request(path, bundled_scene_path);
    const std::string scene_hash = attach_exact_reference(request);
    v1::SubmitBatchResponse response = client.upload_and_submit(request, scene_hash);
    std::printf("%s\n", response.batch_id().c_str());
  });

  auto id_command = [&](const char* name, const char* description,
                        std::shared_ptr<IdArguments> arguments) {
    CLI::App* command = batch->add_subcommand(name, description);
    command->add_option("batch", arguments->id, "Batch id (batch-3)")->required();
    add_connection_options(command, arguments->connection);
    return command;
  };
  auto watch_arguments = std::make_shared<IdArguments>();
  CLI::App* watch = id_command("watch", "Follow a batch until it ends", watch_arguments);
  watch->add_flag("--quiet,-q", watch_arguments->quiet,
                  "No progress (a bar on a terminal, else lines)");
  watch->callback([watch_arguments] {
    farm::BatchClient client(connection_of(watch_arguments->connection));
    v1::BatchStatus status = watch_batch(client, watch_arguments->id, watch_arguments->quiet);
    print_status(status);
    if (status.state() != v1::BATCH_STATE_DONE) set_command_exit_code(1);
  });
  auto status_arguments = std::make_shared<IdArguments>();
  id_command("status", "A batch's state, jobs and errors", status_arguments)
      ->callback([status_arguments] {
        farm::BatchClient client(connection_of(status_arguments->connection));
        print_status(client.status(status_arguments->id));
      });
  auto cancel_arguments = std::make_shared<IdArguments>();
  id_command("cancel", "Cancel a batch's unfinished jobs", cancel_arguments)
      ->callback([cancel_arguments] {
        farm::BatchClient client(connection_of(cancel_arguments->connection));
        print_status(client.cancel(cancel_arguments->id));
      });
  auto fetch_arguments = std::make_shared<IdArguments>();
  CLI::App* fetch =
      id_command("fetch", "Write a finished batch's result folder into DIR", fetch_arguments);
  fetch->add_option("-o,--output", fetch_arguments->output, "Output folder")->required();
  fetch->callback([fetch_arguments] {
    farm::BatchClient client(connection_of(fetch_arguments->connection));
    farm::write_batch_result(client, client.status(fetch_arguments->id), fetch_arguments->output);
    std::printf("wrote %s\n",
                (std::filesystem::path(fetch_arguments->output) / "batch.json").string().c_str());
  });
  auto list_connection = std::make_shared<ConnectionArguments>();
  CLI::App* list = batch->add_subcommand("list", "List the coordinator's batches");
  add_connection_options(list, *list_connection);
  list->callback([list_connection] {
    farm::BatchClient client(connection_of(*list_connection));
    for (const v1::BatchStatus& status : client.list())
      std::printf("%s  %-32s %s\n", progress_line(status).c_str(), status.name().c_str(),
                  status.scene_name().c_str());
  });

  auto report_arguments = std::make_shared<IdArguments>();
  CLI::App* report = app.add_subcommand(
      "report", "Write a batch's report: from a result folder, or fetched by batch id first");
  report->add_option("batch", report_arguments->id, "Batch result folder or batch id")->required();
  report->add_option("-o,--output", report_arguments->output, "Output folder")->required();
  add_connection_options(report, report_arguments->connection);
  auto report_reference = std::make_shared<std::string>();
  report->add_option("--reference", *report_reference,
                     "Measure the runs against this EXR instead of the batch's reference");
  report->callback([report_arguments, report_reference] {
    std::filesystem::path source = report_arguments->id;
    std::filesystem::path out = report_arguments->output;
    if (!std::filesystem::is_directory(source)) {
      farm::BatchClient client(connection_of(report_arguments->connection));
      source = out / "result";
      farm::write_batch_result(client, client.status(report_arguments->id), source);
    }
    BatchReportOptions options;
    options.reference_exr = *report_reference;
    write_batch_report(source, out, options);
    std::printf("wrote %s\n", (out / "report.html").string().c_str());
  });

  struct DepthArguments {
    std::string folder, deep, json;
    double tolerance = 0.10;
  };
  auto depth_arguments = std::make_shared<DepthArguments>();
  CLI::App* depth = app.add_subcommand(
      "check-depth",
      "Check a batch's table against a deeper reference: every cell's corrected MRSE within "
      "--tolerance of the same runs' MRSE against DEEP (exit status 1 when not)");
  depth->add_option("folder", depth_arguments->folder, "Batch result folder")->required();
  depth->add_option("--deep", depth_arguments->deep, "The deeper reference EXR")->required();
  depth->add_option("--tolerance", depth_arguments->tolerance, "Relative tolerance")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  depth->add_option("--json", depth_arguments->json, "Also write the check as JSON");
  depth->callback([depth_arguments] {
    const DeepCheck check = check_against_deep_reference(
        depth_arguments->folder, depth_arguments->deep, depth_arguments->tolerance);
    std::printf("%s", deep_check_text(check).c_str());
    if (!depth_arguments->json.empty()) {
      std::ofstream out(depth_arguments->json);
      out << deep_check_json(check).dump(2) << "\n";
      if (!out) throw std::runtime_error("cannot write " + depth_arguments->json);
    }
    if (!check.passed()) set_command_exit_code(1);
  });
}

#endif  // PENUMBRA_WITH_FARM

}  // namespace penumbra
