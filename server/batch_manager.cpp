#include "server/batch_manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/batch/reference_sizing.h"
#include "core/image/image.h"
#include "core/image/noise_corrected_mrse.h"
#include "core/method/method.h"
#include "core/method/method_check.h"
#include "core/scene/json_node.h"

namespace penumbra::farm {

namespace {

int64_t unix_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool job_terminal(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

FarmError invalid(const std::string& message) {
  return FarmError(FarmErrorCode::InvalidArgument, message);
}

std::string reference_kind_name(BatchReferenceKind kind) {
  switch (kind) {
    case BatchReferenceKind::Auto:
      return "auto";
    case BatchReferenceKind::Exr:
      return "exr";
    case BatchReferenceKind::Job:
      return "job";
    case BatchReferenceKind::Exact:
      return "exact";
  }
  return "auto";
}

// The pass count that fills `budget` compute seconds at `seconds_per_pass`.
uint32_t passes_for_budget(double budget, double seconds_per_pass, uint32_t max_spp) {
  double passes = budget / std::max(seconds_per_pass, 1e-9);
  if (!std::isfinite(passes)) return max_spp;
  return uint32_t(std::clamp<double>(std::llround(passes), 1.0, double(max_spp)));
}

}  // namespace

void BatchManager::Wakeup::notify() {
  {
    std::lock_guard lock(mutex);
    pending = true;
  }
  condition.notify_all();
}

bool BatchManager::is_terminal(v1::BatchState state) {
  return state == v1::BATCH_STATE_DONE || state == v1::BATCH_STATE_FAILED ||
         state == v1::BATCH_STATE_CANCELLED;
}

BatchManager::BatchManager(Coordinator& coordinator, SceneParser parser,
                           BatchManagerOptions options)
    : coordinator_(coordinator),
      parser_(std::move(parser)),
      options_(std::move(options)),
      store_(options_.data_dir) {
  reference_cache_ = store_.reference_cache();
  for (v1::StoredBatch& stored : store_.load_all()) {
    uint64_t number = parse_batch_number(stored.status().batch_id());
    auto batch = std::make_unique<Batch>();
    try {
      batch->spec =
          parse_batch_spec(stored.status().spec_json(), stored.source_name(), options_.limits);
    } catch (const std::exception& error) {
      stored.mutable_status()->set_state(v1::BATCH_STATE_FAILED);
      stored.mutable_status()->set_error(std::string("stored spec is unreadable: ") + error.what());
    }
    batch->stored = std::move(stored);
    next_number_ = std::max(next_number_, number + 1);
    if (!is_terminal(batch->stored.status().state()))
      spdlog::info("{}: resumed ({})", batch->stored.status().batch_id(),
                   v1::BatchState_Name(batch->stored.status().state()));
    cancel_unknown_jobs(*batch);
    batches_[number] = std::move(batch);
  }
  coordinator_.set_batch_listener([wakeup = wakeup_] { wakeup->notify(); });
  driver_ = std::thread([this] { drive_loop(); });
}

BatchManager::~BatchManager() {
  coordinator_.set_batch_listener({});
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    ++version_;
  }
  wakeup_->notify();
  changed_.notify_all();
  if (driver_.joinable()) driver_.join();
}

v1::SubmitBatchResponse BatchManager::submit(const v1::SubmitBatchRequest& request,
                                             const CallContext& caller) {
  const std::string& owner = caller.client;
  std::string source = request.source_name().empty() ? "batch spec" : request.source_name();
  BatchSpec spec = parse_batch_spec(request.spec_json(), source, options_.limits);
  // The scene: a package in the request, or one uploaded in chunks and named by its hash.
  v1::ScenePackage uploaded;
  if (!request.has_scene()) {
    if (request.scene_hash().empty())
      throw invalid(
          "scene: the request carries no scene package and no scene_hash (the client packs "
          "or uploads the spec's scene \"" +
          spec.scene + "\")");
    uploaded = coordinator_.scene(request.scene_hash());
  }
  const v1::ScenePackage& package = request.has_scene() ? request.scene() : uploaded;
  Scene scene;
  try {
    scene = parser_(package);
  } catch (const FormatError& error) {
    throw invalid(std::string("scene: ") + error.what());
  }
  if (!request.has_scene() && scene.content_hash != request.scene_hash())
    throw invalid("scene_hash: the stored scene " + request.scene_hash().substr(0, 12) +
                  " parses to another content hash " + scene.content_hash.substr(0, 12));
  if (spec.strict && !scene.warnings.empty()) {
    std::string list;
    for (const std::string& warning : scene.warnings) list += "; " + warning;
    throw invalid("$.strict: the scene has " + std::to_string(scene.warnings.size()) +
                  " warning(s) (in " + source + ")" + list);
  }

  // Regions: the scene's, then the spec's (which must lie inside the image).
  std::map<std::string, Region> regions = scene.regions;
  for (const auto& [name, region] : spec.regions) {
    if (region.x1 > scene.camera.width || region.y1 > scene.camera.height)
      throw invalid(json_region_path(name) + ": region [" + std::to_string(region.x0) + ", " +
                    std::to_string(region.y0) + ", " + std::to_string(region.x1) + ", " +
                    std::to_string(region.y1) + "] lies outside the image (" +
                    std::to_string(scene.camera.width) + "x" + std::to_string(scene.camera.height) +
                    ") (in " + source + ")");
    regions[name] = region;
  }
  for (uint32_t spp : spec.budget_spp)
    if (spp > options_.max_spp)
      throw invalid("$.budget.spp: " + std::to_string(spp) +
                    " exceeds the coordinator's limit of " + std::to_string(options_.max_spp) +
                    " passes (in " + source + ")");
  if (spec.reference.kind == BatchReferenceKind::Auto && !spec.reference.sized &&
      spec.reference.spp > options_.max_spp)
    throw invalid("$.reference.spp: " + std::to_string(spec.reference.spp) +
                  " exceeds the coordinator's limit of " + std::to_string(options_.max_spp) +
                  " passes (in " + source + ")");

  v1::StoredBatch stored;
  v1::BatchStatus& status = *stored.mutable_status();
  v1::BatchReferenceStatus& reference = *status.mutable_reference();
  reference.set_kind(reference_kind_name(spec.reference.kind));
  switch (spec.reference.kind) {
    case BatchReferenceKind::Exact:  // rendered and uploaded by the client, like an EXR
    case BatchReferenceKind::Exr: {
      if (request.reference_exr().empty())
        throw invalid("$.reference: the spec names the EXR \"" + spec.reference.exr_path +
                      "\" but the request carries no reference_exr (in " + source + ")");
      Image image;
      ImageMetadata reference_metadata;
      try {
        image = decode_exr(request.reference_exr(), &reference_metadata);
      } catch (const std::exception& error) {
        throw invalid("$.reference: \"" + spec.reference.exr_path +
                      "\" is not a readable EXR: " + error.what());
      }
      const std::string reference_hash = reference_metadata["penumbra:scene_hash"];
      if (image.width != scene.camera.width || image.height != scene.camera.height)
        throw invalid("$.reference: \"" + spec.reference.exr_path + "\" is " +
                      std::to_string(image.width) + "x" + std::to_string(image.height) +
                      ", the scene is " + std::to_string(scene.camera.width) + "x" +
                      std::to_string(scene.camera.height));
      // A reference of another scene would measure the difference of the scenes.
      if (!reference_hash.empty() && reference_hash != scene.content_hash)
        throw invalid("$.reference: \"" + spec.reference.exr_path +
                      "\" is of another scene (scene_hash " + reference_hash.substr(0, 12) +
                      ", the spec's scene " + scene.content_hash.substr(0, 12) + ")");
      stored.set_reference_exr(request.reference_exr());
      reference.set_state(v1::JOB_STATE_DONE);
      if (spec.reference.kind == BatchReferenceKind::Exact) {
        reference.set_method("exact (fallback " + spec.reference.fallback_method + ")");
        reference.set_spp(spec.reference.camera_samples);
      }
      break;
    }
    case BatchReferenceKind::Job: {
      v1::JobStatus job;
      try {
        job = coordinator_.status(caller, spec.reference.job_id, false);
      } catch (const FarmError& error) {
        throw FarmError(error.code(), std::string("$.reference: ") + error.what());
      }
      if (job.width() != uint32_t(scene.camera.width) ||
          job.height() != uint32_t(scene.camera.height))
        throw invalid("$.reference: " + job.job_id() + " is " + std::to_string(job.width()) + "x" +
                      std::to_string(job.height()) + ", the scene is " +
                      std::to_string(scene.camera.width) + "x" +
                      std::to_string(scene.camera.height));
      if (job.scene_hash() != scene.content_hash)
        throw invalid("$.reference: " + job.job_id() + " rendered another scene (" +
                      job.scene_name() + ", scene_hash " + job.scene_hash().substr(0, 12) +
                      "; the spec's scene " + scene.content_hash.substr(0, 12) + ")");
      if (job.state() == v1::JOB_STATE_FAILED || job.state() == v1::JOB_STATE_CANCELLED)
        throw invalid("$.reference: " + job.job_id() + " ended " + v1::JobState_Name(job.state()) +
                      "; it has no image");
      reference.set_job_id(job.job_id());
      reference.set_method(job.method());
      reference.set_sampler(job.sampler());
      reference.set_spp(job.spp_budget());
      break;
    }
    case BatchReferenceKind::Auto:
      reference.set_method(spec.reference.method);
      reference.set_sampler(spec.reference.sampler);
      if (spec.reference.sized) {
        v1::BatchReferenceSizing& sizing = *reference.mutable_sizing();
        sizing.set_probe_spp(std::max<uint32_t>(options_.sizing_probe_spp, 2));
        sizing.set_target_share(spec.reference.target_share);
        sizing.set_max_seconds(spec.reference.max_seconds);
        // The reference method must run where the methods do.
        try {
          check_method_runs_on(scene, parse_method(spec.reference.method));
        } catch (const FormatError& error) {
          throw invalid("$.reference.method: " + std::string(error.what()));
        }
      } else {
        reference.set_spp(spec.reference.spp);
      }
      break;
  }

  status.set_name(spec.name);
  status.set_state(v1::BATCH_STATE_REFERENCE);
  status.set_spec_json(request.spec_json());
  status.set_scene_name(scene.name);
  status.set_scene_hash(scene.content_hash);
  status.set_width(uint32_t(scene.camera.width));
  status.set_height(uint32_t(scene.camera.height));
  for (const auto& [name, region] : regions) {
    v1::BatchRegion* entry = status.add_regions();
    entry->set_name(name);
    entry->mutable_rect()->set_x0(region.x0);
    entry->mutable_rect()->set_y0(region.y0);
    entry->mutable_rect()->set_x1(region.x1);
    entry->mutable_rect()->set_y1(region.y1);
  }
  for (const BatchMethodSpec& method : spec.methods) {
    v1::BatchMethodStatus* entry = status.add_methods();
    entry->set_label(method.label);
    entry->set_method(method.method);
    entry->set_sampler(method.sampler);
    if (spec.budget_seconds) {
      entry->set_has_budget_seconds(true);
      entry->set_budget_seconds(*spec.budget_seconds);
    }
    // What the estimator cannot run on this scene never reaches a worker.
    try {
      check_method_runs_on(scene, parse_method(method.method));
    } catch (const FormatError& error) {
      entry->set_error(error.what());
    }
  }
  status.set_submitted_unix_ms(unix_ms());
  status.set_owner(owner);
  stored.set_source_name(source);

  if (request.has_scene()) coordinator_.store_scene(scene.content_hash, request.scene());

  v1::SubmitBatchResponse response;
  {
    std::lock_guard lock(mutex_);
    uint64_t number = next_number_++;
    status.set_batch_id(batch_name(number));
    auto batch = std::make_unique<Batch>();
    batch->stored = std::move(stored);
    batch->spec = std::move(spec);
    Batch& b = *batch;
    batches_[number] = std::move(batch);
    store_.save(b.stored);
    spdlog::info("{}: submitted: \"{}\" on scene {} ({} methods, {} repeats)",
                 b.stored.status().batch_id(), b.spec.name, scene.name, b.spec.methods.size(),
                 b.spec.repeats);
    try {
      advance(b);
    } catch (const std::exception& error) {
      fail(b, error.what());
    }
    changed_locked();
    response.set_batch_id(b.stored.status().batch_id());
    response.set_scene_hash(scene.content_hash);
  }
  wakeup_->notify();
  return response;
}

std::string BatchManager::json_region_path(const std::string& name) {
  return json_member_path("$.regions", name);
}

BatchManager::Batch& BatchManager::batch_locked(const std::string& batch_id,
                                                const CallContext& caller) {
  uint64_t number = parse_batch_number(batch_id);
  auto it = batches_.find(number);
  if (number == 0 || it == batches_.end() || !caller.may_see(it->second->stored.status().owner()))
    throw FarmError(FarmErrorCode::NotFound,
                    "no batch \"" + batch_id + "\" (batch ids look like batch-3)");
  return *it->second;
}

v1::BatchStatus BatchManager::status(const std::string& batch_id, bool with_curves,
                                     const CallContext& caller) {
  std::lock_guard lock(mutex_);
  return status_locked(batch_locked(batch_id, caller), with_curves);
}

std::vector<v1::BatchStatus> BatchManager::list(const CallContext& caller) {
  std::lock_guard lock(mutex_);
  std::vector<v1::BatchStatus> out;
  for (auto& [number, batch] : batches_)
    if (caller.may_see(batch->stored.status().owner())) out.push_back(status_locked(*batch, false));
  return out;
}

v1::BatchStatus BatchManager::cancel(const std::string& batch_id, const CallContext& caller) {
  std::lock_guard lock(mutex_);
  Batch& batch = batch_locked(batch_id, caller);
  if (!is_terminal(batch.stored.status().state())) {
    finish(batch, v1::BATCH_STATE_CANCELLED);
    changed_locked();
  }
  return status_locked(batch, false);
}

std::string BatchManager::reference_exr(const std::string& batch_id, const CallContext& caller) {
  std::string job_id;
  {
    std::lock_guard lock(mutex_);
    Batch& batch = batch_locked(batch_id, caller);
    if (!batch.stored.reference_exr().empty()) return batch.stored.reference_exr();
    job_id = batch.stored.status().reference().job_id();
  }
  if (job_id.empty())
    throw FarmError(FarmErrorCode::FailedPrecondition,
                    batch_id + ": the reference is not rendered yet");
  return coordinator_.result_exr(job_id);
}

uint64_t BatchManager::version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

uint64_t BatchManager::wait_for_change(uint64_t seen, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen || stopping_; });
  return version_;
}

