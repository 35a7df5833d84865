#pragma once
// The coordinator's core: jobs, tasks, leases, workers, persistence and job assembly, as one
// thread-safe class with no gRPC in sight. The gRPC services (server/services.h)
// translate calls to it; errors are FarmError (server/farm_error.h).
// Requests and results use the protobuf messages of penumbra/v1/farm.proto as plain data.
//
// Jobs: the image is cut into tiles (default 64x64); a task is a tile and a pass block (default
// 8 passes). An spp budget opens every block at submission; a seconds budget opens blocks one at
// a time while the summed compute seconds stay under the budget, so the job stops at a pass
// boundary with the same pass count in every tile. A block is sealed when every tile has
// completed it (and every result is durable): its results are merged into the per-tile sums
// (exactly, core/render/tile.h) and the MRSE against the reference is recorded. The store keeps
// the task results of sealed blocks until a checkpoint (every checkpoint_blocks blocks) writes
// the merged sums and drops them (a restart merges them again), so a block's pixels are written
// about once, not twice. The job is done when its last block is sealed: the EXR is stored.
//
// A batch's equal-time run (submit_in_batch with awaits_pass_count) starts as a seconds budget:
// it renders blocks until that budget is spent (its calibration), then waits for the batch
// manager to give it a pass count (set_pass_count) and renders on to it as an spp job, its later
// blocks possibly larger; it waits again at each count until one is final. The image is the same
// as a job of the final spp rendered in one go.

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
#include "server/call_context.h"
#include "server/farm_error.h"
#include "server/job_workers.h"
#include "server/lease_table.h"
#include "server/scene_transfer.h"
#include "server/scheduler.h"
#include "server/store.h"

