#include "worker/worker.h"

#include <grpcpp/client_context.h>
#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/render/local_render.h"
#include "core/sampling/pattern.h"
#include "penumbra/version.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_chunks.h"
#include "proto/support/scene_packing.h"
#include "worker/task_decoding.h"

namespace penumbra::farm {

namespace {

// Renderers are small (a method's estimator, the camera, the pixel filter: the scene's BVHs
// belong to its prepared scene), so many jobs interleaved on one worker each keep theirs.
constexpr size_t kMaxRenderers = 64;

std::unique_ptr<grpc::ClientContext> context_with_deadline(std::chrono::seconds seconds) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + seconds);
  return context;
}

// A scene content hash as core computes it: SHA-256 as 64 lowercase hex digits. Cache files are
// named by it, so nothing else (no "../", no "/", no upper case, no other length) is accepted.
bool is_content_hash(const std::string& text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::string describe(const grpc::Status& status) {
  return "status " + std::to_string(int(status.error_code())) + ": " + status.error_message();
}

}  // namespace

RenderWorker::RenderWorker(WorkerOptions options) : options_(std::move(options)) {
  if (options_.threads < 1) options_.threads = 1;
  if (options_.build_flavour.empty()) options_.build_flavour = kBuildFlavour;
  // The farm's channel: large messages, quick reconnection when the coordinator comes back (the
  // default waits up to two minutes), TLS and the token on every call when configured.
  FarmConnection connection;
  connection.address = options_.coordinator;
  connection.tls_ca = options_.tls_ca;
  connection.tls_cert = options_.tls_cert;
  connection.tls_key = options_.tls_key;
  connection.token = options_.token;
  channel_ = make_farm_channel(connection);
  stub_ = v1::Workers::NewStub(channel_);
}

RenderWorker::~RenderWorker() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (render_thread_.joinable()) render_thread_.join();
}

void RenderWorker::drain() {
  draining_ = true;
  wake_.notify_all();
}

void RenderWorker::backoff() {
  backoff_ = std::clamp(backoff_ * 2, std::chrono::milliseconds(100), options_.max_backoff);
  std::unique_lock lock(mutex_);
  wake_.wait_for(lock, backoff_, [this] { return stopping_; });
}

int RenderWorker::run() {
  render_thread_ = std::thread([this] { render_loop(); });
  std::optional<std::chrono::steady_clock::time_point> drain_deadline;
  int exit_code = 0;
  while (true) {
    if (draining_ && !drain_deadline) {
      drain_deadline = std::chrono::steady_clock::now() + options_.drain_timeout;
      spdlog::info("draining: finishing the tasks held, then exiting");
    }
    bool ok = true;
    if (worker_id_.empty()) {
      v1::RegisterRequest request;
      request.set_name(options_.name);
      request.set_threads(uint32_t(options_.threads));
      request.set_version(kVersion);
      request.set_build_flavour(options_.build_flavour);
      request.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
      v1::RegisterResponse response;
      auto context = context_with_deadline(std::chrono::seconds(10));
      grpc::Status status = stub_->Register(context.get(), request, &response);
      if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION ||
          status.error_code() == grpc::StatusCode::INVALID_ARGUMENT ||
          status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
          status.error_code() == grpc::StatusCode::PERMISSION_DENIED) {
        spdlog::critical("the coordinator refused this worker: {}", status.error_message());
        exit_code = 2;
        break;
      }
      if (status.error_code() == grpc::StatusCode::ALREADY_EXISTS) {
        // Our name is held by a live registration: our own previous process (it gets declared
        // dead after its missed heartbeats) or another worker of the same --name.
        spdlog::warn("{}; retrying", status.error_message());
        ok = false;
      } else if (status.ok()) {
        worker_id_ = response.worker_id();
        heartbeat_period_ = std::chrono::duration<double>(response.heartbeat_seconds());
        last_heartbeat_ = std::chrono::steady_clock::now();
        spdlog::info("registered with {} as {}", options_.coordinator, worker_id_);
      } else {
        spdlog::debug("coordinator {} unavailable ({}); retrying", options_.coordinator,
                      describe(status));
        ok = false;
      }
    }
    if (ok && !worker_id_.empty()) ok = deliver_outbox();
    if (ok && !worker_id_.empty() &&
        std::chrono::steady_clock::now() - last_heartbeat_ >= heartbeat_period_)
      ok = send_heartbeat();
    bool leased = false;
    if (draining_) {
      std::lock_guard lock(mutex_);
      if (queue_.empty() && !rendering_ && outbox_.empty()) break;
      if (std::chrono::steady_clock::now() > *drain_deadline) {
        spdlog::warn("drain timed out with {} results undelivered", outbox_.size());
        break;
      }
    } else if (ok && !worker_id_.empty()) {
      size_t before = 0;
      {
        std::lock_guard lock(mutex_);
        before = queue_.size();
      }
      ok = lease_more();
      std::lock_guard lock(mutex_);
      leased = queue_.size() > before;
    }
    if (!ok) {
      backoff();
      continue;
    }
    reset_backoff();
    if (!leased) {
      // Idle until the next poll, or until the next heartbeat is due if that comes first.
      using Seconds = std::chrono::duration<double>;
      Seconds wait = options_.idle_poll;
      if (!worker_id_.empty()) {
        const Seconds due =
            Seconds(last_heartbeat_ - std::chrono::steady_clock::now()) + heartbeat_period_;
        wait = std::clamp(due, Seconds(0), wait);
      }
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, wait);
    }
  }
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    queue_.clear();
  }
  wake_.notify_all();
  render_thread_.join();
  spdlog::info("worker {} stopped", worker_id_);
  return exit_code;
}