void BatchManager::changed_locked() {
  ++version_;
  changed_.notify_all();
}

void BatchManager::drive_loop() {
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
      bool active = false;
      for (auto& [number, batch] : batches_) {
        if (is_terminal(batch->stored.status().state())) continue;
        active = true;
        try {
          advance(*batch);
        } catch (const std::exception& error) {
          spdlog::error("{}: {}", batch->stored.status().batch_id(), error.what());
          fail(*batch, error.what());
        }
      }
      // Jobs progress without the batch record changing: watchers poll while anything runs.
      if (active) changed_locked();
    }
    std::unique_lock lock(wakeup_->mutex);
    wakeup_->condition.wait_for(lock, options_.poll, [&] { return wakeup_->pending; });
    wakeup_->pending = false;
  }
}

bool BatchManager::advance(Batch& batch) {
  bool changed = false;
  for (int step = 0; step < 4; ++step) {
    v1::BatchState before = batch.stored.status().state();
    bool moved = false;
    switch (before) {
      case v1::BATCH_STATE_REFERENCE:
        moved = advance_reference(batch);
        break;
      case v1::BATCH_STATE_CALIBRATING:
        moved = advance_calibration(batch);
        break;
      case v1::BATCH_STATE_RUNNING:
        moved = advance_runs(batch);
        break;
      default:
        break;
    }
    changed = changed || moved;
    if (moved) store_.save(batch.stored);
    if (batch.stored.status().state() == before) break;
  }
  return changed;
}

