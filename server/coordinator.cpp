#include "server/coordinator.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>
#include <random>
#include <tuple>

#include "core/image/metrics.h"
#include "core/method/method.h"
#include "core/method/method_check.h"
#include "core/render/renderer.h"
#include "core/sampling/pattern.h"
#include "penumbra/version.h"

namespace penumbra::farm {

namespace {

int64_t unix_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool is_terminal(int state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

FarmError invalid(const std::string& message) {
  return FarmError(FarmErrorCode::InvalidArgument, message);
}

// The pass schedule: blocks of passes_per_task passes from pass 0, then the phases (each pass
// count a calibrated batch run was given starts one where its earlier blocks end).
uint64_t first_pass_of_block(const v1::StoredJob& stored, uint64_t block) {
  uint64_t first_block = 0, first_pass = 0, passes = stored.passes_per_task();
  for (const v1::PassPhase& phase : stored.phases()) {
    if (phase.first_block() > block) break;
    first_block = phase.first_block();
    first_pass = phase.first_pass();
    passes = phase.passes_per_task();
  }
  return first_pass + (block - first_block) * passes;
}

// The number of blocks that cover passes [0, spp).
uint32_t blocks_for_passes(const v1::StoredJob& stored, uint32_t spp) {
  uint64_t first_block = 0, first_pass = 0, passes = stored.passes_per_task();
  for (const v1::PassPhase& phase : stored.phases()) {
    if (phase.first_pass() >= spp) break;
    first_block = phase.first_block();
    first_pass = phase.first_pass();
    passes = phase.passes_per_task();
  }
  return uint32_t(first_block + (spp - first_pass + passes - 1) / passes);
}

// The regions a job measures (curve points, final errors): the scene's, then the spec's (a
// batch's regions), which replace a scene region of the same name.
std::map<std::string, Region> measured_regions(const Scene& scene, const v1::JobSpec& spec) {
  std::map<std::string, Region> regions = scene.regions;
  for (const v1::BatchRegion& region : spec.regions())
    regions[region.name()] = {region.rect().x0(), region.rect().y0(), region.rect().x1(),
                              region.rect().y1()};
  return regions;
}

}  // namespace

struct Coordinator::Job {
  JobRecord record;
  v1::StoredJob stored;
  uint64_t tile_count = 0;
  std::vector<TileRect> tiles;            // empty once the job ended
  std::shared_ptr<const Scene> scene;     // null once the job ended
  std::map<std::string, Region> regions;  // measured_regions, while the scene is known
  uint32_t total_blocks = 0;              // spp budget; seconds budget: the most it may open
  std::vector<TileAccumulator> sealed;    // per tile, blocks [0, blocks_sealed)
  struct PendingResult {
    TileAccumulator tile;
    double compute_seconds = 0;
    bool durable = false;  // written to the store (only durable results are sealed)
  };
  std::map<uint64_t, PendingResult> pending;  // completed tasks of unsealed blocks
  double sealed_compute_seconds = 0;          // of the tasks merged into `sealed`
  // The store's sums hold blocks [0, durable_blocks) (the last checkpoint) and their compute
  // seconds; it keeps the task results of the sealed blocks after them.
  uint32_t durable_blocks = 0;
  double durable_compute_seconds = 0;
  std::map<uint64_t, int> failures;
  uint64_t tasks_completed_ever = 0;  // for the average task cost (seconds budgets)
  double task_seconds_ever = 0;
  std::vector<CurvePoint> curve;
  std::optional<Image> reference;
  bool has_mrse = false;
  double mrse = 0;
  v1::RegionErrors errors;
  // A store write of sealing or finishing failed (e.g. the data disk is full): memory was left
  // as it was before, and the expiry thread tries again.
  bool store_retry = false;
  // This job's work per worker id since this coordinator started (job_workers): results
  // accepted, their compute seconds, the first lease and the completions of the last rate
  // window.
  struct WorkerTally {
    uint64_t tasks_completed = 0;
    double compute_seconds = 0;
    SteadyTime first_lease;
    std::deque<SteadyTime> recent;
  };
  std::map<std::string, WorkerTally> by_worker;

