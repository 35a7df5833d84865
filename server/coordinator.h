#pragma once
// The coordinator's core: jobs, tasks, leases, workers, persistence and job assembly, as one
// thread-safe class with no gRPC in sight. The gRPC services (server/jobs_service.h,
// server/workers_service.h) translate calls to it; errors are FarmError (server/farm_error.h).
// Requests and results use the protobuf messages of penumbra/v1/farm.proto as plain data.
//
// Jobs: the image is cut into tiles (default 64x64); a task is a tile and a pass block (default
// 8 passes). An spp budget opens every block at submission; a seconds budget opens blocks one at
// a time while the summed compute seconds stay under the budget, so the job stops at a pass
// boundary with the same pass count in every tile. A block is sealed when every tile has
// completed it: its results are merged into the per-tile sums (exactly, core/render/tile.h), the
// MRSE against the reference is recorded, and the block's task results are dropped from the
// store. The job is done when its last block is sealed: the EXR is assembled and stored.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/image/image.h"
#include "core/render/film.h"
#include "core/render/tile.h"
#include "core/scene/scene.h"
#include "penumbra/v1/farm.pb.h"
#include "server/farm_error.h"
#include "server/lease_table.h"
#include "server/scheduler.h"
#include "server/store.h"

namespace penumbra::farm {

struct CoordinatorOptions {
  std::string data_dir;
  std::chrono::milliseconds lease_time{30'000};
  uint32_t default_tile_size = 64;
  uint32_t default_passes_per_task = 8;
  size_t max_scene_bytes = size_t(256) << 20;
  size_t max_queued_tasks = 1'000'000;
  uint32_t max_spp = 1u << 20;
  double max_seconds_budget = 1e7;
  int max_task_failures = 3;
  uint32_t max_tasks_per_lease = 256;
  std::string build_flavour;  // empty: penumbra::kBuildFlavour
};

// Monotonic counters and gauges for monitoring (Prometheus metrics, dashboards, benchmarks).
struct CoordinatorCounters {
  uint64_t tasks_leased = 0;     // leases granted since start
  uint64_t tasks_completed = 0;  // results accepted
  uint64_t tasks_failed = 0;     // FailTask calls that released a lease
  uint64_t late_results = 0;     // late or duplicate results dropped
  uint64_t leases_expired = 0;   // leases that timed out and were queued again
  uint64_t jobs_submitted = 0;
  uint64_t queued_tasks = 0;  // gauge: tasks waiting for a worker
  uint64_t leased_tasks = 0;  // gauge: tasks held by workers now
};

// Parses a scene package without touching the filesystem. Throws FormatError.
using SceneParser = std::function<Scene(const v1::ScenePackage&)>;

class Coordinator {
 public:
  // Opens the store under options.data_dir and resumes the jobs it holds: sealed tiles and
  // completed tasks are kept, every other task of a running job is queued again.
  Coordinator(CoordinatorOptions options, SceneParser parser);
  ~Coordinator();
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  // Jobs (clients). A client's spec.batch_id is ignored.
  v1::SubmitJobResponse submit(const v1::JobSpec& spec);
  // A job of a batch (server/batch_manager.h): served round-robin with the batch's other jobs.
  v1::SubmitJobResponse submit_in_batch(const v1::JobSpec& spec, const std::string& batch_id);
  // Stores a scene package (already parsed and validated by the caller) under its hash, so
  // jobs may name it by scene_hash.
  void store_scene(const std::string& scene_hash, const v1::ScenePackage& package);
  v1::JobStatus status(const std::string& job_id, bool with_curve = true);
  std::vector<v1::JobStatus> list();
  v1::JobState cancel(const std::string& job_id);
  std::string result_exr(const std::string& job_id);
  // The finished job's image (decoded from its EXR).
  Film result_film(const std::string& job_id);
  // A running or finished job's image so far: the sealed pass blocks of every tile (tiles with
  // none are black). For live previews; the pass count is returned in `passes`.
  Film preview_film(const std::string& job_id, uint32_t* passes = nullptr);
  std::vector<v1::WorkerInfo> workers();
  CoordinatorCounters counters() const;

  // Calls `on_change` (from any thread, never under the coordinator's lock) whenever the job's
  // status may have changed. Returns an id for unsubscribe.
  uint64_t subscribe(const std::string& job_id, std::function<void()> on_change);
  void unsubscribe(uint64_t subscription);

  // Workers.
  v1::RegisterResponse register_worker(const v1::RegisterRequest& request);
  v1::HeartbeatResponse heartbeat(const v1::HeartbeatRequest& request);
  v1::LeaseTasksResponse lease_tasks(const v1::LeaseTasksRequest& request);
  v1::ScenePackage scene(const std::string& scene_hash);
  // True when the result was accepted; false for a late or duplicate result (dropped).
  bool complete_task(const v1::CompleteTaskRequest& request);
  void fail_task(const v1::FailTaskRequest& request);

  // Requeues tasks whose leases expired (a background thread calls it every lease_time / 4).
  void expire_leases();

  static std::string job_name(uint64_t job_id);
  const CoordinatorOptions& options() const { return options_; }
  const SceneParser& scene_parser() const { return parser_; }
  // The scheduler group of a batch id ("batch-3" -> 3); 0 (no group) for anything else.
  static uint64_t batch_group(const std::string& batch_id);

 private:
  struct Job;
  struct Worker {
    std::string name;
    uint32_t threads = 0;
    std::string version, build_flavour;
    SteadyTime last_contact;
    uint64_t tasks_completed = 0;
    double compute_seconds = 0;
  };
  using Notifications = std::vector<std::function<void()>>;

  v1::SubmitJobResponse submit_spec(v1::JobSpec spec);
  uint64_t parse_job_id(const std::string& job_id) const;
  Job& job_locked(const std::string& job_id);
  Worker& worker_locked(const std::string& worker_id);
  void resume(const JobRecord& record);
  void open_block(Job& job);
  void maybe_open_block(Job& job);
  void seal_ready_blocks(Job& job);
  void finish(Job& job);
  void end_job(Job& job, v1::JobState state, const std::string& error);
  void load_reference(Job& job);
  v1::JobStatus status_locked(const Job& job, bool with_curve) const;
  TileRect task_tile(const Job& job, uint64_t task_index) const;
  std::pair<uint32_t, uint32_t> task_passes(const Job& job, uint64_t task_index) const;
  void collect_notifications(uint64_t job_id, Notifications& out) const;
  static void run(const Notifications& notifications);
  void expiry_loop();

  CoordinatorOptions options_;
  SceneParser parser_;
  Store store_;
  mutable std::mutex mutex_;
  std::map<uint64_t, std::unique_ptr<Job>> jobs_;
  Scheduler scheduler_;
  LeaseTable leases_;
  std::map<std::string, Worker> workers_;
  uint64_t next_worker_ = 1;
  std::map<uint64_t, std::pair<uint64_t, std::function<void()>>> subscriptions_;
  uint64_t next_subscription_ = 1;
  CoordinatorCounters counters_;  // under mutex_; gauges filled in by counters()

  std::mutex expiry_mutex_;
  std::condition_variable expiry_wake_;
  bool stopping_ = false;
  std::thread expiry_thread_;
};

}  // namespace penumbra::farm