std::string BatchManager::reference_cache_key(const Batch& batch) const {
  const BatchReferenceSpec& reference = batch.spec.reference;
  // The status's spp: the spec's, or the sized one.
  return batch.stored.status().scene_hash() + "|" + to_string(parse_method(reference.method)) +
         "|" + reference.sampler + "|" + std::to_string(batch.stored.status().reference().spp()) +
         "|" + std::to_string(reference.seed);
}

std::string BatchManager::submit_job(Batch& batch, v1::JobSpec spec, bool in_batch,
                                     bool awaits_pass_count) {
  spec.set_scene_hash(batch.stored.status().scene_hash());
  if (spec.name().empty()) spec.set_name(batch.stored.status().batch_id());
  spec.set_owner(batch.stored.status().owner());
  v1::SubmitJobResponse response =
      in_batch
          ? coordinator_.submit_in_batch(spec, batch.stored.status().batch_id(), awaits_pass_count)
          : coordinator_.submit(spec);
  return response.job_id();
}

// Blocks of about passes / blocks_per_run passes, within [at_least, max_passes_per_task].
uint32_t BatchManager::passes_per_task_for(uint32_t passes, uint32_t at_least) const {
  uint32_t blocks = std::max<uint32_t>(options_.blocks_per_run, 1);
  uint32_t per_block = (passes + blocks - 1) / blocks;
  uint32_t most = std::max<uint32_t>(options_.max_passes_per_task, 1);
  return std::clamp<uint32_t>(per_block, std::min(std::max<uint32_t>(at_least, 1), most), most);
}

