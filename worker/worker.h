#pragma once
// The worker daemon's core: registers with the coordinator, leases as many tasks as it has
// threads (so one is always waiting while another renders), renders them with core in a TBB
// arena of `threads`, heartbeats its leases, and delivers results, keeping those it could not
// deliver and retrying them. When the coordinator is away it retries with backoff (it may start
// before the coordinator). drain() stops leasing, finishes what it holds, delivers it and
// returns from run().
//
// Scenes are fetched by content hash in chunks (GetSceneManifest, then GetSceneChunk per chunk,
// each checked against its SHA-256) and cached on disk (cache_dir, at most cache_max_bytes,
// least recently used scenes deleted first). A scene is prepared once (parsed, Embree and
// line-query BVHs built, textures decoded: core/render/prepared_scene.h) and shared by every
// job of it whatever its method, within max_prepared_bytes of memory; a job's Renderer (its
// method's estimator) is kept across its tiles.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/render/prepared_scene.h"
#include "core/render/renderer.h"
#include "penumbra/v1/farm.grpc.pb.h"
#include "worker/task_decoding.h"

namespace penumbra::farm {

struct WorkerOptions {
  std::string coordinator = "127.0.0.1:7420";
  // TLS and token (proto/support/farm_client.h FarmConnection; `coordinator` is its address).
  std::string tls_ca, tls_cert, tls_key;  // PEM paths; tls_ca set: TLS; cert + key: mutual TLS
  std::string token;                      // "worker" or "admin" role; empty: none
  int threads = 1;
  std::string cache_dir;  // empty: scenes are cached in memory only
  // The disk cache's bound: beyond it, the scenes used least recently are deleted.
  uint64_t cache_max_bytes = uint64_t(4) << 30;
  // Memory for prepared scenes (parsed scene, Embree and line-query BVHs, textures) kept across
  // jobs; the scene in use is kept even when it alone is larger.
  size_t max_prepared_bytes = size_t(4) << 30;
  std::string name = "worker";
  std::string build_flavour;  // empty: penumbra::kBuildFlavour
  std::chrono::milliseconds idle_poll{100};
  std::chrono::milliseconds max_backoff{2000};
  std::chrono::seconds drain_timeout{60};
};

class RenderWorker {
 public:
  // Throws std::runtime_error when the connection cannot be set up (unreadable PEM file, a token
  // over plaintext to a host that is not loopback).
  explicit RenderWorker(WorkerOptions options);
  ~RenderWorker();
  RenderWorker(const RenderWorker&) = delete;
  RenderWorker& operator=(const RenderWorker&) = delete;

  // Works until drained (returns 0) or refused by the coordinator (returns 2: wrong build or
  // protocol, unknown token or a token without the worker role; the reason is logged).
  int run();
  // Stops leasing; run() returns once held tasks are rendered and delivered (or drain_timeout).
  void drain();

 private:
  struct HeldTask {
    v1::Task task;
    bool revoked = false;
  };
  struct Outgoing {
    std::optional<v1::CompleteTaskRequest> completion;
    std::optional<v1::FailTaskRequest> failure;
    const std::string& token() const {
      return completion ? completion->attempt_token() : failure->attempt_token();
    }
  };

  bool register_with_coordinator();
  bool deliver_outbox();
  bool send_heartbeat();
  bool lease_more();
  void render_loop();
  void render(const v1::Task& task);
  std::shared_ptr<const Scene> scene_for(const std::string& hash);
  // The package's bytes from the coordinator, in chunks, each checked against the manifest.
  std::string fetch_scene_bytes(const std::string& hash);
  // Deletes the least recently used scene files until the cache fits cache_max_bytes (`keep`,
  // the scene just written, stays).
  void evict_disk_cache(const std::filesystem::path& keep);
  // The scene parsed and prepared (BVHs, textures), shared by every job of it whatever the
  // method; kept by content hash within max_prepared_bytes, least recently used evicted first.
  std::shared_ptr<const PreparedScene> prepared_for(const std::string& hash);
  void evict_prepared_locked(const std::string& keep);
  // The renderer of a decoded task (cached per job, scene, method, sampler and seed).
  std::shared_ptr<const Renderer> renderer_for(
      const v1::Task& task, const DecodedTask& decoded,
      const std::shared_ptr<const PreparedScene>& prepared);
  void backoff();
  void reset_backoff() { backoff_ = std::chrono::milliseconds(0); }

  WorkerOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Workers::Stub> stub_;
  std::string worker_id_;
  std::chrono::duration<double> heartbeat_period_{1.0};
  std::chrono::steady_clock::time_point last_heartbeat_;
  std::chrono::milliseconds backoff_{0};

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<HeldTask> queue_;         // leased, not yet rendering
  std::optional<HeldTask> rendering_;  // the task being rendered
  std::deque<Outgoing> outbox_;        // results not yet delivered
  std::atomic<bool> draining_{false};
  bool stopping_ = false;
  std::thread render_thread_;

  std::mutex cache_mutex_;
  uint64_t use_clock_ = 0;  // orders uses, for least-recently-used eviction
  struct PreparedEntry {
    std::string scene_hash;
    std::shared_ptr<const PreparedScene> prepared;
    uint64_t last_use = 0;
  };
  std::vector<PreparedEntry> prepared_;
  struct RendererEntry {
    std::string scene_hash;
    std::shared_ptr<const Renderer> renderer;
    uint64_t last_use = 0;
  };
  std::map<std::string, RendererEntry> renderers_;  // by job and options
};

}  // namespace penumbra::farm