bool RenderWorker::deliver_outbox() {
  while (true) {
    Outgoing outgoing;
    {
      std::lock_guard lock(mutex_);
      if (outbox_.empty()) return true;
      outgoing = outbox_.front();
    }
    grpc::Status status;
    bool accepted = true;
    if (outgoing.completion) {
      outgoing.completion->set_worker_id(worker_id_);
      v1::CompleteTaskResponse response;
      auto context = context_with_deadline(std::chrono::seconds(30));
      status = stub_->CompleteTask(context.get(), *outgoing.completion, &response);
      accepted = response.accepted();
    } else {
      outgoing.failure->set_worker_id(worker_id_);
      v1::FailTaskResponse response;
      auto context = context_with_deadline(std::chrono::seconds(10));
      status = stub_->FailTask(context.get(), *outgoing.failure, &response);
    }
    bool transient = status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                     status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED ||
                     status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED;
    if (transient) {
      spdlog::debug("result undelivered ({}); kept for retry", describe(status));
      return false;
    }
    if (!status.ok())
      spdlog::error("result dropped: the coordinator rejected it: {}", describe(status));
    else if (!accepted)
      spdlog::info("{} task {}: result dropped by the coordinator (lease expired or duplicate)",
                   outgoing.completion->job_id(), outgoing.completion->task_index());
    std::lock_guard lock(mutex_);
    if (!outbox_.empty() && outbox_.front().token() == outgoing.token()) outbox_.pop_front();
  }
}

bool RenderWorker::send_heartbeat() {
  v1::HeartbeatRequest request;
  request.set_worker_id(worker_id_);
  {
    std::lock_guard lock(mutex_);
    for (const HeldTask& held : queue_) request.add_attempt_tokens(held.task.attempt_token());
    if (rendering_) request.add_attempt_tokens(rendering_->task.attempt_token());
    for (const Outgoing& outgoing : outbox_) request.add_attempt_tokens(outgoing.token());
  }
  v1::HeartbeatResponse response;
  // The next heartbeat is due a period after this one was sent, not after its answer came: the
  // coordinator declares a worker dead at its first missed heartbeat, so the round trip must not
  // add up from one heartbeat to the next.
  const auto sent = std::chrono::steady_clock::now();
  auto context = context_with_deadline(std::chrono::seconds(10));
  grpc::Status status = stub_->Heartbeat(context.get(), request, &response);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND) {
    // The coordinator no longer knows us (it restarted): our leases are gone with it.
    spdlog::warn("coordinator forgot worker {}; registering again", worker_id_);
    worker_id_.clear();
    std::lock_guard lock(mutex_);
    queue_.clear();
    if (rendering_) rendering_->revoked = true;
    return true;
  }
  if (!status.ok()) return false;
  last_heartbeat_ = sent;
  if (response.revoked_tokens_size() == 0) return true;
  std::lock_guard lock(mutex_);
  for (const std::string& token : response.revoked_tokens()) {
    std::erase_if(queue_, [&](const HeldTask& held) { return held.task.attempt_token() == token; });
    if (rendering_ && rendering_->task.attempt_token() == token) rendering_->revoked = true;
  }
  spdlog::info("{} leases revoked by the coordinator", response.revoked_tokens_size());
  return true;
}