v1::JobSpec BatchManager::run_spec(const Batch& batch, const v1::BatchMethodStatus& method,
                                   uint32_t repeat, bool equal_time) const {
  v1::JobSpec spec;
  spec.set_method(method.method());
  spec.set_sampler(method.sampler());
  spec.set_seed(batch.spec.seed + repeat);
  std::string name = batch.stored.status().batch_id();
  name.append(" ").append(method.label()).append(" r").append(std::to_string(repeat));
  spec.set_name(name + (equal_time ? " equal time" : ""));
  // The batch's regions (the scene's and the spec's): every curve point measures each of them.
  *spec.mutable_regions() = batch.stored.status().regions();
  attach_reference(batch, spec);
  return spec;
}

void BatchManager::attach_reference(const Batch& batch, v1::JobSpec& spec) const {
  if (!batch.stored.reference_exr().empty())
    spec.set_reference_exr(batch.stored.reference_exr());
  else
    spec.set_reference_job(batch.stored.status().reference().job_id());
}

bool BatchManager::advance_reference(Batch& batch) {
  v1::BatchStatus& status = *batch.stored.mutable_status();
  v1::BatchReferenceStatus& reference = *status.mutable_reference();
  bool changed = false;
  if (reference.kind() == "auto" && reference.job_id().empty() && batch.spec.reference.sized &&
      !reference.sizing().sized()) {
    bool sized = false;
    changed = advance_sizing(batch, sized);
    if (!sized || is_terminal(status.state())) return changed;
  }
  if (reference.kind() == "auto" && reference.job_id().empty()) {
    std::string key = reference_cache_key(batch);
    auto cached = reference_cache_.find(key);
    if (cached != reference_cache_.end()) {
      try {
        v1::JobStatus job = coordinator_.status(cached->second, false);
        if (job.state() != v1::JOB_STATE_FAILED && job.state() != v1::JOB_STATE_CANCELLED) {
          reference.set_job_id(job.job_id());
          reference.set_cached(true);
          spdlog::info("{}: reference {} reused (cached for this scene and settings)",
                       status.batch_id(), job.job_id());
        }
      } catch (const FarmError&) {
        // The cached job is gone: render it again.
      }
    }
    if (reference.job_id().empty()) {
      v1::JobSpec spec;
      spec.set_method(batch.spec.reference.method);
      spec.set_sampler(batch.spec.reference.sampler);
      spec.set_seed(batch.spec.reference.seed);
      spec.set_spp(reference.spp());
      spec.set_passes_per_task(passes_per_task_for(reference.spp(), 1));
      spec.set_name("reference for " + status.scene_name() + " (" + status.batch_id() + ")");
      reference.set_job_id(submit_job(batch, spec, false));
      reference_cache_[key] = reference.job_id();
      store_.save_reference_cache(reference_cache_);
      spdlog::info("{}: reference {} submitted ({} at {} spp)", status.batch_id(),
                   reference.job_id(), batch.spec.reference.method, reference.spp());
    }
    changed = true;
  }
  if (reference.kind() != "exr" && reference.kind() != "exact") {
    v1::JobStatus job = coordinator_.status(reference.job_id(), false);
    if (reference.state() != job.state()) {
      reference.set_state(job.state());
      changed = true;
    }
    if (job.state() == v1::JOB_STATE_FAILED || job.state() == v1::JOB_STATE_CANCELLED) {
      fail(batch, "the reference " + job.job_id() + " ended " + v1::JobState_Name(job.state()) +
                      (job.error().empty() ? std::string() : ": " + job.error()));
      return true;
    }
    if (job.state() != v1::JOB_STATE_DONE) return changed;
  }
  status.set_state(batch.spec.budget_seconds ? v1::BATCH_STATE_CALIBRATING
                                             : v1::BATCH_STATE_RUNNING);
  return true;
}