namespace penumbra::farm {

struct CoordinatorOptions {
  std::string data_dir;
  // A lease not extended for this long expires and its task is queued again: the fence that
  // makes a late result of a lost lease recognisable (only the current attempt token counts).
  std::chrono::milliseconds lease_time{30'000};
  // Workers heartbeat every heartbeat_interval (at most lease_time / 3); any call counts as
  // contact. A worker silent for missed_heartbeats intervals and half an interval more is dead
  // (by default at its first missed heartbeat: 1.5 s of silence): its leases are revoked and its
  // tasks queued again at once, long before they would expire. The lease stays the fence: a
  // result or heartbeat of a worker declared dead names a revoked attempt token and is dropped.
  std::chrono::milliseconds heartbeat_interval{1'000};
  uint32_t missed_heartbeats = 1;
  // A dead worker leaves the worker list after this long (0: never).
  std::chrono::milliseconds forget_worker_after{300'000};
  uint32_t default_tile_size = 64;
  uint32_t default_passes_per_task = 8;
  size_t max_scene_bytes = size_t(256) << 20;
  size_t max_queued_tasks = 1'000'000;
  uint32_t max_spp = 1u << 20;
  double max_seconds_budget = 1e7;
  int max_task_failures = 3;
  uint32_t max_tasks_per_lease = 256;
  // Sealed blocks whose task results the store keeps before a checkpoint writes the merged
  // sums (an spp job that will finish within this many more blocks skips it).
  uint32_t checkpoint_blocks = 4;
  std::string build_flavour;  // empty: penumbra::kBuildFlavour
};

// Monotonic counters and gauges for monitoring (Prometheus metrics, dashboards, benchmarks).
struct CoordinatorCounters {
  uint64_t tasks_leased = 0;     // leases granted since start
  uint64_t tasks_completed = 0;  // results accepted
  uint64_t tasks_failed = 0;     // FailTask calls that released a lease
  uint64_t late_results = 0;     // late or duplicate results dropped
  uint64_t leases_expired = 0;   // leases that timed out, or of dead workers, queued again
  uint64_t workers_lost = 0;     // workers declared dead (missed heartbeats)
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

  // Jobs (clients). A client's spec.batch_id is ignored. The calls taking a CallContext act for
  // that caller (server/call_context.h): what it submits is owned by caller.client (its
  // spec.owner is replaced; a reference_job must be one it may see), and another owner's job is
  // NOT_FOUND exactly like an unknown id. The calls without one are the coordinator's own
  // (batch manager, HTTP side): every job, spec.owner kept.
  v1::SubmitJobResponse submit(const CallContext& caller, const v1::JobSpec& spec);
  v1::SubmitJobResponse submit(const v1::JobSpec& spec);
  // A job of a batch (server/batch_manager.h): served round-robin with the batch's other jobs.
  // `awaits_pass_count` (a seconds budget): once that budget is spent the job waits, RUNNING
  // with nothing queued, for set_pass_count.
  v1::SubmitJobResponse submit_in_batch(const v1::JobSpec& spec, const std::string& batch_id,
                                        bool awaits_pass_count = false);
  // True when the job has spent the seconds budget it was submitted with and waits for its pass
  // count; its status then has the calibration's passes and compute seconds.
  bool awaits_pass_count(const std::string& job_id);
  // Gives a waiting job a pass count: it becomes an spp job of max(spp, passes rendered) passes,
  // the rest in blocks of `passes_per_task`, persisted before this returns; unless `final` it
  // waits again once they are rendered. Again on a job that was given its final count: nothing
  // happens. FailedPrecondition for a job that does not wait (or not yet), InvalidArgument for
  // counts out of range.
  void set_pass_count(const std::string& job_id, uint32_t spp, uint32_t passes_per_task,
                      bool final = true);
  // Called (from any thread, never under the coordinator's lock) when a batch's job ends or
  // starts waiting for its pass count. One listener; empty to remove it.
  void set_batch_listener(std::function<void()> listener);
  // Stores a scene package (already parsed and validated by the caller) under its hash, so
  // jobs may name it by scene_hash.
  void store_scene(const std::string& scene_hash, const v1::ScenePackage& package);
  v1::JobStatus status(const CallContext& caller, const std::string& job_id,
                       bool with_curve = true);
  v1::JobStatus status(const std::string& job_id, bool with_curve = true);
  // The jobs the caller may see, by id.
  std::vector<v1::JobStatus> list(const CallContext& caller);
  std::vector<v1::JobStatus> list();
  // The ids of the batch's jobs (submit_in_batch) that have not ended.
  std::vector<std::string> unfinished_jobs_in_batch(const std::string& batch_id);
  v1::JobState cancel(const CallContext& caller, const std::string& job_id);
  v1::JobState cancel(const std::string& job_id);
  // The result EXR: a done job's, or a cancelled job's sealed passes (JobStatus.has_result);
  // FailedPrecondition without one.
  std::string result_exr(const CallContext& caller, const std::string& job_id);
  std::string result_exr(const std::string& job_id);
  // The finished job's image (decoded from its EXR).
  Film result_film(const std::string& job_id);
  // A job's image so far: the sealed pass blocks of every tile (tiles with none are black); an
  // ended job's stored result (black for a failed job). For previews; the pass count is
  // returned in `passes`.
  Film preview_film(const std::string& job_id, uint32_t* passes = nullptr);
  std::vector<v1::WorkerInfo> workers();
  // The workers that rendered or hold this job's tasks since this coordinator started, by id
  // (server/job_workers.h); the others do not appear.
  std::vector<JobWorkerActivity> job_workers(const std::string& job_id);
  // The job's reference EXR: the uploaded one, or the reference job's result once that job is
  // done; empty without a reference (or before the reference job is done).
  std::optional<std::string> reference_exr(const std::string& job_id);
  // The regions of the job's scene; empty when its scene is not loaded (a job that had ended
  // before this coordinator started).
  std::map<std::string, Region> regions(const std::string& job_id);
  CoordinatorCounters counters() const;

  // Calls `on_change` (from any thread, never under the coordinator's lock) whenever the job's
  // status may have changed. Returns an id for unsubscribe.
  uint64_t subscribe(const CallContext& caller, const std::string& job_id,
                     std::function<void()> on_change);
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

  // Requeues the tasks of dead workers and those whose leases expired, and forgets workers dead
  // for forget_worker_after (a background thread calls it every heartbeat / 4).
  void expire_leases();
  // The heartbeat period workers are told (heartbeat_interval, at most lease_time / 3) and the
  // silence after which a worker is dead.
  std::chrono::milliseconds heartbeat_period() const;
  std::chrono::milliseconds dead_after() const;
  // How often the background thread calls expire_leases.
  std::chrono::milliseconds expiry_period() const;

  static std::string job_name(uint64_t job_id);
  const CoordinatorOptions& options() const { return options_; }
  const SceneParser& scene_parser() const { return parser_; }
  // Scenes in chunks: clients' uploads, workers' fetches (server/scene_transfer.h).
  SceneTransfer& scene_transfer() { return transfer_; }
  // The scheduler group of a batch id ("batch-3" -> 3); 0 (no group) for anything else.
  static uint64_t batch_group(const std::string& batch_id);

 private:
  struct Job;
  struct Worker {
    std::string name;
    uint32_t threads = 0;
    std::string version, build_flavour;
    SteadyTime last_contact;
    bool dead = false;        // missed its heartbeats: its leases were revoked
    int calls_in_flight = 0;  // results being stored: the worker is in contact meanwhile
    uint64_t tasks_completed = 0;
    double compute_seconds = 0;
  };
  using Notifications = std::vector<std::function<void()>>;

  v1::SubmitJobResponse submit_spec(v1::JobSpec spec, bool awaits_pass_count = false,
                                    const CallContext& caller = CallContext::internal());
  uint64_t parse_job_id(const std::string& job_id) const;
  // NotFound for an unknown id and for a job the caller may not see (the same message).
  Job& job_locked(const std::string& job_id, const CallContext& caller = CallContext::internal());
  Worker& worker_locked(const std::string& worker_id);
  void resume(const JobRecord& record);
  void open_block(Job& job);
  void maybe_open_block(Job& job);
  void seal_ready_blocks(Job& job);
  void finish(Job& job);
  void cancel_locked(Job& job);
  // Passes every tile has (the sealed blocks').
  uint32_t sealed_passes(const Job& job) const;
  // The EXR of `film` (the job's sealed passes, `spp` of them) with the job's metadata and
  // `extra`.
  std::string encode_result(const Job& job, const Film& film, uint32_t spp,
                            const ImageMetadata& extra) const;
  // The errors of `film` against the job's reference, per region (none without a reference).
  void record_final_errors(Job& job, const Film& film);
  // A done job, or a cancelled one whose sealed passes were stored.
  static bool has_result(const Job& job);
  void end_job(Job& job, v1::JobState state, const std::string& error);
  void load_reference(Job& job);
  bool waits_for_pass_count(const Job& job) const;
  // The job's record as the store holds it: sealed blocks and their compute seconds up to the
  // last checkpoint.
  JobRecord durable_record(const Job& job) const;
  v1::JobStatus status_locked(const Job& job, bool with_curve) const;
  TileRect task_tile(const Job& job, uint64_t task_index) const;
  std::pair<uint32_t, uint32_t> task_passes(const Job& job, uint64_t task_index) const;
  void collect_notifications(uint64_t job_id, Notifications& out) const;
  static void run(const Notifications& notifications);
  void expiry_loop();

  CoordinatorOptions options_;
  SceneParser parser_;
  Store store_;
  SceneTransfer transfer_;
  mutable std::mutex mutex_;
  std::map<uint64_t, std::unique_ptr<Job>> jobs_;
  Scheduler scheduler_;
  LeaseTable leases_;
  std::map<std::string, Worker> workers_;
  uint64_t next_worker_ = 1;
  // When expire_leases last held the lock: a pass that comes much later than its period found a
  // coordinator that heard nobody meanwhile (stopped, or its lock held through a slow write).
  std::optional<SteadyTime> last_expiry_pass_;
  std::map<uint64_t, std::pair<uint64_t, std::function<void()>>> subscriptions_;
  std::function<void()> batch_listener_;
  uint64_t next_subscription_ = 1;
  CoordinatorCounters counters_;  // under mutex_; gauges filled in by counters()

  std::mutex expiry_mutex_;
  std::condition_variable expiry_wake_;
  bool stopping_ = false;
  std::thread expiry_thread_;
};

}  // namespace penumbra::farm