bool RenderWorker::lease_more() {
  // Hold one task more than can render at once, so the next one is ready when one finishes.
  const size_t capacity = size_t(std::max(options_.threads, 2));
  size_t held = 0;
  {
    std::lock_guard lock(mutex_);
    held = queue_.size() + (rendering_ ? 1 : 0);
  }
  if (held >= capacity) return true;
  v1::LeaseTasksRequest request;
  request.set_worker_id(worker_id_);
  request.set_max_tasks(uint32_t(capacity - held));
  v1::LeaseTasksResponse response;
  auto context = context_with_deadline(std::chrono::seconds(10));
  grpc::Status status = stub_->LeaseTasks(context.get(), request, &response);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND) {
    worker_id_.clear();
    return true;
  }
  if (!status.ok()) return false;
  if (response.tasks_size() == 0) return true;
  {
    std::lock_guard lock(mutex_);
    for (const v1::Task& task : response.tasks()) queue_.push_back({task, false});
  }
  wake_.notify_all();
  return true;
}

void RenderWorker::render_loop() {
  tbb::task_arena arena(options_.threads);
  while (true) {
    v1::Task task;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      rendering_ = queue_.front();
      queue_.pop_front();
      task = rendering_->task;
    }
    Outgoing outgoing;
    try {
      // Fields first (the scene hash names a cache file), then against the scene: the tile
      // inside the image, the pass range not empty (worker/task_decoding.h).
      TaskFields fields = check_task_fields(task);
      std::shared_ptr<const PreparedScene> prepared = prepared_for(task.scene_hash());
      const DecodedTask decoded = decode_task(task, std::move(fields), prepared->scene());
      std::shared_ptr<const Renderer> renderer = renderer_for(task, decoded, prepared);
      const TileRect rect = decoded.tile;
      TileAccumulator accumulator(rect);
      // Compute seconds: with one thread the arena runs the task on this thread (its one slot
      // is this thread's), so this thread's CPU clock measures the task alone, also when other
      // workers share the process (the embedded farm); with more threads the process's clock
      // (a worker daemon is alone in its process).
      auto cpu_seconds = [single = options_.threads == 1] {
        if (!single) return process_cpu_seconds();
        timespec now{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
        return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
      };
      double cpu_start = cpu_seconds();
      arena.execute(
          [&] { renderer->render_tile(rect, decoded.pass_begin, decoded.pass_end, accumulator); });
      v1::CompleteTaskRequest completion;
      completion.set_job_id(task.job_id());
      completion.set_task_index(task.task_index());
      completion.set_attempt_token(task.attempt_token());
      completion.set_tile(accumulator.serialize());
      completion.set_compute_seconds(std::max(0.0, cpu_seconds() - cpu_start));
      outgoing.completion = std::move(completion);
    } catch (const std::exception& error) {
      spdlog::error("{} task {}: {}", task.job_id(), task.task_index(), error.what());
      v1::FailTaskRequest failure;
      failure.set_job_id(task.job_id());
      failure.set_task_index(task.task_index());
      failure.set_attempt_token(task.attempt_token());
      failure.set_error(error.what());
      outgoing.failure = std::move(failure);
    }
    {
      std::lock_guard lock(mutex_);
      if (!rendering_->revoked) outbox_.push_back(std::move(outgoing));
      rendering_.reset();
    }
    wake_.notify_all();
  }
}