bool BatchManager::advance_sizing(Batch& batch, bool& sized) {
  v1::BatchStatus& status = *batch.stored.mutable_status();
  v1::BatchReferenceSizing& sizing = *status.mutable_reference()->mutable_sizing();
  sized = false;
  const uint32_t probe_spp = std::max<uint32_t>(sizing.probe_spp(), 2);
  // Independent of every run (runs use seed + repeat) and of the reference's own seed.
  const uint64_t probe_seed = batch.spec.reference.seed ^ 0x70726f6265ull;  // "probe"
  if (sizing.probe_jobs_size() == 0) {
    auto probe = [&](const std::string& method, const std::string& sampler,
                     const std::string& label) {
      v1::JobSpec spec;
      spec.set_method(method);
      spec.set_sampler(sampler);
      spec.set_seed(probe_seed);
      spec.set_spp(probe_spp);
      spec.set_passes_per_task(probe_spp);
      spec.set_name(status.batch_id() + " reference sizing probe: " + label);
      sizing.add_probe_jobs(submit_job(batch, spec, true));
    };
    for (const v1::BatchMethodStatus& method : status.methods())
      if (method.error().empty()) probe(method.method(), method.sampler(), method.label());
    probe(batch.spec.reference.method, batch.spec.reference.sampler, "reference");
    spdlog::info("{}: sizing the reference from {} probes of {} spp", status.batch_id(),
                 sizing.probe_jobs_size(), probe_spp);
    store_.save(batch.stored);
    return true;
  }
  std::vector<v1::JobStatus> probes;
  for (const std::string& job : sizing.probe_jobs()) {
    probes.push_back(coordinator_.status(job, false));
    if (!job_terminal(probes.back().state())) return false;
  }
  if (probes.back().state() != v1::JOB_STATE_DONE) {
    fail(batch, "the reference method's sizing probe " + probes.back().job_id() + " ended " +
                    v1::JobState_Name(probes.back().state()) +
                    (probes.back().error().empty() ? "" : ": " + probes.back().error()));
    return true;
  }
  // The probes' films; the denominator of every noise term is their mean (all unbiased
  // estimates of one image, so the mean is the least noisy guess at the truth).
  std::vector<Film> films(probes.size());
  std::vector<bool> usable(probes.size(), false);
  Image denominator;
  int used = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (probes[i].state() != v1::JOB_STATE_DONE || probes[i].passes_complete() == 0) continue;
    films[i] = coordinator_.result_film(probes[i].job_id());
    if (films[i].variance.width == 0) continue;
    usable[i] = true;
    if (used++ == 0) {
      denominator = films[i].color;
    } else {
      for (size_t k = 0; k < denominator.rgb.size(); ++k)
        denominator.rgb[k] += films[i].color.rgb[k];
    }
  }
  if (!usable.back()) {
    fail(batch, "the reference method's sizing probe has no variance layer");
    return true;
  }
  for (float& value : denominator.rgb) value /= float(used);
  // Each method's spp at the batch's budget: its largest spp level, or what its seconds buy at
  // the probe's cost per pass, whichever is more.
  std::vector<double> budget_spp;
  std::vector<std::string> labels;
  std::vector<size_t> probe_of;
  size_t next = 0;
  for (const v1::BatchMethodStatus& method : status.methods()) {
    if (!method.error().empty()) continue;
    const size_t index = next++;
    if (!usable[index]) continue;
    double spp = batch.spec.budget_spp.empty() ? 0.0 : double(batch.spec.budget_spp.back());
    if (batch.spec.budget_seconds && probes[index].compute_seconds() > 0)
      spp = std::max(spp, *batch.spec.budget_seconds * double(probes[index].passes_complete()) /
                              probes[index].compute_seconds());
    budget_spp.push_back(std::max(spp, 1.0));
    labels.push_back(method.label());
    probe_of.push_back(index);
  }
  const size_t reference_probe = probes.size() - 1;
  if (labels.empty()) {
    fail(batch, "no method's sizing probe finished: the reference cannot be sized");
    return true;
  }
  ReferenceSizingRequest request;
  request.target_share = sizing.target_share();
  request.max_seconds = sizing.max_seconds();
  request.max_spp = options_.max_spp;
  request.seconds_per_pass =
      probes[reference_probe].compute_seconds() / double(probes[reference_probe].passes_complete());
  std::vector<std::pair<std::string, Region>> regions = {
      {"image", Region{0, 0, int(status.width()), int(status.height())}}};
  for (const v1::BatchRegion& region : status.regions())
    regions.emplace_back(region.name(), Region{region.rect().x0(), region.rect().y0(),
                                               region.rect().x1(), region.rect().y1()});
  for (const auto& [name, rect] : regions) {
    ReferenceSizingRegion region;
    region.name = name;
    const Film& reference_film = films[reference_probe];
    region.reference_noise = noise_per_sample(
        reference_film.variance, probes[reference_probe].passes_complete(), denominator, rect);
    for (size_t m = 0; m < labels.size(); ++m) {
      const Film& film = films[probe_of[m]];
      region.expected.push_back(noise_per_sample(film.variance,
                                                 probes[probe_of[m]].passes_complete(), denominator,
                                                 rect) /
                                budget_spp[m]);
    }
    request.regions.push_back(std::move(region));
  }
  const ReferenceSizing result = size_reference(request);
  sizing.set_sized(true);
  sizing.set_seconds_per_pass(request.seconds_per_pass);
  sizing.set_required_spp(result.required_spp);
  sizing.set_capped(result.capped);
  sizing.set_predicted_share(result.predicted_share);
  sizing.set_predicted_seconds(result.predicted_seconds);
  sizing.set_deciding_region(result.deciding_region);
  sizing.set_best_method(result.best_method >= 0 ? labels[size_t(result.best_method)] : "");
  status.mutable_reference()->set_spp(result.spp);
  spdlog::info(
      "{}: reference sized to {} spp (the target asks for {:.0f}; {}predicted share {:.2f}% in "
      "{}, best method {}; {:.1f} compute s)",
      status.batch_id(), result.spp, result.required_spp,
      result.capped ? "capped by max_seconds; " : "", 100 * result.predicted_share,
      result.deciding_region, sizing.best_method(), result.predicted_seconds);
  store_.save(batch.stored);
  sized = true;
  return true;
}

