// The client's farm commands: submit, watch, list, status, cancel, fetch, workers. Each talks to
// the coordinator named by --coordinator or PENUMBRA_COORDINATOR through the jobs API
// (proto/support/farm_client.h), with TLS (--tls-ca or PENUMBRA_TLS_CA, mutual with
// --tls-cert/--tls-key) and a token (--token, --token-file or PENUMBRA_TOKEN) when given;
// gRPC errors reach the user as "CODE: what to fix".
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "client/cli_options.h"
#include "client/commands.h"
#include "client/connection_options.h"
#include "client/progress.h"
#include "client/read_file.h"
#include "client/scene_checks.h"
#include "core/scene/render_settings.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"
#include "proto/support/state_names.h"

namespace penumbra {

namespace {

using farm::FarmClient;
using farm::state_name;

FarmClient connect(const ConnectionArguments& arguments) {
  return FarmClient(connection_of(arguments));
}

std::string budget_text(const v1::JobStatus& status) {
  char text[64];
  if (status.spp_budget())
    std::snprintf(text, sizeof text, "%u spp", status.spp_budget());
  else
    std::snprintf(text, sizeof text, "%.4g s", status.seconds_budget());
  return text;
}

// Follows a job until it ends: a bar redrawn in place on a terminal, plain lines (at most one a
// second, and the last) otherwise, nothing with `quiet`. Returns the final status; sets a
// failing exit code when the job did not finish.
v1::JobStatus watch_job(FarmClient& client, const std::string& job_id, bool quiet) {
  ProgressReporter progress(job_id, quiet ? ProgressMode::Quiet : ProgressMode::Auto, stdout, 1.0);
  auto show = [&](const v1::JobStatus& status) {
    JobProgress job;
    job.job_id = status.job_id();
    job.state = state_name(status.state());
    job.done = status.state() == v1::JOB_STATE_DONE;
    job.spp_budget = status.spp_budget();
    job.seconds_budget = status.seconds_budget();
    job.passes_complete = status.passes_complete();
    job.tiles_complete = status.tiles_complete();
    job.tiles_total = status.tiles_total();
    job.tasks_complete = status.tasks_complete();
    job.tasks_total = status.tasks_total();
    job.tasks_leased = status.tasks_leased();
    job.compute_seconds = status.compute_seconds();
    job.wall_seconds = status.wall_seconds();
    if (status.has_mrse()) job.mrse = status.mrse();
    ProgressState state = job_progress_state(job);
    progress.update(state.done, state.total, state.unit, state.extra, state.rate, state.rate_unit,
                    state.elapsed);
  };
  v1::JobStatus last = client.watch(job_id, show);
  show(last);
  progress.finish();
  if (last.state() != v1::JOB_STATE_DONE) {
    std::fprintf(stderr, "penumbra: %s %s%s%s\n", job_id.c_str(), state_name(last.state()).c_str(),
                 last.error().empty() ? "" : ": ", last.error().c_str());
    set_command_exit_code(1);
  }
  return last;
}

struct SubmitArguments {
  ConnectionArguments connection;
  // Method, sampler and budget left empty/zero take the scene file's own, then Penumbra's
  // defaults (core/scene/render_settings.h).
  std::string scene, method, sampler, reference, name;
  uint32_t spp = 0;
  double seconds = 0;
  int priority = 0;
  uint64_t seed = 0;
  uint32_t tile_size = 0, passes_per_task = 0;
  bool wait = false, strict = false, accept_reference_mismatch = false;
  bool quiet = false;  // no progress while waiting
};

void submit(const SubmitArguments& arguments) {
  if (arguments.spp > 0 && arguments.seconds > 0)
    throw std::runtime_error(
        "--spp and --seconds both given: a farm job has one budget, passes (--spp N) or summed "
        "compute seconds (--seconds S)");
  v1::JobSpec spec;
  *spec.mutable_scene() = farm::pack_scene_file(arguments.scene);
  // The scene as the coordinator will read it: its warnings now, before anything is sent.
  const Scene scene = farm::parse_wire_package(spec.scene());
  report_scene_warnings(scene, arguments.strict, arguments.scene);
  spec.set_strict(arguments.strict);
  spec.set_accept_reference_mismatch(arguments.accept_reference_mismatch);
  RenderSettings settings = {arguments.method, arguments.sampler, arguments.spp, arguments.seconds};
  if (settings.method.empty() || settings.sampler.empty() ||
      (settings.spp == 0 && settings.seconds == 0))
    settings = choose_render_settings(scene, settings);
  spec.set_method(settings.method);
  spec.set_sampler(settings.sampler);
  spec.set_seed(arguments.seed);
  if (settings.seconds > 0)
    spec.set_compute_seconds(settings.seconds);
  else
    spec.set_spp(settings.spp);
  spec.set_priority(arguments.priority);
  spec.set_tile_size(arguments.tile_size);
  spec.set_passes_per_task(arguments.passes_per_task);
  spec.set_name(arguments.name);
  if (!arguments.reference.empty()) {
    if (std::filesystem::is_regular_file(arguments.reference)) {
      spec.set_reference_exr(read_file(arguments.reference));
      // Checked here too, so the refusal names the file (the coordinator checks it again).
      for (const std::string& warning :
           check_reference_bytes(spec.reference_exr(), arguments.reference, scene,
                                 arguments.accept_reference_mismatch))
        std::fprintf(stderr, "penumbra: warning: %s\n", warning.c_str());
    } else if (arguments.reference.rfind("job-", 0) == 0) {
      spec.set_reference_job(arguments.reference);
    } else {
      throw std::runtime_error("--reference " + arguments.reference +
                               ": neither an EXR file nor a job id (job-N)");
    }
  }
  FarmClient client = connect(arguments.connection);
  // The scene travels in chunks (no message is larger than one, whatever the scene's size) and
  // only those the coordinator lacks: a submission of the same scene again sends none.
  const v1::ScenePackage package = spec.scene();
  spec.set_scene_hash(scene.content_hash);
  farm::SceneUploadResult upload = client.upload_scene(package, scene.content_hash);
  if (!upload.already_stored && upload.chunks_total > 0)
    std::printf("scene %s uploaded: %u of %u chunk(s) sent\n",
                scene.content_hash.substr(0, 12).c_str(), upload.chunks_sent, upload.chunks_total);
  v1::SubmitJobResponse response = client.submit(spec);
  std::printf("%s submitted (scene %s)\n", response.job_id().c_str(),
              response.scene_hash().substr(0, 12).c_str());
  std::fflush(stdout);
  if (arguments.wait) watch_job(client, response.job_id(), arguments.quiet);
}

void print_status(const v1::JobStatus& status) {
  std::printf("job        %s%s%s\n", status.job_id().c_str(), status.name().empty() ? "" : "  ",
              status.name().c_str());
  std::printf("state      %s%s%s\n", state_name(status.state()).c_str(),
              status.error().empty() ? "" : ": ", status.error().c_str());
  std::printf("scene      %s (%ux%u, %s)\n", status.scene_name().c_str(), status.width(),
              status.height(), status.scene_hash().substr(0, 12).c_str());
  std::printf("method     %s, sampler %s, seed %llu, priority %d\n", status.method().c_str(),
              status.sampler().c_str(), static_cast<unsigned long long>(status.seed()),
              status.priority());
  std::printf("budget     %s\n", budget_text(status).c_str());
  std::printf(
      "progress   %u spp complete of %u planned; tiles %u/%u; tasks %llu/%llu (%llu leased)\n",
      status.passes_complete(), status.passes_planned(), status.tiles_complete(),
      status.tiles_total(), static_cast<unsigned long long>(status.tasks_complete()),
      static_cast<unsigned long long>(status.tasks_total()),
      static_cast<unsigned long long>(status.tasks_leased()));
  for (const std::string& warning : status.warnings())
    std::printf("warning    %s\n", warning.c_str());
  std::printf("time       %.2f compute s, %.2f wall s\n", status.compute_seconds(),
              status.wall_seconds());
  if (status.state() == v1::JOB_STATE_CANCELLED)
    std::printf("result     %s\n",
                status.has_result()
                    ? ("the " + std::to_string(status.passes_complete()) +
                       " sealed passes: an unbiased image of " +
                       std::to_string(status.passes_complete()) + " spp (penumbra fetch)")
                          .c_str()
                    : "none (cancelled before any pass was sealed)");
  if (status.curve_size()) {
    std::printf("MRSE curve (passes, compute s, wall s, MRSE):\n");
    for (const auto& point : status.curve())
      std::printf("  %6u  %9.3f  %9.3f  %.6g\n", point.passes(), point.compute_seconds(),
                  point.wall_seconds(), point.mrse());
  }
  if (status.errors_size()) {
    std::printf("errors against the reference:\n");
    for (const auto& error : status.errors())
      std::printf("  %-16s MRSE %.6g  MSE %.6g  RMSE %.6g\n", error.region().c_str(), error.mrse(),
                  error.mse(), error.rmse());
  }
}

}  // namespace

void add_farm_commands(CLI::App& app) {
  auto submit_arguments = std::make_shared<SubmitArguments>();
  CLI::App* submit_command = app.add_subcommand(
      "submit", "Submit a render job to the farm (packs the scene and its OBJs)");
  submit_command->add_option("scene", submit_arguments->scene, "Scene file (penumbra/scene@1)")
      ->required()
      ->check(CLI::ExistingFile);
  submit_command->add_option("--method,-m", submit_arguments->method,
                             "Method (penumbra/method@1; default: the scene's own, else sa)");
  submit_command->add_option("--sampler,-s", submit_arguments->sampler,
                             "Sample pattern (default: the scene's own, else stratified)");
  submit_command
      ->add_option("--spp", submit_arguments->spp,
                   "Budget: samples per pixel (default: the scene's, else 16)")
      ->check(CLI::Range(1u, 1u << 20));
  submit_command
      ->add_option("--seconds", submit_arguments->seconds,
                   "Budget instead of --spp: summed compute seconds (stops at a pass boundary)")
      ->check(CLI::Range(1e-3, 1e7));
  submit_command->add_option("--reference", submit_arguments->reference,
                             "Reference of the same scene: an EXR file or a job id");
  submit_command->add_flag("--accept-reference-mismatch",
                           submit_arguments->accept_reference_mismatch,
                           "Use a reference of another scene: warn and record it");
  submit_command->add_flag("--strict", submit_arguments->strict,
                           "Refuse the scene when its reader warns (unknown keys, ignored "
                           "parameters)");
  submit_command->add_option("--priority", submit_arguments->priority, "Higher runs first");
  submit_command->add_option("--seed", submit_arguments->seed, "Random seed")
      ->check(seed_check())
      ->capture_default_str();
  submit_command->add_option("--tile-size", submit_arguments->tile_size, "Tile side (64)");
  submit_command->add_option("--passes-per-task", submit_arguments->passes_per_task,
                             "Passes in one task (8)");
  submit_command->add_option("--name", submit_arguments->name, "A label for the job");
  submit_command->add_flag("--wait", submit_arguments->wait, "Watch the job until it ends");
  submit_command->add_flag("--quiet,-q", submit_arguments->quiet,
                           "With --wait: no progress (a bar on a terminal, else lines)");
  add_connection_options(submit_command, submit_arguments->connection);
  submit_command->callback([submit_arguments] { submit(*submit_arguments); });

  struct JobArguments {
    ConnectionArguments connection;
    std::string job;
    std::string output;
    bool quiet = false;  // watch: no progress
  };
  auto job_command = [&app](const std::string& name, const std::string& description,
                            std::shared_ptr<JobArguments> arguments) {
    CLI::App* command = app.add_subcommand(name, description);
    command->add_option("job", arguments->job, "Job id (job-N)")->required();
    add_connection_options(command, arguments->connection);
    return command;
  };

  auto watch_arguments = std::make_shared<JobArguments>();
  CLI::App* watch = job_command("watch", "Follow a job's progress: spp, tiles, ETA, current MRSE",
                                watch_arguments);
  watch->add_flag("--quiet,-q", watch_arguments->quiet,
                  "No progress (a bar on a terminal, else lines); the exit code says how it ended");
  watch->callback([watch_arguments] {
    FarmClient client = connect(watch_arguments->connection);
    watch_job(client, watch_arguments->job, watch_arguments->quiet);
  });

  auto status_arguments = std::make_shared<JobArguments>();
  job_command("status", "Show a job: state, progress, MRSE curve, errors", status_arguments)
      ->callback([status_arguments] {
        FarmClient client = connect(status_arguments->connection);
        print_status(client.status(status_arguments->job));
      });

  auto cancel_arguments = std::make_shared<JobArguments>();
  job_command("cancel", "Cancel a job (its sealed passes stay fetchable)", cancel_arguments)
      ->callback([cancel_arguments] {
        FarmClient client = connect(cancel_arguments->connection);
        v1::JobState state = client.cancel(cancel_arguments->job);
        v1::JobStatus status = client.status(cancel_arguments->job);
        std::printf("%s %s", cancel_arguments->job.c_str(), state_name(state).c_str());
        if (state == v1::JOB_STATE_CANCELLED && status.has_result())
          std::printf("; %u sealed passes kept (penumbra fetch %s -o FILE.exr)",
                      status.passes_complete(), cancel_arguments->job.c_str());
        std::printf("\n");
      });

  auto fetch_arguments = std::make_shared<JobArguments>();
  CLI::App* fetch_command = job_command(
      "fetch",
      "Download a job's EXR (RGB, variance, metadata): a done job's, or a cancelled job's "
      "sealed passes",
      fetch_arguments);
  fetch_command->add_option("-o,--output", fetch_arguments->output, "Output EXR path")->required();
  fetch_command->callback([fetch_arguments] {
    FarmClient client = connect(fetch_arguments->connection);
    const v1::JobStatus status = client.status(fetch_arguments->job);
    std::string bytes = client.fetch(fetch_arguments->job);
    std::string temporary = fetch_arguments->output + ".part";
    {
      std::ofstream out(temporary, std::ios::binary);
      out.write(bytes.data(), std::streamsize(bytes.size()));
      if (!out) throw std::runtime_error("cannot write " + temporary);
    }
    std::filesystem::rename(temporary, fetch_arguments->output);
    std::printf("%s -> %s (%zu bytes, %u spp%s)\n", fetch_arguments->job.c_str(),
                fetch_arguments->output.c_str(), bytes.size(), status.passes_complete(),
                status.state() == v1::JOB_STATE_CANCELLED ? ", cancelled: its sealed passes" : "");
  });

  auto list_connection = std::make_shared<ConnectionArguments>();
  CLI::App* list_command = app.add_subcommand("list", "List the farm's jobs");
  add_connection_options(list_command, *list_connection);
  list_command->callback([list_connection] {
    FarmClient client = connect(*list_connection);
    const std::vector<v1::JobStatus> jobs = client.list();  // a connection error: no header
    std::printf("%-9s %-10s %4s %-20s %-16s %-10s %9s %10s %10s\n", "JOB", "STATE", "PRIO", "SCENE",
                "METHOD", "BUDGET", "SPP", "COMPUTE s", "MRSE");
    for (const v1::JobStatus& job : jobs) {
      char mrse[32] = "-";
      if (job.has_mrse()) std::snprintf(mrse, sizeof mrse, "%.4g", job.mrse());
      std::printf("%-9s %-10s %4d %-20s %-16s %-10s %9u %10.2f %10s\n", job.job_id().c_str(),
                  state_name(job.state()).c_str(), job.priority(), job.scene_name().c_str(),
                  job.method().c_str(), budget_text(job).c_str(), job.passes_complete(),
                  job.compute_seconds(), mrse);
    }
  });

  auto workers_connection = std::make_shared<ConnectionArguments>();
  CLI::App* workers_command = app.add_subcommand("workers", "List the farm's workers");
  add_connection_options(workers_command, *workers_connection);
  workers_command->callback([workers_connection] {
    FarmClient client = connect(*workers_connection);
    const std::vector<v1::WorkerInfo> workers = client.workers();
    std::printf("%-24s %-6s %7s %7s %10s %11s %s\n", "WORKER", "ALIVE", "THREADS", "LEASED",
                "COMPLETED", "COMPUTE s", "LAST SEEN");
    for (const v1::WorkerInfo& worker : workers)
      std::printf("%-24s %-6s %7u %7u %10llu %11.2f %.1f s ago\n", worker.worker_id().c_str(),
                  worker.alive() ? "yes" : "no", worker.threads(), worker.tasks_leased(),
                  static_cast<unsigned long long>(worker.tasks_completed()),
                  worker.compute_seconds(), worker.seconds_since_heartbeat());
  });
}

}  // namespace penumbra