std::string RenderWorker::fetch_scene_bytes(const std::string& hash) {
  // Transient failures (the coordinator restarting, a deadline under load) are retried with
  // backoff; anything else fails the task (the coordinator then retries it elsewhere).
  auto call = [&](const char* what, auto&& invoke) {
    grpc::Status status;
    for (int attempt = 0; attempt < 20; ++attempt) {
      status = invoke();
      if (status.ok() || (status.error_code() != grpc::StatusCode::UNAVAILABLE &&
                          status.error_code() != grpc::StatusCode::DEADLINE_EXCEEDED))
        break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100 * (1 << std::min(attempt, 4))));
    }
    if (!status.ok())
      throw std::runtime_error("cannot fetch scene " + hash + " (" + what +
                               "): " + describe(status));
  };
  v1::GetSceneRequest request;
  request.set_scene_hash(hash);
  v1::SceneManifest manifest;
  call("manifest", [&] {
    auto context = context_with_deadline(std::chrono::seconds(60));
    return stub_->GetSceneManifest(context.get(), request, &manifest);
  });
  if (manifest.scene_hash() != hash)
    throw std::runtime_error("scene " + hash + ": the coordinator sent the manifest of " +
                             manifest.scene_hash());
  check_scene_manifest(manifest, std::numeric_limits<uint64_t>::max());
  return assemble_scene_chunks(manifest, [&](uint32_t index) {
    v1::GetSceneChunkRequest chunk_request;
    chunk_request.set_scene_hash(hash);
    chunk_request.set_index(index);
    v1::SceneChunk chunk;
    call("chunk", [&] {
      auto context = context_with_deadline(std::chrono::seconds(60));
      return stub_->GetSceneChunk(context.get(), chunk_request, &chunk);
    });
    return std::move(*chunk.mutable_data());
  });
}

void RenderWorker::evict_disk_cache(const std::filesystem::path& keep) {
  namespace fs = std::filesystem;
  std::error_code error;
  struct Entry {
    fs::path path;
    fs::file_time_type used;
    uintmax_t bytes;
  };
  std::vector<Entry> entries;
  uintmax_t total = 0;
  for (const fs::directory_entry& entry :
       fs::directory_iterator(fs::path(options_.cache_dir) / "scenes", error)) {
    if (entry.path().extension() != ".pb" || !entry.is_regular_file(error)) continue;
    Entry e{entry.path(), entry.last_write_time(error), entry.file_size(error)};
    total += e.bytes;
    entries.push_back(std::move(e));
  }
  // Least recently used first (a file's time is touched at each use).
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& entry : entries) {
    if (total <= options_.cache_max_bytes) break;
    if (entry.path == keep) continue;
    if (fs::remove(entry.path, error)) {
      total -= entry.bytes;
      spdlog::info("scene cache: evicted {} ({} bytes; the cache holds at most {})",
                   entry.path.filename().string(), entry.bytes, options_.cache_max_bytes);
    }
  }
}

std::shared_ptr<const Scene> RenderWorker::scene_for(const std::string& hash) {
  if (!is_content_hash(hash))
    throw std::runtime_error("scene hash \"" + hash +
                             "\" is not a content hash (64 lowercase hex)");
  namespace fs = std::filesystem;
  fs::path cached;
  std::optional<Scene> scene;
  if (!options_.cache_dir.empty()) {
    cached = fs::path(options_.cache_dir) / "scenes" / (hash + ".pb");
    v1::ScenePackage package;
    std::ifstream in(cached, std::ios::binary);
    if (in && package.ParseFromIstream(&in)) {
      try {
        scene = parse_wire_package(package);
        if (scene->content_hash != hash) scene.reset();
      } catch (const std::exception& error) {
        spdlog::warn("cached scene {} unusable ({}); fetching it again", hash, error.what());
      }
    }
    if (scene) {
      std::error_code error;
      fs::last_write_time(cached, fs::file_time_type::clock::now(), error);  // recently used
    }
  }
  if (!scene) {
    const std::string bytes = fetch_scene_bytes(hash);
    v1::ScenePackage package;
    if (!package.ParseFromString(bytes))
      throw std::runtime_error("scene " + hash + " arrived unreadable");
    scene = parse_wire_package(package);
    if (scene->content_hash != hash)
      throw std::runtime_error("scene " + hash + " arrived with hash " + scene->content_hash);
    if (!cached.empty()) {
      std::error_code error;
      fs::create_directories(cached.parent_path(), error);
      auto temporary = cached;
      temporary += ".tmp";
      {
        std::ofstream out(temporary, std::ios::binary);
        out.write(bytes.data(), std::streamsize(bytes.size()));
      }
      fs::rename(temporary, cached, error);
      evict_disk_cache(cached);
    }
    spdlog::info("scene {} ({}) fetched: {} bytes", scene->name, hash.substr(0, 12), bytes.size());
  }
  return std::make_shared<const Scene>(std::move(*scene));
}