bool BatchManager::advance_calibration(Batch& batch) {
  bool changed = submit_runs(batch);
  changed = drive_equal_time_runs(batch) || changed;
  // Calibrated: every equal-time job has its cost per pass, or has ended.
  for (const v1::BatchMethodStatus& method : batch.stored.status().methods())
    for (const v1::BatchRun& run : method.runs())
      if (run.equal_time() && run.seconds_per_pass() == 0 &&
          !job_terminal(coordinator_.status(run.job_id(), false).state()))
        return changed;
  batch.stored.mutable_status()->set_state(v1::BATCH_STATE_RUNNING);
  return true;
}

bool BatchManager::advance_runs(Batch& batch) {
  bool changed = submit_runs(batch);
  changed = drive_equal_time_runs(batch) || changed;
  for (const v1::BatchMethodStatus& method : batch.stored.status().methods())
    for (const v1::BatchRun& run : method.runs())
      if (!job_terminal(coordinator_.status(run.job_id(), false).state())) return changed;
  finish(batch, v1::BATCH_STATE_DONE);
  return true;
}

// Every run at once, repeat by repeat and method by method, so that with round-robin serving
// every method's jobs advance together; false when they were submitted before.
bool BatchManager::submit_runs(Batch& batch) {
  v1::BatchStatus& status = *batch.stored.mutable_status();
  if (std::any_of(status.methods().begin(), status.methods().end(),
                  [](const v1::BatchMethodStatus& m) { return m.runs_size() > 0; }))
    return false;
  for (uint32_t repeat = 0; repeat < batch.spec.repeats; ++repeat) {
    for (v1::BatchMethodStatus& method : *status.mutable_methods()) {
      if (!method.error().empty()) continue;
      auto add_run = [&](const v1::JobSpec& spec, bool equal_time) {
        std::string job_id = submit_job(batch, spec, true, equal_time);
        v1::BatchRun* run = method.add_runs();
        run->set_repeat(repeat);
        run->set_seed(spec.seed());
        run->set_equal_time(equal_time);
        run->set_spp_planned(equal_time ? 0 : spec.spp());
        run->set_job_id(job_id);
        if (equal_time && repeat == 0) method.set_calibration_job(job_id);
      };
      if (method.has_budget_seconds()) {
        // A seconds budget of a share of the method's budget, then it waits for its pass count.
        v1::JobSpec spec = run_spec(batch, method, repeat, true);
        spec.set_compute_seconds(
            std::max(1e-3, method.budget_seconds() * options_.calibration_share));
        spec.set_passes_per_task(std::max<uint32_t>(options_.calibration_passes_per_task, 1));
        add_run(spec, true);
      }
      for (uint32_t spp : batch.spec.budget_spp) {
        v1::JobSpec spec = run_spec(batch, method, repeat, false);
        spec.set_name(spec.name() + " " + std::to_string(spp) + " spp");
        spec.set_spp(spp);
        spec.set_passes_per_task(passes_per_task_for(spp, 1));
        add_run(spec, false);
      }
    }
  }
  store_.save(batch.stored);
  return true;
}