  const v1::JobSpec& spec() const { return stored.spec(); }
  bool seconds_budget() const { return spec().budget_case() == v1::JobSpec::kComputeSeconds; }
};

std::string Coordinator::job_name(uint64_t job_id) {
  return "job-" + std::to_string(job_id);
}

Coordinator::Coordinator(CoordinatorOptions options, SceneParser parser)
    : options_(std::move(options)),
      parser_(std::move(parser)),
      store_(options_.data_dir),
      transfer_(store_, parser_, options_.max_scene_bytes),
      leases_(options_.lease_time, std::random_device{}()) {
  if (options_.build_flavour.empty()) options_.build_flavour = kBuildFlavour;
  for (const JobRecord& record : store_.jobs()) resume(record);
  expiry_thread_ = std::thread([this] { expiry_loop(); });
}

Coordinator::~Coordinator() {
  {
    std::lock_guard lock(expiry_mutex_);
    stopping_ = true;
  }
  expiry_wake_.notify_all();
  expiry_thread_.join();
}

std::chrono::milliseconds Coordinator::heartbeat_period() const {
  return std::max(std::chrono::milliseconds(1),
                  std::min(options_.heartbeat_interval, options_.lease_time / 3));
}

std::chrono::milliseconds Coordinator::dead_after() const {
  const auto period = heartbeat_period();
  return period * std::max<uint32_t>(options_.missed_heartbeats, 1) + period / 2;
}

std::chrono::milliseconds Coordinator::expiry_period() const {
  return std::max(std::chrono::milliseconds(10),
                  std::min(options_.lease_time, heartbeat_period()) / 4);
}

void Coordinator::expiry_loop() {
  const auto period = expiry_period();
  std::unique_lock lock(expiry_mutex_);
  while (!expiry_wake_.wait_for(lock, period, [this] { return stopping_; })) {
    lock.unlock();
    expire_leases();
    lock.lock();
  }
}

// ---------------------------------------------------------------------------------------------
// Jobs

void Coordinator::resume(const JobRecord& record) {
  auto job = std::make_unique<Job>();
  job->record = record;
  if (!job->stored.ParseFromString(record.spec)) {
    spdlog::error("{}: stored spec is unreadable; marking it failed", job_name(record.id));
    job->record.state = v1::JOB_STATE_FAILED;
    job->record.error = "stored job specification is unreadable";
    store_.update_job(job->record);
    jobs_[record.id] = std::move(job);
    return;
  }
  Job& j = *job;
  jobs_[record.id] = std::move(job);
  const uint32_t tile_size = j.stored.tile_size();
  j.tile_count = cut_tiles(int(j.stored.width()), int(j.stored.height()), int(tile_size)).size();
  if (!j.record.final_errors.empty()) j.errors.ParseFromString(j.record.final_errors);
  j.curve = store_.curve(record.id);
  if (!j.curve.empty()) {
    j.has_mrse = true;
    j.mrse = j.curve.back().mrse;
  }
  if (is_terminal(record.state)) return;
  // The store's sums and compute seconds are the checkpointed blocks'; the task results hold
  // the rest, sealed again below.
  j.sealed_compute_seconds = record.compute_seconds;
  j.durable_blocks = record.blocks_sealed;
  j.durable_compute_seconds = record.compute_seconds;

  try {
    auto package = store_.scene(j.spec().scene_hash());
    if (!package) throw FarmError(FarmErrorCode::NotFound, "scene is missing from the store");
    v1::ScenePackage scene_package;
    scene_package.ParseFromString(*package);
    j.scene = std::make_shared<const Scene>(parser_(scene_package));
    j.regions = measured_regions(*j.scene, j.spec());
    j.tiles = cut_tiles(int(j.stored.width()), int(j.stored.height()), int(tile_size));
    j.sealed.reserve(j.tiles.size());
    auto sealed = store_.tiles(record.id);
    for (size_t t = 0; t < j.tiles.size(); ++t) {
      auto it = sealed.find(uint32_t(t));
      j.sealed.push_back(it == sealed.end() ? TileAccumulator(j.tiles[t])
                                            : TileAccumulator::deserialize(it->second));
    }
    for (TaskResultRecord& result : store_.task_results(record.id)) {
      j.pending.emplace(result.task_index,
                        Job::PendingResult{TileAccumulator::deserialize(result.tile),
                                           result.compute_seconds, true});
      j.record.compute_seconds += result.compute_seconds;
      j.record.blocks_opened = std::max<uint32_t>(j.record.blocks_opened,
                                                  uint32_t(result.task_index / j.tile_count) + 1);
    }
  } catch (const std::exception& error) {
    spdlog::error("{}: cannot resume: {}", job_name(record.id), error.what());
    end_job(j, v1::JOB_STATE_FAILED, std::string("cannot resume after restart: ") + error.what());
    return;
  }
  j.total_blocks = j.seconds_budget() ? options_.max_spp / j.stored.passes_per_task()
                                      : blocks_for_passes(j.stored, j.spec().spp());
  // An spp job opens every block at submission; a crash may have come before that was written.
  if (!j.seconds_budget()) j.record.blocks_opened = j.total_blocks;
  j.record.blocks_opened = std::max<uint32_t>(j.record.blocks_opened, 1);
  j.tasks_completed_ever = uint64_t(j.record.blocks_sealed) * j.tile_count + j.pending.size();
  j.task_seconds_ever = j.record.compute_seconds;
  scheduler_.add_job(record.id, record.priority, record.id, batch_group(j.spec().batch_id()));
  for (uint64_t task = uint64_t(j.record.blocks_sealed) * j.tile_count;
       task < uint64_t(j.record.blocks_opened) * j.tile_count; ++task)
    if (!j.pending.count(task)) scheduler_.enqueue({record.id, task});
  load_reference(j);
  spdlog::info("{}: resumed with {} of {} blocks sealed, {} tasks queued", job_name(record.id),
               j.record.blocks_sealed, j.record.blocks_opened, scheduler_.queued(record.id));
  seal_ready_blocks(j);
  if (!is_terminal(j.record.state)) maybe_open_block(j);
}

uint64_t Coordinator::batch_group(const std::string& batch_id) {
  if (batch_id.rfind("batch-", 0) != 0) return 0;
  std::string digits = batch_id.substr(6);
  if (digits.empty() || digits.size() > 18 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return 0;
  return std::stoull(digits);
}

v1::SubmitJobResponse Coordinator::submit(const v1::JobSpec& request) {
  v1::JobSpec spec = request;
  spec.clear_batch_id();  // only the batch manager sets it (submit_in_batch)
  return submit_spec(std::move(spec));
}

v1::SubmitJobResponse Coordinator::submit(const CallContext& caller, const v1::JobSpec& request) {
  v1::JobSpec spec = request;
  spec.clear_batch_id();
  // The owner is whoever called, never what the request says.
  spec.set_owner(caller.client);
  return submit_spec(std::move(spec), false, caller);
}

v1::SubmitJobResponse Coordinator::submit_in_batch(const v1::JobSpec& request,
                                                   const std::string& batch_id,
                                                   bool awaits_pass_count) {
  v1::JobSpec spec = request;
  spec.set_batch_id(batch_id);
  if (awaits_pass_count && spec.budget_case() != v1::JobSpec::kComputeSeconds)
    throw invalid("spec.budget: a job that awaits its pass count starts with compute_seconds");
  return submit_spec(std::move(spec), awaits_pass_count);
}

void Coordinator::store_scene(const std::string& scene_hash, const v1::ScenePackage& package) {
  store_.put_scene(scene_hash, package.SerializeAsString());
}

v1::SubmitJobResponse Coordinator::submit_spec(v1::JobSpec spec, bool awaits_pass_count,
                                               const CallContext& caller) {
  // Validation and scene parsing happen outside the lock: they can take a while.
  if (spec.method().empty()) throw invalid("spec.method: empty; give a method such as \"sa\"");
  // The method is parsed once here; the check against the scene below reuses it.
  MethodSpec method;
  try {
    method = parse_method(spec.method());
  } catch (const FormatError& error) {
    throw invalid(error.what());
  }
  if (spec.sampler().empty()) spec.set_sampler("stratified");
  if (!parse_pattern(spec.sampler()))
    throw invalid("spec.sampler: unknown sampler \"" + spec.sampler() + "\"");
  switch (spec.budget_case()) {
    case v1::JobSpec::kSpp:
      if (spec.spp() == 0) throw invalid("spec.spp: the budget must be at least 1 pass");
      if (spec.spp() > options_.max_spp)
        throw FarmError(FarmErrorCode::ResourceExhausted,
                        "spec.spp: " + std::to_string(spec.spp()) + " passes exceed the limit of " +
                            std::to_string(options_.max_spp));
      break;
    case v1::JobSpec::kComputeSeconds:
      if (!(spec.compute_seconds() > 0) || !std::isfinite(spec.compute_seconds()))
        throw invalid("spec.compute_seconds: the budget must be a positive number of seconds");
      if (spec.compute_seconds() > options_.max_seconds_budget)
        throw FarmError(FarmErrorCode::ResourceExhausted,
                        "spec.compute_seconds: the budget exceeds the limit of " +
                            std::to_string(options_.max_seconds_budget) + " s");
      break;
    default:
      throw invalid("spec.budget: give spp or compute_seconds");
  }
  uint32_t tile_size = spec.tile_size() ? spec.tile_size() : options_.default_tile_size;
  if (tile_size < 4 || tile_size > 1024)
    throw invalid("spec.tile_size: " + std::to_string(tile_size) + " is outside [4, 1024]");
  uint32_t passes_per_task =
      spec.passes_per_task() ? spec.passes_per_task() : options_.default_passes_per_task;
  if (passes_per_task > 4096)
    throw invalid("spec.passes_per_task: " + std::to_string(passes_per_task) +
                  " is outside [1, 4096]");

  // The scene: parse the package (never a path) or find the uploaded one by hash.
  v1::ScenePackage package;
  if (spec.has_scene()) {
    package = spec.scene();
    size_t bytes = package.scene_json().size();
    for (const auto& [path, data] : package.files()) bytes += path.size() + data.size();
    if (bytes > options_.max_scene_bytes)
      throw FarmError(FarmErrorCode::ResourceExhausted,
                      "spec.scene: " + std::to_string(bytes) +
                          " bytes exceed the coordinator's scene-size limit of " +
                          std::to_string(options_.max_scene_bytes) +
                          " bytes (penumbra-coordinator --max-scene-mib)");
  } else if (!spec.scene_hash().empty()) {
    auto stored = store_.scene(spec.scene_hash());
    if (!stored)
      throw FarmError(FarmErrorCode::NotFound,
                      "spec.scene_hash: no scene " + spec.scene_hash() + " on this coordinator");
    package.ParseFromString(*stored);
  } else {
    throw invalid("spec.scene: give a scene package or the hash of an uploaded scene");
  }
  std::shared_ptr<const Scene> scene;
  try {
    scene = std::make_shared<const Scene>(parser_(package));
  } catch (const FormatError& error) {
    throw invalid(std::string("scene: ") + error.what());
  }
  if (!spec.scene_hash().empty() && spec.scene_hash() != scene->content_hash)
    throw invalid("spec.scene_hash: " + spec.scene_hash() + " does not match the scene's hash " +
                  scene->content_hash);
  // What the scene reader ignored travels with the job (status, EXR), or refuses it.
  std::vector<std::string> warnings = scene->warnings;
  if (spec.strict() && !warnings.empty()) {
    std::string list;
    for (const std::string& warning : warnings) list += "; " + warning;
    throw invalid("scene: " + std::to_string(warnings.size()) +
                  " warning(s) refused by spec.strict" + list);
  }
  // A reference of another scene (its scene hash differs) measures the difference of the
  // scenes, not the method's error: refused unless the client accepts it, then recorded.
  auto check_reference_scene = [&](const std::string& field, const std::string& hash,
                                   const std::string& name) {
    if (hash.empty() || hash == scene->content_hash) return;
    const std::string what = field + ": the reference" + (name.empty() ? "" : " " + name) +
                             " is of another scene (scene_hash " + hash.substr(0, 12) +
                             ", this job's " + scene->content_hash.substr(0, 12) + ")";
    if (!spec.accept_reference_mismatch())
      throw invalid(what +
                    "; set accept_reference_mismatch (--accept-reference-mismatch) to "
                    "use it anyway");
    warnings.push_back(what + "; accepted (accept_reference_mismatch)");
  };
  // The method must be able to run on this scene (line-bd16 refuses GGX, the Peters
  // combinations need psa and ltc, ...): refused now, not after a worker's three failures.
  try {
    check_method_runs_on(*scene, method);
  } catch (const FormatError& error) {
    throw invalid(error.what());
  }

  for (int i = 0; i < spec.regions_size(); ++i) {
    const v1::BatchRegion& region = spec.regions(i);
    const v1::TileRect& rect = region.rect();
    const std::string field = "spec.regions[" + std::to_string(i) + "]";
    if (region.name().empty() || region.name() == "image")
      throw invalid(field + ".name: a region needs a name other than \"image\"");
    if (rect.x0() < 0 || rect.y0() < 0 || rect.x0() >= rect.x1() || rect.y0() >= rect.y1() ||
        rect.x1() > scene->camera.width || rect.y1() > scene->camera.height)
      throw invalid(field + ".rect: [" + std::to_string(rect.x0()) + ", " +
                    std::to_string(rect.y0()) + ", " + std::to_string(rect.x1()) + ", " +
                    std::to_string(rect.y1()) + ") is empty or outside the " +
                    std::to_string(scene->camera.width) + "x" +
                    std::to_string(scene->camera.height) + " image");
  }

  std::optional<Image> reference;
  if (spec.reference_case() == v1::JobSpec::kReferenceExr) {
    ImageMetadata reference_metadata;
    try {
      reference = decode_exr(spec.reference_exr(), &reference_metadata);
    } catch (const std::exception& error) {
      throw invalid(std::string("spec.reference_exr: not a readable EXR: ") + error.what());
    }
    if (reference->width != scene->camera.width || reference->height != scene->camera.height)
      throw invalid("spec.reference_exr: " + std::to_string(reference->width) + "x" +
                    std::to_string(reference->height) + " does not match the scene's " +
                    std::to_string(scene->camera.width) + "x" +
                    std::to_string(scene->camera.height));
    check_reference_scene("spec.reference_exr", reference_metadata["penumbra:scene_hash"],
                          reference_metadata["penumbra:scene"]);
  }

  auto tiles = cut_tiles(scene->camera.width, scene->camera.height, int(tile_size));
  if (spec.has_scene()) store_.put_scene(scene->content_hash, package.SerializeAsString());
  spec.clear_scene();
  spec.set_scene_hash(scene->content_hash);

  Notifications notifications;
  v1::SubmitJobResponse response;
  {
    std::lock_guard lock(mutex_);
    if (spec.reference_case() == v1::JobSpec::kReferenceJob) {
      uint64_t reference_id = parse_job_id(spec.reference_job());
      auto it = jobs_.find(reference_id);
      if (it == jobs_.end() || !caller.may_see(it->second->spec().owner()))
        throw FarmError(FarmErrorCode::NotFound,
                        "spec.reference_job: no job " + spec.reference_job());
      if (it->second->stored.width() != uint32_t(scene->camera.width) ||
          it->second->stored.height() != uint32_t(scene->camera.height))
        throw invalid("spec.reference_job: " + spec.reference_job() +
                      " has another resolution than this scene");
      check_reference_scene("spec.reference_job", it->second->spec().scene_hash(),
                            job_name(reference_id));
      spec.set_reference_job(job_name(reference_id));
    }
    auto job = std::make_unique<Job>();
    job->stored.mutable_spec()->CopyFrom(spec);
    job->stored.set_scene_name(scene->name);
    job->stored.set_width(uint32_t(scene->camera.width));
    job->stored.set_height(uint32_t(scene->camera.height));
    job->stored.set_tile_size(tile_size);
    job->stored.set_passes_per_task(passes_per_task);
    job->stored.set_awaits_pass_count(awaits_pass_count);
    for (const std::string& warning : warnings) job->stored.add_warnings(warning);
    job->tiles = std::move(tiles);
    job->tile_count = job->tiles.size();
    job->total_blocks = job->seconds_budget() ? options_.max_spp / passes_per_task
                                              : blocks_for_passes(job->stored, spec.spp());
    uint64_t new_tasks =
        job->tile_count * (job->seconds_budget() ? 1 : uint64_t(job->total_blocks));
    if (scheduler_.queued_total() + new_tasks > options_.max_queued_tasks)
      throw FarmError(FarmErrorCode::ResourceExhausted,
                      "the coordinator's queue is full: " + std::to_string(new_tasks) +
                          " more tasks would exceed " + std::to_string(options_.max_queued_tasks));
    job->scene = scene;
    job->regions = measured_regions(*scene, spec);
    job->reference = std::move(reference);
    job->record.spec = job->stored.SerializeAsString();
    job->record.priority = spec.priority();
    job->record.state = v1::JOB_STATE_QUEUED;
    job->record.submitted_unix_ms = unix_ms();
    job->record.id = store_.add_job(job->record);
    uint64_t id = job->record.id;
    Job& j = *job;
    jobs_[id] = std::move(job);
    scheduler_.add_job(id, spec.priority(), id, batch_group(spec.batch_id()));
    if (j.seconds_budget()) {
      open_block(j);
    } else {
      while (j.record.blocks_opened < j.total_blocks) open_block(j);
    }
    store_.update_job(j.record);
    j.sealed.reserve(j.tiles.size());
    for (const TileRect& tile : j.tiles) j.sealed.emplace_back(tile);
    load_reference(j);
    spdlog::info("{}: submitted: scene {} ({}x{}), method {}, sampler {}, {} tiles, priority {}",
                 job_name(id), scene->name, scene->camera.width, scene->camera.height,
                 spec.method(), spec.sampler(), j.tile_count, spec.priority());
    ++counters_.jobs_submitted;
    response.set_job_id(job_name(id));
    response.set_scene_hash(scene->content_hash);
    collect_notifications(id, notifications);
  }
  run(notifications);
  return response;
}

void Coordinator::open_block(Job& job) {
  uint64_t first = uint64_t(job.record.blocks_opened) * job.tile_count;
  for (uint64_t tile = 0; tile < job.tile_count; ++tile)
    scheduler_.enqueue({job.record.id, first + tile});
  ++job.record.blocks_opened;
}

// Seconds budgets: opens the next pass block when the job has nothing queued, is at most one
// block ahead of the sealed ones, and the compute spent plus the expected cost of the tasks in
// flight stays under the budget.
void Coordinator::maybe_open_block(Job& job) {
  if (!job.seconds_budget() || is_terminal(job.record.state)) return;
  if (scheduler_.queued(job.record.id) != 0) return;
  if (job.record.blocks_opened >= job.total_blocks) return;
  if (job.record.blocks_opened > job.record.blocks_sealed + 1) return;
  if (job.tasks_completed_ever == 0) return;  // no cost estimate yet
  uint64_t done = uint64_t(job.record.blocks_sealed) * job.tile_count + job.pending.size();
  uint64_t in_flight = uint64_t(job.record.blocks_opened) * job.tile_count - done;
  double average = job.task_seconds_ever / double(job.tasks_completed_ever);
  if (job.record.compute_seconds + double(in_flight) * average < job.spec().compute_seconds())
    open_block(job);
}

void Coordinator::load_reference(Job& job) {
  if (job.reference || job.spec().reference_case() == v1::JobSpec::REFERENCE_NOT_SET) return;
  try {
    if (job.spec().reference_case() == v1::JobSpec::kReferenceExr) {
      job.reference = decode_exr(job.spec().reference_exr());
      return;
    }
    uint64_t reference_id = parse_job_id(job.spec().reference_job());
    auto it = jobs_.find(reference_id);
    if (it == jobs_.end() || it->second->record.state != v1::JOB_STATE_DONE) return;
    if (auto exr = store_.result(reference_id)) job.reference = decode_exr(*exr);
  } catch (const std::exception& error) {
    spdlog::warn("{}: cannot load its reference: {}", job_name(job.record.id), error.what());
  }
}

void Coordinator::seal_ready_blocks(Job& job) {
  while (!is_terminal(job.record.state) && job.record.blocks_sealed < job.record.blocks_opened) {
    uint64_t first = uint64_t(job.record.blocks_sealed) * job.tile_count;
    uint64_t end = first + job.tile_count;
    auto begin_it = job.pending.lower_bound(first);
    auto end_it = job.pending.lower_bound(end);
    if (uint64_t(std::distance(begin_it, end_it)) != job.tile_count) break;
    if (!std::all_of(begin_it, end_it, [](const auto& entry) { return entry.second.durable; }))
      break;
    // Memory changes only once the store has what it must keep: on a failed write (a full disk)
    // the sealed tiles, curve and counts are put back and the block is sealed again later.
    std::vector<TileAccumulator> sealed_before = job.sealed;
    const double sealed_seconds_before = job.sealed_compute_seconds;
    const bool has_mrse_before = job.has_mrse;
    const double mrse_before = job.mrse;
    for (auto it = begin_it; it != end_it; ++it) {
      job.sealed[it->first - first].merge(it->second.tile);
      job.sealed_compute_seconds += it->second.compute_seconds;
    }
    ++job.record.blocks_sealed;
    uint32_t passes = task_passes(job, end - 1).second;
    // After a restart, a block sealed before it has its curve point in the store already.
    const bool recorded = !job.curve.empty() && job.curve.back().passes >= passes;
    std::optional<CurvePoint> point;
    load_reference(job);
    if (job.reference && !recorded) {
      Film film = assemble_film(int(job.stored.width()), int(job.stored.height()), job.sealed);
      try {
        CurvePoint p;
        p.passes = passes;
        p.compute_seconds = job.record.compute_seconds;
        p.wall_seconds = double(unix_ms() - job.record.started_unix_ms) / 1000.0;
        p.mrse = mrse(film.color, *job.reference);
        for (const auto& [region, summary] : error_summary(film.color, *job.reference, job.regions))
          if (region != "image") p.regions.emplace_back(region, summary.mrse);
        point = p;
        job.curve.push_back(p);
        job.has_mrse = true;
        job.mrse = p.mrse;
      } catch (const std::exception& error) {
        spdlog::warn("{}: no MRSE: {}", job_name(job.record.id), error.what());
      }
    }
    // A checkpoint writes the merged sums and drops the task results they hold, once `every`
    // sealed blocks have piled up, unless the job ends sooner (its end drops them all).
    const uint32_t every = std::max<uint32_t>(options_.checkpoint_blocks, 1);
    const uint32_t piled_up = job.record.blocks_sealed - job.durable_blocks;
    const bool ends_soon =
        !job.seconds_budget() && job.total_blocks - job.record.blocks_sealed < every;
    const bool checkpoint = piled_up >= every && (every == 1 || !ends_soon);
    try {
      if (checkpoint) {
        std::map<uint32_t, std::string> tiles;
        for (size_t tile = 0; tile < job.sealed.size(); ++tile)
          tiles[uint32_t(tile)] = job.sealed[tile].serialize();
        JobRecord durable = job.record;
        durable.compute_seconds = job.sealed_compute_seconds;
        store_.seal_block(durable, tiles, uint64_t(job.durable_blocks) * job.tile_count, end,
                          point);
        job.durable_blocks = job.record.blocks_sealed;
        job.durable_compute_seconds = job.sealed_compute_seconds;
      } else {
        // The curve point and the job's fields (its state, its start) without the sums.
        store_.seal_block(durable_record(job), {}, end, end, point);
      }
    } catch (const std::exception& error) {
      spdlog::error("{}: cannot store sealed passes (will retry): {}", job_name(job.record.id),
                    error.what());
      job.sealed = std::move(sealed_before);
      job.sealed_compute_seconds = sealed_seconds_before;
      --job.record.blocks_sealed;
      if (point) job.curve.pop_back();
      job.has_mrse = has_mrse_before;
      job.mrse = mrse_before;
      job.store_retry = true;
      return;
    }
    job.pending.erase(job.pending.lower_bound(first), job.pending.lower_bound(end));
    spdlog::debug("{}: {} passes sealed{}", job_name(job.record.id), passes,
                  checkpoint ? " (checkpoint)" : "");
  }
  maybe_open_block(job);
  if (waits_for_pass_count(job)) {
    spdlog::info("{}: {} passes, {:.3f} compute seconds; waits for its pass count",
                 job_name(job.record.id),
                 task_passes(job, uint64_t(job.record.blocks_sealed) * job.tile_count - 1).second,
                 job.record.compute_seconds);
    return;
  }
  if (!is_terminal(job.record.state) && job.record.blocks_sealed == job.record.blocks_opened &&
      scheduler_.queued(job.record.id) == 0 &&
      (job.seconds_budget() || job.record.blocks_sealed == job.total_blocks))
    finish(job);
}

// A job that awaits its pass count waits once every block it opened is sealed and its budget
// is rendered: no more blocks fit in its seconds budget (maybe_open_block opened none), or every
// block of the pass count it was given is sealed.
bool Coordinator::waits_for_pass_count(const Job& job) const {
  return job.stored.awaits_pass_count() && !is_terminal(job.record.state) &&
         job.record.blocks_sealed > 0 && job.record.blocks_sealed == job.record.blocks_opened &&
         scheduler_.queued(job.record.id) == 0 &&
         (job.seconds_budget() || job.record.blocks_sealed == job.total_blocks);
}

JobRecord Coordinator::durable_record(const Job& job) const {
  JobRecord durable = job.record;
  durable.blocks_sealed = job.durable_blocks;
  durable.compute_seconds = job.durable_compute_seconds;
  return durable;
}

bool Coordinator::awaits_pass_count(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  return waits_for_pass_count(job_locked(job_id));
}

void Coordinator::set_pass_count(const std::string& job_id, uint32_t spp, uint32_t passes_per_task,
                                 bool final) {
  Notifications notifications;
  {
    std::lock_guard lock(mutex_);
    Job& job = job_locked(job_id);
    if (!job.stored.awaits_pass_count()) {
      if (job.stored.phases_size() > 0) return;  // its final count was given before
      throw FarmError(FarmErrorCode::FailedPrecondition,
                      job_id + " does not await a pass count (not a calibrated batch run)");
    }
    if (is_terminal(job.record.state))
      throw FarmError(
          FarmErrorCode::FailedPrecondition,
          job_id + " has ended (" + v1::JobState_Name(v1::JobState(job.record.state)) + ")");
    if (!waits_for_pass_count(job))
      throw FarmError(FarmErrorCode::FailedPrecondition,
                      job_id + " is still rendering the passes it has");
    if (spp == 0 || spp > options_.max_spp)
      throw invalid("spp: " + std::to_string(spp) + " is outside [1, " +
                    std::to_string(options_.max_spp) + "]");
    if (passes_per_task == 0 || passes_per_task > 4096)
      throw invalid("passes_per_task: " + std::to_string(passes_per_task) +
                    " is outside [1, 4096]");
    // The job goes on from the end of its last block, in a phase of blocks of its own.
    const uint32_t rendered =
        task_passes(job, uint64_t(job.record.blocks_sealed) * job.tile_count - 1).second;
    v1::StoredJob stored = job.stored;
    stored.mutable_spec()->set_spp(std::max(spp, rendered));
    stored.set_awaits_pass_count(!final);
    v1::PassPhase* phase = stored.add_phases();
    phase->set_first_block(job.record.blocks_sealed);
    phase->set_first_pass(rendered);
    phase->set_passes_per_task(passes_per_task);
    const uint32_t total_blocks = blocks_for_passes(stored, stored.spec().spp());
    const uint64_t new_tasks = uint64_t(total_blocks - job.record.blocks_opened) * job.tile_count;
    if (scheduler_.queued_total() + new_tasks > options_.max_queued_tasks)
      throw FarmError(FarmErrorCode::ResourceExhausted,
                      "the coordinator's queue is full: " + std::to_string(new_tasks) +
                          " more tasks would exceed " + std::to_string(options_.max_queued_tasks));
    JobRecord durable = durable_record(job);
    durable.spec = stored.SerializeAsString();
    durable.blocks_opened = total_blocks;
    store_.update_job_spec(durable);
    job.stored = std::move(stored);
    job.record.spec = durable.spec;
    job.total_blocks = total_blocks;
    while (job.record.blocks_opened < job.total_blocks) open_block(job);
    spdlog::info("{}: pass count {}{} ({} rendered, the rest in blocks of {})",
                 job_name(job.record.id), job.spec().spp(), final ? "" : " for now", rendered,
                 passes_per_task);
    seal_ready_blocks(job);  // nothing more to render: finishes or waits again
    collect_notifications(job.record.id, notifications);
  }
  run(notifications);
}

void Coordinator::set_batch_listener(std::function<void()> listener) {
  std::lock_guard lock(mutex_);
  batch_listener_ = std::move(listener);
}

uint32_t Coordinator::sealed_passes(const Job& job) const {
  return job.record.blocks_sealed == 0
             ? 0
             : task_passes(job, uint64_t(job.record.blocks_sealed) * job.tile_count - 1).second;
}

std::string Coordinator::encode_result(const Job& job, const Film& film, uint32_t spp,
                                       const ImageMetadata& extra) const {
  RenderOptions render_options;
  render_options.method = job.spec().method();
  render_options.sampler = parse_pattern(job.spec().sampler()).value_or(Pattern::Stratified);
  render_options.seed = job.spec().seed();
  ImageMetadata metadata =
      render_metadata(*job.scene, render_options, spp, job.record.compute_seconds);
  metadata["penumbra:job"] = job_name(job.record.id);
  // The scene's warnings (render_metadata has them) and an accepted reference mismatch.
  std::string warnings;
  for (const std::string& warning : job.stored.warnings()) warnings += warning + "\n";
  if (!warnings.empty()) metadata["penumbra:warnings"] = warnings;
  for (const auto& [key, value] : extra) metadata[key] = value;
  return encode_exr(film.color, &film.variance, metadata);
}

void Coordinator::record_final_errors(Job& job, const Film& film) {
  load_reference(job);
  job.errors.Clear();
  if (!job.reference) return;
  try {
    for (const auto& [region, summary] : error_summary(film.color, *job.reference, job.regions)) {
      v1::RegionError* error = job.errors.add_errors();
      error->set_region(region);
      error->set_mrse(summary.mrse);
      error->set_mse(summary.mse);
      error->set_rmse(summary.rmse);
    }
    job.record.final_errors = job.errors.SerializeAsString();
  } catch (const std::exception& error) {
    job.errors.Clear();
    spdlog::warn("{}: no final errors: {}", job_name(job.record.id), error.what());
  }
}

void Coordinator::finish(Job& job) {
  const uint32_t spp = sealed_passes(job);
  Film film = assemble_film(int(job.stored.width()), int(job.stored.height()), job.sealed);
  std::string exr;
  try {
    exr = encode_result(job, film, spp, {});
  } catch (const std::exception& error) {
    end_job(job, v1::JOB_STATE_FAILED, std::string("cannot encode the EXR: ") + error.what());
    return;
  }
  record_final_errors(job, film);
  if (film.nonfinite_samples)
    spdlog::error("{}: {} samples were not finite (counted as zero)", job_name(job.record.id),
                  film.nonfinite_samples);
  // The job is DONE in memory only once the store holds its EXR (a full disk: retried later).
  JobRecord done = job.record;
  done.state = v1::JOB_STATE_DONE;
  done.finished_unix_ms = unix_ms();
  try {
    store_.finish_job(done, exr);
  } catch (const std::exception& error) {
    spdlog::error("{}: cannot store the result (will retry): {}", job_name(job.record.id),
                  error.what());
    job.store_retry = true;
    return;
  }
  job.store_retry = false;
  job.record = done;
  spdlog::info("{}: done: {} spp, {:.2f} compute seconds, {:.2f} wall seconds",
               job_name(job.record.id), spp, job.record.compute_seconds,
               double(job.record.finished_unix_ms - job.record.started_unix_ms) / 1000.0);
  end_job(job, v1::JOB_STATE_DONE, "");
}

// Releases what a job that ended no longer needs, in memory and in the store.
void Coordinator::end_job(Job& job, v1::JobState state, const std::string& error) {
  job.record.state = state;
  if (!error.empty()) job.record.error = error;
  if (!job.record.finished_unix_ms) job.record.finished_unix_ms = unix_ms();
  scheduler_.remove_job(job.record.id);
  leases_.release_job(job.record.id);
  job.sealed.clear();
  job.sealed.shrink_to_fit();
  job.pending.clear();
  job.tiles.clear();
  job.failures.clear();
  store_.drop_work(job.record);
}

uint64_t Coordinator::parse_job_id(const std::string& job_id) const {
  std::string digits = job_id.rfind("job-", 0) == 0 ? job_id.substr(4) : job_id;
  if (digits.empty() || digits.size() > 18 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw FarmError(FarmErrorCode::NotFound, "no job \"" + job_id + "\" (job ids look like job-7)");
  return std::stoull(digits);
}

Coordinator::Job& Coordinator::job_locked(const std::string& job_id, const CallContext& caller) {
  auto it = jobs_.find(parse_job_id(job_id));
  if (it == jobs_.end() || !caller.may_see(it->second->spec().owner()))
    throw FarmError(FarmErrorCode::NotFound, "no job " + job_id);
  return *it->second;
}

TileRect Coordinator::task_tile(const Job& job, uint64_t task_index) const {
  return job.tiles[task_index % job.tile_count];
}

std::pair<uint32_t, uint32_t> Coordinator::task_passes(const Job& job, uint64_t task_index) const {
  uint64_t block = task_index / job.tile_count;
  uint32_t begin = uint32_t(first_pass_of_block(job.stored, block));
  uint32_t end = uint32_t(first_pass_of_block(job.stored, block + 1));
  if (!job.seconds_budget()) end = std::min(end, job.spec().spp());
  return {begin, end};
}

v1::JobStatus Coordinator::status_locked(const Job& job, bool with_curve) const {
  v1::JobStatus status;
  const JobRecord& record = job.record;
  status.set_job_id(job_name(record.id));
  status.set_state(v1::JobState(record.state));
  status.set_error(record.error);
  status.set_name(job.spec().name());
  status.set_owner(job.spec().owner());
  status.set_priority(record.priority);
  status.set_scene_name(job.stored.scene_name());
  status.set_scene_hash(job.spec().scene_hash());
  status.set_method(job.spec().method());
  status.set_sampler(job.spec().sampler());
  status.set_seed(job.spec().seed());
  status.set_width(job.stored.width());
  status.set_height(job.stored.height());
  status.set_spp_budget(job.seconds_budget() ? 0 : job.spec().spp());
  status.set_seconds_budget(job.seconds_budget() ? job.spec().compute_seconds() : 0);
  auto passes_of_blocks = [&](uint32_t blocks) {
    uint32_t passes = uint32_t(first_pass_of_block(job.stored, blocks));
    return job.seconds_budget() ? passes : std::min(passes, job.spec().spp());
  };
  status.set_passes_complete(passes_of_blocks(record.blocks_sealed));
  status.set_passes_planned(passes_of_blocks(record.blocks_opened));
  status.set_tiles_total(uint32_t(job.tile_count));
  uint64_t open_blocks = record.blocks_opened - record.blocks_sealed;
  uint32_t tiles_complete = 0;
  if (open_blocks == 0) {
    tiles_complete = uint32_t(job.tile_count);
  } else if (!is_terminal(record.state)) {
    std::vector<uint32_t> done_per_tile(job.tile_count, 0);
    for (const auto& [task, tile] : job.pending) ++done_per_tile[task % job.tile_count];
    for (uint32_t done : done_per_tile) tiles_complete += done == open_blocks;
  }
  uint64_t tasks_complete = uint64_t(record.blocks_sealed) * job.tile_count + job.pending.size();
  if (record.state == v1::JOB_STATE_CANCELLED) {
    tiles_complete = std::max(tiles_complete, job.stored.tiles_complete_at_cancel());
    tasks_complete = std::max(tasks_complete, job.stored.tasks_complete_at_cancel());
  }
  status.set_tiles_complete(tiles_complete);
  status.set_tasks_total(uint64_t(record.blocks_opened) * job.tile_count);
  status.set_tasks_complete(tasks_complete);
  status.set_tasks_leased(leases_.count_for_job(record.id));
  status.set_has_result(has_result(job));
  *status.mutable_warnings() = job.stored.warnings();
  status.set_compute_seconds(record.compute_seconds);
  if (record.started_unix_ms) {
    int64_t end =
        is_terminal(record.state) && record.finished_unix_ms ? record.finished_unix_ms : unix_ms();
    status.set_wall_seconds(double(end - record.started_unix_ms) / 1000.0);
  }
  status.set_has_mrse(job.has_mrse);
  status.set_mrse(job.mrse);
  if (with_curve) {
    for (const CurvePoint& point : job.curve) {
      v1::ErrorSample* sample = status.add_curve();
      sample->set_passes(point.passes);
      sample->set_compute_seconds(point.compute_seconds);
      sample->set_wall_seconds(point.wall_seconds);
      sample->set_mrse(point.mrse);
      for (const auto& [region, value] : point.regions) {
        v1::RegionError* error = sample->add_regions();
        error->set_region(region);
        error->set_mrse(value);
      }
    }
  }
  *status.mutable_errors() = job.errors.errors();
  status.set_submitted_unix_ms(record.submitted_unix_ms);
  status.set_has_reference(job.spec().reference_case() != v1::JobSpec::REFERENCE_NOT_SET);
  return status;
}

v1::JobStatus Coordinator::status(const std::string& job_id, bool with_curve) {
  return status(CallContext::internal(), job_id, with_curve);
}

v1::JobStatus Coordinator::status(const CallContext& caller, const std::string& job_id,
                                  bool with_curve) {
  std::lock_guard lock(mutex_);
  return status_locked(job_locked(job_id, caller), with_curve);
}

std::vector<v1::JobStatus> Coordinator::list() {
  return list(CallContext::internal());
}

std::vector<v1::JobStatus> Coordinator::list(const CallContext& caller) {
  std::lock_guard lock(mutex_);
  std::vector<v1::JobStatus> result;
  for (const auto& [id, job] : jobs_)
    if (caller.may_see(job->spec().owner())) result.push_back(status_locked(*job, false));
  return result;
}

std::vector<std::string> Coordinator::unfinished_jobs_in_batch(const std::string& batch_id) {
  std::lock_guard lock(mutex_);
  std::vector<std::string> result;
  for (const auto& [id, job] : jobs_)
    if (job->spec().batch_id() == batch_id && !is_terminal(job->record.state))
      result.push_back(job_name(job->record.id));
  return result;
}

v1::JobState Coordinator::cancel(const std::string& job_id) {
  return cancel(CallContext::internal(), job_id);
}

v1::JobState Coordinator::cancel(const CallContext& caller, const std::string& job_id) {
  Notifications notifications;
  v1::JobState state;
  {
    std::lock_guard lock(mutex_);
    Job& job = job_locked(job_id, caller);
    if (!is_terminal(job.record.state)) cancel_locked(job);
    state = v1::JobState(job.record.state);
    collect_notifications(job.record.id, notifications);
  }
  run(notifications);
  return state;
}

// Cancelling keeps what is sealed: the blocks every tile has completed are an image of that many
// passes, as unbiased as a job of that spp budget (every pixel has the same passes), stored as the
// job's result with its spp in the metadata. The results of unsealed blocks are dropped (only
// some tiles have them), but the task and tile counts stay as they were.
void Coordinator::cancel_locked(Job& job) {
  const v1::JobStatus before = status_locked(job, false);
  v1::StoredJob stored = job.stored;
  stored.set_tasks_complete_at_cancel(before.tasks_complete());
  stored.set_tiles_complete_at_cancel(before.tiles_complete());
  const uint32_t spp = sealed_passes(job);
  std::optional<std::string> exr;
  if (spp > 0 && job.scene) {
    try {
      Film film = assemble_film(int(job.stored.width()), int(job.stored.height()), job.sealed);
      exr = encode_result(job, film, spp,
                          {{"penumbra:cancelled", "after " + std::to_string(spp) + " of " +
                                                      std::to_string(before.passes_planned()) +
                                                      " planned passes"}});
      record_final_errors(job, film);
      stored.set_has_partial_result(true);
    } catch (const std::exception& error) {
      spdlog::error("{}: cannot encode its sealed passes: {}", job_name(job.record.id),
                    error.what());
      exr.reset();
    }
  }
  JobRecord record = job.record;
  record.spec = stored.SerializeAsString();
  record.state = v1::JOB_STATE_CANCELLED;
  record.error.clear();
  record.finished_unix_ms = unix_ms();
  try {
    store_.cancel_job(record, exr);
  } catch (const std::exception& error) {
    // The cancellation itself must happen: without the image when the store cannot take it.
    spdlog::error("{}: cannot store its sealed passes: {}", job_name(job.record.id), error.what());
    stored.set_has_partial_result(false);
    record.spec = stored.SerializeAsString();
    record.error = std::string("the sealed passes could not be stored: ") + error.what();
  }
  job.stored = std::move(stored);
  job.record = record;
  end_job(job, v1::JOB_STATE_CANCELLED, record.error);
  spdlog::info("{}: cancelled; {} sealed passes kept", job_name(job.record.id),
               job.stored.has_partial_result() ? spp : 0);
}

bool Coordinator::has_result(const Job& job) {
  return job.record.state == v1::JOB_STATE_DONE ||
         (job.record.state == v1::JOB_STATE_CANCELLED && job.stored.has_partial_result());
}

std::string Coordinator::result_exr(const std::string& job_id) {
  return result_exr(CallContext::internal(), job_id);
}

std::string Coordinator::result_exr(const CallContext& caller, const std::string& job_id) {
  uint64_t id;
  {
    std::lock_guard lock(mutex_);
    Job& job = job_locked(job_id, caller);
    if (!has_result(job))
      throw FarmError(FarmErrorCode::FailedPrecondition,
                      job_id + " has no result: it is " +
                          v1::JobState_Name(v1::JobState(job.record.state)) +
                          (job.record.state == v1::JOB_STATE_CANCELLED
                               ? " (cancelled before any pass was sealed)"
                               : "") +
                          (job.record.error.empty() ? "" : " (" + job.record.error + ")"));
    id = job.record.id;
  }
  auto exr = store_.result(id);
  if (!exr) throw FarmError(FarmErrorCode::Internal, job_id + ": the stored result is missing");
  return *exr;
}

Film Coordinator::result_film(const std::string& job_id) {
  Film film;
  film.color = decode_exr(result_exr(job_id), nullptr, &film.variance);
  return film;
}

uint64_t Coordinator::subscribe(const std::string& job_id, std::function<void()> on_change) {
  return subscribe(CallContext::internal(), job_id, std::move(on_change));
}

uint64_t Coordinator::subscribe(const CallContext& caller, const std::string& job_id,
                                std::function<void()> on_change) {
  std::lock_guard lock(mutex_);
  uint64_t id = job_locked(job_id, caller).record.id;
  uint64_t subscription = next_subscription_++;
  subscriptions_[subscription] = {id, std::move(on_change)};
  return subscription;
}

void Coordinator::unsubscribe(uint64_t subscription) {
  std::lock_guard lock(mutex_);
  subscriptions_.erase(subscription);
}

void Coordinator::collect_notifications(uint64_t job_id, Notifications& out) const {
  for (const auto& [id, subscription] : subscriptions_)
    if (subscription.first == job_id) out.push_back(subscription.second);
  if (!batch_listener_) return;
  auto it = jobs_.find(job_id);
  if (it == jobs_.end() || it->second->spec().batch_id().empty()) return;
  if (is_terminal(it->second->record.state) || waits_for_pass_count(*it->second))
    out.push_back(batch_listener_);
}

void Coordinator::run(const Notifications& notifications) {
  for (const auto& notify : notifications) notify();
}

// ---------------------------------------------------------------------------------------------
// Workers

v1::RegisterResponse Coordinator::register_worker(const v1::RegisterRequest& request) {
  if (request.protocol_version() != v1::PROTOCOL_VERSION_CURRENT)
    throw FarmError(
        FarmErrorCode::FailedPrecondition,
        "worker speaks protocol version " + std::to_string(int(request.protocol_version())) +
            "; this coordinator speaks " + std::to_string(int(v1::PROTOCOL_VERSION_CURRENT)));
  if (request.build_flavour() != options_.build_flavour)
    throw FarmError(FarmErrorCode::FailedPrecondition,
                    "worker build \"" + request.build_flavour() +
                        "\" would render different bits than this coordinator's build \"" +
                        options_.build_flavour +
                        "\"; rebuild the worker from the same source "
                        "with the same compiler and flags");
  if (request.threads() == 0) throw invalid("threads: a worker needs at least one thread");
  // The worker's id is its name, so a worker keeps its id across restarts. A name held by a
  // live worker is refused (two processes under one id would share leases); a dead one's is
  // taken over. Without a name: w1, w2, ...
  std::lock_guard lock(mutex_);
  std::string id = request.name();
  if (id.empty()) {
    do id = fmt::format("w{}", next_worker_++);
    while (workers_.count(id));
  } else if (auto held = workers_.find(id); held != workers_.end() && !held->second.dead) {
    const double since =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - held->second.last_contact)
            .count();
    if (since <= std::chrono::duration<double>(dead_after()).count())
      throw FarmError(FarmErrorCode::AlreadyExists,
                      fmt::format("a live worker is registered as \"{}\" (heard from {:.1f} s "
                                  "ago): give each worker its own --name (a restarted worker "
                                  "gets its name back once the old one has missed its "
                                  "heartbeats)",
                                  id, since));
  }
  if (auto previous = workers_.find(id); previous != workers_.end()) {
    // A restart: whatever the previous process held is lost with it.
    for (const Lease& lease : leases_.release_worker(id)) {
      scheduler_.requeue(lease.task);
      ++counters_.leases_expired;
    }
    workers_.erase(previous);
  }
  Worker& worker = workers_[id];
  worker.name = request.name().empty() ? id : request.name();
  worker.threads = request.threads();
  worker.version = request.version();
  worker.build_flavour = request.build_flavour();
  worker.last_contact = std::chrono::steady_clock::now();
  spdlog::info("worker {} registered: {} threads, version {}", id, worker.threads, worker.version);
  v1::RegisterResponse response;
  response.set_worker_id(id);
  double lease_seconds = std::chrono::duration<double>(options_.lease_time).count();
  response.set_lease_seconds(lease_seconds);
  response.set_heartbeat_seconds(std::chrono::duration<double>(heartbeat_period()).count());
  return response;
}

Coordinator::Worker& Coordinator::worker_locked(const std::string& worker_id) {
  auto it = workers_.find(worker_id);
  if (it == workers_.end())
    throw FarmError(FarmErrorCode::NotFound,
                    "no worker " + worker_id + " (register again: the coordinator restarted?)");
  it->second.last_contact = std::chrono::steady_clock::now();
  if (it->second.dead) {
    // Back after it was declared dead: its old leases are gone (its heartbeat hears that they
    // are revoked); it leases anew.
    it->second.dead = false;
    spdlog::info("worker {} is back", worker_id);
  }
  return it->second;
}

v1::HeartbeatResponse Coordinator::heartbeat(const v1::HeartbeatRequest& request) {
  std::lock_guard lock(mutex_);
  worker_locked(request.worker_id());
  auto now = std::chrono::steady_clock::now();
  v1::HeartbeatResponse response;
  for (const std::string& token : request.attempt_tokens())
    if (!leases_.extend(token, request.worker_id(), now)) response.add_revoked_tokens(token);
  return response;
}

v1::LeaseTasksResponse Coordinator::lease_tasks(const v1::LeaseTasksRequest& request) {
  Notifications notifications;
  v1::LeaseTasksResponse response;
  {
    std::lock_guard lock(mutex_);
    worker_locked(request.worker_id());
    auto now = std::chrono::steady_clock::now();
    uint32_t wanted = std::min(request.max_tasks(), options_.max_tasks_per_lease);
    while (uint32_t(response.tasks_size()) < wanted) {
      auto next = scheduler_.next();
      if (!next) break;
      Job& job = *jobs_.at(next->job_id);
      if (job.record.state == v1::JOB_STATE_QUEUED) {
        job.record.state = v1::JOB_STATE_RUNNING;
        job.record.started_unix_ms = unix_ms();
        collect_notifications(job.record.id, notifications);
      }
      v1::Task* task = response.add_tasks();
      task->set_job_id(job_name(job.record.id));
      task->set_task_index(next->task_index);
      task->set_attempt_token(leases_.grant(*next, request.worker_id(), now));
      ++counters_.tasks_leased;
      if (auto [tally, added] = job.by_worker.try_emplace(request.worker_id()); added)
        tally->second.first_lease = now;
      task->set_scene_hash(job.spec().scene_hash());
      task->set_method(job.spec().method());
      task->set_sampler(job.spec().sampler());
      task->set_seed(job.spec().seed());
      TileRect tile = task_tile(job, next->task_index);
      task->mutable_tile()->set_x0(tile.x0);
      task->mutable_tile()->set_y0(tile.y0);
      task->mutable_tile()->set_x1(tile.x1);
      task->mutable_tile()->set_y1(tile.y1);
      auto [pass_begin, pass_end] = task_passes(job, next->task_index);
      task->set_pass_begin(pass_begin);
      task->set_pass_end(pass_end);
      maybe_open_block(job);
    }
  }
  run(notifications);
  return response;
}

v1::ScenePackage Coordinator::scene(const std::string& scene_hash) {
  auto stored = store_.scene(scene_hash);
  if (!stored) throw FarmError(FarmErrorCode::NotFound, "no scene " + scene_hash);
  v1::ScenePackage package;
  if (!package.ParseFromString(*stored))
    throw FarmError(FarmErrorCode::Internal, "stored scene " + scene_hash + " is unreadable");
  return package;
}

bool Coordinator::complete_task(const v1::CompleteTaskRequest& request) {
  // Check the tile's shape before taking the lock; it is most of the work.
  TileAccumulator tile;
  try {
    tile = TileAccumulator::deserialize(request.tile());
  } catch (const std::invalid_argument& error) {
    throw invalid(std::string("tile: ") + error.what());
  }
  if (!std::isfinite(request.compute_seconds()) || request.compute_seconds() < 0)
    throw invalid("compute_seconds: must be finite and not negative");
  uint64_t job_id = 0;
  try {
    job_id = parse_job_id(request.job_id());
  } catch (const FarmError&) {
    return false;
  }
  const uint64_t task_index = request.task_index();
  {
    std::lock_guard lock(mutex_);
    const Lease* lease = leases_.find(request.attempt_token());
    if (!lease || lease->task.job_id != job_id || lease->task.task_index != task_index) {
      spdlog::debug("{} task {}: late or duplicate result from {} dropped", request.job_id(),
                    task_index, request.worker_id());
      ++counters_.late_results;
      return false;
    }
    Job& job = *jobs_.at(job_id);
    TileRect rect = task_tile(job, task_index);
    auto [pass_begin, pass_end] = task_passes(job, task_index);
    if (!(tile.rect() == rect))
      throw invalid("tile: the result's rectangle does not match task " +
                    std::to_string(task_index));
    for (int64_t i = 0; i < rect.pixel_count(); ++i)
      if (tile.count(i) != pass_end - pass_begin)
        throw invalid("tile: pixel " + std::to_string(i) + " has " + std::to_string(tile.count(i)) +
                      " samples, the task asked for " + std::to_string(pass_end - pass_begin));
    leases_.release(request.attempt_token());
    ++counters_.tasks_completed;
    auto worker = workers_.find(request.worker_id());
    if (worker != workers_.end()) {
      ++worker->second.tasks_completed;
      worker->second.compute_seconds += request.compute_seconds();
      worker->second.last_contact = std::chrono::steady_clock::now();
      // Delivering a result is contact for as long as the durable write takes.
      ++worker->second.calls_in_flight;
    }
    {
      Job::WorkerTally& tally = job.by_worker[request.worker_id()];
      ++tally.tasks_completed;
      tally.compute_seconds += request.compute_seconds();
      const SteadyTime now = std::chrono::steady_clock::now();
      tally.recent.push_back(now);
      while (now - tally.recent.front() > std::chrono::seconds(kJobWorkerRateWindowSeconds))
        tally.recent.pop_front();
    }
    job.record.compute_seconds += request.compute_seconds();
    ++job.tasks_completed_ever;
    job.task_seconds_ever += request.compute_seconds();
    if (!job.record.started_unix_ms) job.record.started_unix_ms = unix_ms();
    job.pending.emplace(task_index,
                        Job::PendingResult{std::move(tile), request.compute_seconds(), false});
  }
  // The durable write happens outside the lock, so that concurrent completions share one
  // transaction (Store::add_task_result commits them as a group).
  auto call_done = [&] {  // under mutex_
    auto worker = workers_.find(request.worker_id());
    if (worker == workers_.end() || worker->second.calls_in_flight == 0) return;
    --worker->second.calls_in_flight;
    worker->second.last_contact = std::chrono::steady_clock::now();
  };
  try {
    store_.add_task_result(job_id, {task_index, request.tile(), request.compute_seconds()});
  } catch (const std::exception& error) {
    {
      std::lock_guard lock(mutex_);
      call_done();
      Job& job = *jobs_.at(job_id);
      if (!is_terminal(job.record.state) && job.pending.erase(task_index)) {
        job.record.compute_seconds -= request.compute_seconds();
        scheduler_.requeue({job_id, task_index});
      }
    }
    // A full disk stays RESOURCE_EXHAUSTED for the worker (it retries later); the rest is
    // INTERNAL.
    auto* farm_error = dynamic_cast<const FarmError*>(&error);
    throw FarmError(farm_error ? farm_error->code() : FarmErrorCode::Internal,
                    std::string("cannot store the result: ") + error.what());
  }
  Notifications notifications;
  {
    std::lock_guard lock(mutex_);
    call_done();
    Job& job = *jobs_.at(job_id);
    auto it = job.pending.find(task_index);
    if (!is_terminal(job.record.state) && it != job.pending.end()) {
      it->second.durable = true;
      seal_ready_blocks(job);
    }
    collect_notifications(job_id, notifications);
  }
  run(notifications);
  return true;
}

void Coordinator::fail_task(const v1::FailTaskRequest& request) {
  Notifications notifications;
  {
    std::lock_guard lock(mutex_);
    auto lease = leases_.release(request.attempt_token());
    if (!lease) return;  // stale: the task was already handed to someone else
    ++counters_.tasks_failed;
    Job& job = *jobs_.at(lease->task.job_id);
    int failures = ++job.failures[lease->task.task_index];
    spdlog::warn("{} task {}: failed on {} ({} of {}): {}", job_name(job.record.id),
                 lease->task.task_index, request.worker_id(), failures, options_.max_task_failures,
                 request.error());
    if (failures >= options_.max_task_failures) {
      end_job(job, v1::JOB_STATE_FAILED,
              "task " + std::to_string(lease->task.task_index) + " failed " +
                  std::to_string(failures) + " times; last error from worker " +
                  request.worker_id() + ": " + request.error());
    } else {
      scheduler_.requeue(lease->task);
    }
    collect_notifications(job.record.id, notifications);
  }
  run(notifications);
}

void Coordinator::expire_leases() {
  Notifications notifications;
  {
    std::lock_guard lock(mutex_);
    auto expired = leases_.expire(std::chrono::steady_clock::now());
    std::sort(expired.begin(), expired.end(), [](const Lease& a, const Lease& b) {
      return std::tuple(a.task.job_id, a.task.task_index) >
             std::tuple(b.task.job_id, b.task.task_index);
    });
    for (const Lease& lease : expired) {
      spdlog::warn("{} task {}: lease of worker {} expired; task queued again",
                   job_name(lease.task.job_id), lease.task.task_index, lease.worker_id);
      scheduler_.requeue(lease.task);
      ++counters_.leases_expired;
    }
    // Dead workers: their tasks go to the others now, not when the leases would expire. A pass
    // more than two periods after the previous one follows a time the coordinator itself heard
    // nobody (the process stopped or starved, the lock held through a slow disk write): the
    // workers' calls that waited meanwhile have not landed yet, so nobody is declared dead in
    // it; the next pass, a period later, decides.
    const auto now = std::chrono::steady_clock::now();
    const bool deaf_before = last_expiry_pass_ && now - *last_expiry_pass_ > 2 * expiry_period();
    last_expiry_pass_ = now;
    for (auto it = workers_.begin(); it != workers_.end();) {
      Worker& worker = it->second;
      const auto silence = now - worker.last_contact;
      if (!deaf_before && !worker.dead && worker.calls_in_flight == 0 && silence > dead_after()) {
        worker.dead = true;
        ++counters_.workers_lost;
        std::vector<Lease> lost = leases_.release_worker(it->first);
        std::sort(lost.begin(), lost.end(), [](const Lease& a, const Lease& b) {
          return std::tuple(a.task.job_id, a.task.task_index) >
                 std::tuple(b.task.job_id, b.task.task_index);
        });
        for (const Lease& lease : lost) {
          scheduler_.requeue(lease.task);
          ++counters_.leases_expired;
          collect_notifications(lease.task.job_id, notifications);
        }
        spdlog::warn(
            "worker {} silent for {:.2f} s ({} heartbeats missed): dead; {} task(s) "
            "queued again",
            it->first, std::chrono::duration<double>(silence).count(), options_.missed_heartbeats,
            lost.size());
      }
      if (worker.dead && options_.forget_worker_after.count() > 0 &&
          silence > options_.forget_worker_after) {
        spdlog::info("worker {} forgotten (dead for {:.0f} s)", it->first,
                     std::chrono::duration<double>(silence).count());
        it = workers_.erase(it);
        continue;
      }
      ++it;
    }
    // Seal or finish again what a failed store write left (space may have returned).
    for (auto& [id, job] : jobs_) {
      if (!job->store_retry || is_terminal(job->record.state)) continue;
      job->store_retry = false;
      seal_ready_blocks(*job);
      collect_notifications(id, notifications);
    }
  }
  run(notifications);
}

Film Coordinator::preview_film(const std::string& job_id, uint32_t* passes) {
  uint64_t id = 0;
  {
    std::lock_guard lock(mutex_);
    const Job& job = job_locked(job_id);
    if (passes) *passes = sealed_passes(job);
    // An ended job's sums are gone from memory: its image is the stored result (a done job's,
    // a cancelled job's sealed passes). A failed job has none: black.
    if (!has_result(job))
      return assemble_film(int(job.stored.width()), int(job.stored.height()), job.sealed);
    if (!is_terminal(job.record.state))
      return assemble_film(int(job.stored.width()), int(job.stored.height()), job.sealed);
    id = job.record.id;
  }
  auto exr = store_.result(id);
  if (!exr) throw FarmError(FarmErrorCode::Internal, job_id + ": the stored result is missing");
  Film film;
  film.color = decode_exr(*exr, nullptr, &film.variance);
  return film;
}

CoordinatorCounters Coordinator::counters() const {
  std::lock_guard lock(mutex_);
  CoordinatorCounters result = counters_;
  result.queued_tasks = scheduler_.queued_total();
  result.leased_tasks = leases_.size();
  return result;
}

std::vector<v1::WorkerInfo> Coordinator::workers() {
  std::lock_guard lock(mutex_);
  auto now = std::chrono::steady_clock::now();
  std::vector<v1::WorkerInfo> result;
  for (const auto& [id, worker] : workers_) {
    v1::WorkerInfo info;
    info.set_worker_id(id);
    info.set_name(worker.name);
    info.set_threads(worker.threads);
    info.set_version(worker.version);
    info.set_build_flavour(worker.build_flavour);
    double since = std::chrono::duration<double>(now - worker.last_contact).count();
    info.set_seconds_since_heartbeat(since);
    info.set_alive(!worker.dead && since <= std::chrono::duration<double>(dead_after()).count());
    info.set_tasks_leased(uint32_t(leases_.count_for_worker(id)));
    info.set_tasks_completed(worker.tasks_completed);
    info.set_compute_seconds(worker.compute_seconds);
    result.push_back(info);
  }
  return result;
}

std::vector<JobWorkerActivity> Coordinator::job_workers(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  const Job& job = job_locked(job_id);
  const auto now = std::chrono::steady_clock::now();
  const auto window = std::chrono::seconds(kJobWorkerRateWindowSeconds);
  std::map<std::string, size_t> leased = leases_.counts_for_job(job.record.id);
  std::vector<JobWorkerActivity> result;
  for (const auto& [id, tally] : job.by_worker) {
    JobWorkerActivity activity;
    activity.worker_id = id;
    if (auto worker = workers_.find(id); worker != workers_.end()) {
      activity.registered = true;
      activity.name = worker->second.name;
      activity.threads = worker->second.threads;
      activity.alive = !worker->second.dead && now - worker->second.last_contact <= dead_after();
    }
    if (auto count = leased.find(id); count != leased.end())
      activity.tasks_leased = uint32_t(count->second);
    activity.tasks_completed = tally.tasks_completed;
    activity.compute_seconds = tally.compute_seconds;
    const auto recent = std::count_if(tally.recent.begin(), tally.recent.end(),
                                      [&](SteadyTime at) { return now - at <= window; });
    const double seconds =
        std::clamp(std::chrono::duration<double>(now - tally.first_lease).count(), 1.0,
                   double(window.count()));
    activity.recent_tasks_per_second = double(recent) / seconds;
    result.push_back(std::move(activity));
  }
  return result;
}

std::optional<std::string> Coordinator::reference_exr(const std::string& job_id) {
  uint64_t reference_id = 0;
  {
    std::lock_guard lock(mutex_);
    const Job& job = job_locked(job_id);
    if (job.spec().reference_case() == v1::JobSpec::kReferenceExr)
      return job.spec().reference_exr();
    if (job.spec().reference_case() != v1::JobSpec::kReferenceJob) return std::nullopt;
    reference_id = parse_job_id(job.spec().reference_job());
    auto it = jobs_.find(reference_id);
    if (it == jobs_.end() || it->second->record.state != v1::JOB_STATE_DONE) return std::nullopt;
  }
  return store_.result(reference_id);
}

std::map<std::string, Region> Coordinator::regions(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  const Job& job = job_locked(job_id);
  return job.regions;
}

}  // namespace penumbra::farm