std::shared_ptr<const PreparedScene> RenderWorker::prepared_for(const std::string& hash) {
  {
    std::lock_guard lock(cache_mutex_);
    for (PreparedEntry& entry : prepared_)
      if (entry.scene_hash == hash) {
        entry.last_use = ++use_clock_;
        return entry.prepared;
      }
  }
  // Parsing and building the BVHs take a while (seconds for a million triangles): outside the
  // lock. One render thread asks, so a scene is prepared once.
  auto prepared = std::make_shared<const PreparedScene>(scene_for(hash));
  std::lock_guard lock(cache_mutex_);
  prepared_.push_back({hash, prepared, ++use_clock_});
  evict_prepared_locked(hash);
  return prepared;
}

void RenderWorker::evict_prepared_locked(const std::string& keep) {
  // Sizes are read now: a line-query BVH built since a scene was cached counts too.
  auto total = [this] {
    size_t bytes = 0;
    for (const PreparedEntry& entry : prepared_) bytes += entry.prepared->memory_bytes();
    return bytes;
  };
  while (prepared_.size() > 1 && total() > options_.max_prepared_bytes) {
    auto oldest = prepared_.end();
    for (auto it = prepared_.begin(); it != prepared_.end(); ++it)
      if (it->scene_hash != keep && (oldest == prepared_.end() || it->last_use < oldest->last_use))
        oldest = it;
    if (oldest == prepared_.end()) break;
    spdlog::info("prepared scene {} evicted ({} MiB; prepared scenes are held up to {} MiB)",
                 oldest->scene_hash.substr(0, 12), oldest->prepared->memory_bytes() >> 20,
                 options_.max_prepared_bytes >> 20);
    // Its renderers hold it too: they go with it, so the memory is freed.
    std::erase_if(renderers_,
                  [&](const auto& item) { return item.second.scene_hash == oldest->scene_hash; });
    prepared_.erase(oldest);
  }
}

std::shared_ptr<const Renderer> RenderWorker::renderer_for(
    const v1::Task& task, const DecodedTask& decoded,
    const std::shared_ptr<const PreparedScene>& prepared) {
  std::ostringstream key;
  key << task.job_id() << '|' << task.scene_hash() << '|' << task.method() << '|' << task.sampler()
      << '|' << task.seed();
  {
    std::lock_guard lock(cache_mutex_);
    auto it = renderers_.find(key.str());
    if (it != renderers_.end()) {
      it->second.last_use = ++use_clock_;
      return it->second.renderer;
    }
  }
  // Only the method's estimator is new; the scene's BVHs and textures are the prepared scene's.
  auto renderer = std::make_shared<const Renderer>(prepared, decoded.options, decoded.method);
  std::lock_guard lock(cache_mutex_);
  renderers_[key.str()] = {task.scene_hash(), renderer, ++use_clock_};
  if (renderers_.size() > kMaxRenderers) {
    auto oldest = renderers_.begin();
    for (auto it = renderers_.begin(); it != renderers_.end(); ++it)
      if (it->second.last_use < oldest->second.last_use) oldest = it;
    renderers_.erase(oldest);
  }
  return renderer;
}

}  // namespace penumbra::farm