bool BatchManager::drive_equal_time_runs(Batch& batch) {
  bool changed = false;
  for (v1::BatchMethodStatus& method : *batch.stored.mutable_status()->mutable_methods())
    for (v1::BatchRun& run : *method.mutable_runs())
      if (run.equal_time() && coordinator_.awaits_pass_count(run.job_id()))
        changed = next_pass_count(batch, method, run) || changed;
  return changed;
}

// An equal-time job waits: after its calibration it is given most of the pass count its cost
// asks for, then its final count from the cost over every pass so far. Each count is stored
// before the job is given it; after a restart the job is given again what it was to get.
bool BatchManager::next_pass_count(Batch& batch, v1::BatchMethodStatus& method, v1::BatchRun& run) {
  const v1::BatchStatus& status = batch.stored.status();
  v1::JobStatus job = coordinator_.status(run.job_id(), false);
  const uint32_t rendered = job.passes_complete();
  const double budget = method.budget_seconds();
  bool changed = false;
  uint32_t spp = 0;
  bool final = true;
  if (rendered == 0 || !(job.compute_seconds() > 0)) {
    spdlog::warn("{}: {} measured no compute time; it ends at {} passes", status.batch_id(),
                 run.job_id(), rendered);
    spp = std::max(rendered, 1u);
    run.set_spp_planned(spp);
    store_.save(batch.stored);
    changed = true;
  } else if (run.seconds_per_pass() == 0) {
    run.set_calibration_passes(rendered);
    run.set_seconds_per_pass(job.compute_seconds() / double(rendered));
    const uint32_t wanted = passes_for_budget(budget, run.seconds_per_pass(), options_.max_spp);
    run.set_first_pass_count(
        std::max(rendered, uint32_t(std::llround(options_.first_count_share * double(wanted)))));
    if (method.calibration_job() == run.job_id()) {
      method.set_seconds_per_pass(run.seconds_per_pass());
      method.set_calibration_passes(rendered);
    }
    spdlog::info(
        "{}: {} r{} costs {:.4f} compute seconds per pass (over {} passes): {} spp, "
        "{} first",
        status.batch_id(), method.label(), run.repeat(), run.seconds_per_pass(), rendered, wanted,
        run.first_pass_count());
    store_.save(batch.stored);
    changed = true;
    spp = run.first_pass_count();
    final = false;
  } else if (job.spp_budget() == 0) {
    spp = run.first_pass_count();  // restarted before the job took its first count
    final = false;
  } else if (run.spp_planned() == 0) {
    const double cost = job.compute_seconds() / double(rendered);
    run.set_spp_planned(std::max(rendered, passes_for_budget(budget, cost, options_.max_spp)));
    spdlog::info("{}: {} r{} costs {:.4f} compute seconds per pass (over {} passes): {} spp",
                 status.batch_id(), method.label(), run.repeat(), cost, rendered,
                 run.spp_planned());
    store_.save(batch.stored);
    changed = true;
    spp = run.spp_planned();
  } else {
    spp = run.spp_planned();  // restarted before the job took its final count
  }
  // The first count in blocks like a run's (points of the MRSE curve), the last few passes in
  // one block (fewer, larger results).
  const uint32_t rest = spp - std::min(spp, rendered);
  const uint32_t passes_per_task =
      final ? std::clamp<uint32_t>(rest, 1, std::max<uint32_t>(options_.max_passes_per_task, 1))
            : passes_per_task_for(rest, options_.calibration_passes_per_task);
  try {
    coordinator_.set_pass_count(run.job_id(), spp, passes_per_task, final);
  } catch (const FarmError& error) {
    // A full queue: again later. A job cancelled since it was asked: it has ended.
    if (error.code() != FarmErrorCode::ResourceExhausted &&
        error.code() != FarmErrorCode::FailedPrecondition)
      throw;
    spdlog::warn("{}: no pass count given ({}); trying again", run.job_id(), error.what());
  }
  return changed;
}

// A coordinator killed after submitting a batch's runs but before the batch was stored leaves
// jobs the stored batch does not name: the batch submits its runs again, and an equal-time job
// among the first ones would wait for a pass count forever. Cancelled when the batch is loaded.
void BatchManager::cancel_unknown_jobs(const Batch& batch) {
  const std::vector<std::string> known = job_ids(batch);
  const std::string& batch_id = batch.stored.status().batch_id();
  for (const std::string& job : coordinator_.unfinished_jobs_in_batch(batch_id)) {
    if (std::find(known.begin(), known.end(), job) != known.end()) continue;
    spdlog::warn("{}: {} was submitted before a restart but never recorded; cancelled", batch_id,
                 job);
    coordinator_.cancel(job);
  }
}

std::vector<std::string> BatchManager::job_ids(const Batch& batch) const {
  std::vector<std::string> ids;
  for (const std::string& probe : batch.stored.status().reference().sizing().probe_jobs())
    ids.push_back(probe);
  for (const v1::BatchMethodStatus& method : batch.stored.status().methods()) {
    for (const v1::BatchRun& run : method.runs()) ids.push_back(run.job_id());
    if (!method.calibration_job().empty() &&
        std::find(ids.begin(), ids.end(), method.calibration_job()) == ids.end())
      ids.push_back(method.calibration_job());
  }
  return ids;
}

void BatchManager::fail(Batch& batch, const std::string& error) {
  batch.stored.mutable_status()->set_error(error);
  spdlog::error("{}: failed: {}", batch.stored.status().batch_id(), error);
  finish(batch, v1::BATCH_STATE_FAILED);
}

void BatchManager::finish(Batch& batch, v1::BatchState state) {
  if (state != v1::BATCH_STATE_DONE)
    for (const std::string& job : job_ids(batch)) {
      try {
        coordinator_.cancel(job);
      } catch (const std::exception&) {
        // Already gone: nothing to cancel.
      }
    }
  batch.stored.mutable_status()->set_state(state);
  batch.stored.set_finished_unix_ms(unix_ms());
  store_.save(batch.stored);
  spdlog::info("{}: {}", batch.stored.status().batch_id(), v1::BatchState_Name(state));
}

v1::BatchStatus BatchManager::status_locked(const Batch& batch, bool with_curves) {
  v1::BatchStatus status = batch.stored.status();
  uint32_t total = 0, done = 0;
  double compute = 0;
  auto count = [&](const v1::JobStatus& job) {
    ++total;
    if (job_terminal(job.state())) ++done;
    compute += job.compute_seconds();
  };
  v1::BatchReferenceStatus& reference = *status.mutable_reference();
  if (!reference.job_id().empty()) {
    try {
      v1::JobStatus job = coordinator_.status(reference.job_id(), false);
      reference.set_state(job.state());
      if (!reference.cached() && reference.kind() == "auto") count(job);
    } catch (const std::exception&) {
    }
  }
  for (const std::string& probe : reference.sizing().probe_jobs()) {
    try {
      count(coordinator_.status(probe, false));
    } catch (const std::exception&) {
    }
  }
  for (v1::BatchMethodStatus& method : *status.mutable_methods()) {
    // A calibration job of its own (batches stored before calibrations were runs).
    const bool separate =
        !method.calibration_job().empty() &&
        std::none_of(method.runs().begin(), method.runs().end(), [&](const v1::BatchRun& run) {
          return run.job_id() == method.calibration_job();
        });
    if (separate) {
      try {
        count(coordinator_.status(method.calibration_job(), false));
      } catch (const std::exception&) {
      }
    }
    for (v1::BatchRun& run : *method.mutable_runs()) {
      try {
        *run.mutable_job() = coordinator_.status(run.job_id(), with_curves);
        count(run.job());
      } catch (const std::exception& error) {
        run.mutable_job()->set_error(error.what());
      }
    }
  }
  status.set_jobs_total(total);
  status.set_jobs_done(done);
  status.set_compute_seconds(compute);
  int64_t end = is_terminal(status.state()) && batch.stored.finished_unix_ms()
                    ? batch.stored.finished_unix_ms()
                    : unix_ms();
  status.set_wall_seconds(double(end - status.submitted_unix_ms()) / 1000.0);
  return status;
}

}  // namespace penumbra::farm
