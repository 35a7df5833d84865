#pragma once
// The coordinator's batches: an equal-time comparison of several methods on one
// scene (core/batch/batch_spec.h), run as jobs of the Coordinator. No gRPC here: the service
// (server/batch_service.h) translates calls; errors are FarmError and FormatError.
//
// A batch goes through three phases, driven by a background thread:
//   1. reference: "auto" renders the spec's reference settings as a job, cached by scene hash
//      and settings (persisted, so a restarted coordinator reuses it too); with "spp": "auto"
//      short probes of every method and of the reference method come first, and their noise per
//      sample sizes the reference (core/batch/reference_sizing.h); "job:<id>" waits for that
//      job; an uploaded EXR is ready at once.
//   2. calibration (when the spec has a seconds budget): every run is submitted, per method and
//      repeat an equal-time job and one job per spp level, all served round-robin on the same
//      workers (server/scheduler.h), every job against the reference (so the coordinator
//      records the MRSE curve at every pass boundary). An equal-time job calibrates itself: it
//      starts with a seconds budget of calibration_share of the method's budget, in small pass
//      blocks, and then waits (Coordinator::awaits_pass_count). Its compute seconds per pass
//      give the pass count that fills the budget, round(budget / cost); the job is first given
//      first_count_share of it (Coordinator::set_pass_count) and waits again, then gets its
//      final count from the cost over all its passes so far, so a calibration window that the
//      machine's load made slower or faster than the rest of the run does not miss the budget.
//      No pass is thrown away, the run's compute seconds include its calibration, and its image
//      is the one a job of its final spp and seed renders in one go.
//   3. runs: once every equal-time job is calibrated, until every job has ended.
// Spec-level-only batches skip 2. The manager moves a batch on when the coordinator reports
// that one of its jobs ended or waits for a pass count (Coordinator::set_batch_listener), and
// at least every `poll`.
// A method the estimator refuses for the scene is recorded with its error and never runs.
// Batches are persisted (server/batch_store.h) and resumed after a restart.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/batch/batch_spec.h"
#include "penumbra/v1/farm.pb.h"
#include "server/batch_store.h"
#include "server/coordinator.h"

namespace penumbra::farm {

struct BatchManagerOptions {
  std::string data_dir;  // the coordinator's; batches go in <data_dir>/batches
  // Each equal-time job's calibration renders for this share of its budget (compute seconds), in
  // blocks of calibration_passes_per_task passes (small: a block of a costly method on a large
  // image stays well within the share of a short budget).
  double calibration_share = 0.05;
  uint32_t calibration_passes_per_task = 4;
  // The share of the pass count the calibration asks for that an equal-time job is given first
  // (room for the cost per pass to grow by 1 / share - 1 before the budget is overrun).
  double first_count_share = 0.85;
  // Runs of a known pass count (and the rest of a calibrated run) go in blocks of about
  // passes / blocks_per_run passes (each block is a point of the MRSE curve), at least
  // calibration_passes_per_task (spp levels: 1) and at most max_passes_per_task: larger blocks
  // mean fewer results to send and store per pass.
  uint32_t blocks_per_run = 4;
  uint32_t max_passes_per_task = 64;
  std::chrono::milliseconds poll{100};
  BatchLimits limits;
  uint32_t max_spp = 1u << 20;  // of any job (the coordinator's limit)
  // A sized auto reference ("spp": "auto") is sized from probes of this many passes of every
  // method and of the reference method (their per-pixel variance per sample and, for the
  // reference, its cost per pass).
  uint32_t sizing_probe_spp = 8;
};

class BatchManager {
 public:
  // Loads the stored batches and starts driving the unfinished ones.
  BatchManager(Coordinator& coordinator, SceneParser parser, BatchManagerOptions options);
  ~BatchManager();
  BatchManager(const BatchManager&) = delete;
  BatchManager& operator=(const BatchManager&) = delete;

  // Every call acts for `caller` (server/call_context.h): a batch is owned by the client that
  // submitted it, and another owner's batch is NOT_FOUND like an unknown id.
  // Validates the spec against the scene (FormatError / FarmError InvalidArgument naming the
  // field; NotFound for an unknown reference job or one the caller may not see), stores the
  // batch and starts it.
  v1::SubmitBatchResponse submit(const v1::SubmitBatchRequest& request,
                                 const CallContext& caller = CallContext::internal());
  // NotFound for an unknown id. `with_curves`: the runs' jobs with their MRSE curves.
  v1::BatchStatus status(const std::string& batch_id, bool with_curves = true,
                         const CallContext& caller = CallContext::internal());
  std::vector<v1::BatchStatus> list(const CallContext& caller = CallContext::internal());
  // Cancels the batch's unfinished jobs (never a shared auto reference).
  v1::BatchStatus cancel(const std::string& batch_id,
                         const CallContext& caller = CallContext::internal());
  // The reference EXR (the reference job's result or the uploaded file); FailedPrecondition
  // while it is not rendered yet.
  std::string reference_exr(const std::string& batch_id,
                            const CallContext& caller = CallContext::internal());

  // A counter that grows whenever some batch may have changed; wait_for_change blocks until it
  // differs from `seen` or `timeout` passes, and returns its value.
  uint64_t version() const;
  uint64_t wait_for_change(uint64_t seen, std::chrono::milliseconds timeout);

  static bool is_terminal(v1::BatchState state);

 private:
  struct Batch {
    v1::StoredBatch stored;
    BatchSpec spec;
  };

  static std::string json_region_path(const std::string& name);
  Batch& batch_locked(const std::string& batch_id,
                      const CallContext& caller = CallContext::internal());
  void drive_loop();
  // Moves the batch on as far as its jobs allow; true when it changed (and was saved).
  bool advance(Batch& batch);
  bool advance_reference(Batch& batch);
  // A sized auto reference: submits the probes, then, once they have ended, sizes the reference
  // (its spp in the status). True when `changed` something; `sized` says whether it is done.
  bool advance_sizing(Batch& batch, bool& sized);
  bool advance_calibration(Batch& batch);
  bool advance_runs(Batch& batch);
  bool submit_runs(Batch& batch);
  bool drive_equal_time_runs(Batch& batch);
  bool next_pass_count(Batch& batch, v1::BatchMethodStatus& method, v1::BatchRun& run);
  v1::JobSpec run_spec(const Batch& batch, const v1::BatchMethodStatus& method, uint32_t repeat,
                       bool equal_time) const;
  uint32_t passes_per_task_for(uint32_t passes, uint32_t at_least) const;
  std::string submit_job(Batch& batch, v1::JobSpec spec, bool in_batch,
                         bool awaits_pass_count = false);
  void attach_reference(const Batch& batch, v1::JobSpec& spec) const;
  std::string reference_cache_key(const Batch& batch) const;
  void fail(Batch& batch, const std::string& error);
  void finish(Batch& batch, v1::BatchState state);
  void cancel_unknown_jobs(const Batch& batch);
  std::vector<std::string> job_ids(const Batch& batch) const;
  v1::BatchStatus status_locked(const Batch& batch, bool with_curves);
  void changed_locked();

  Coordinator& coordinator_;
  SceneParser parser_;
  BatchManagerOptions options_;
  BatchStore store_;
  mutable std::mutex mutex_;
  std::map<uint64_t, std::unique_ptr<Batch>> batches_;
  uint64_t next_number_ = 1;
  std::map<std::string, std::string> reference_cache_;
  uint64_t version_ = 0;
  std::condition_variable changed_;
  bool stopping_ = false;
  // Wakes the driver: a submission, the coordinator's batch listener, the destructor. Shared
  // with the listener, which may run after this manager is gone.
  struct Wakeup {
    std::mutex mutex;
    std::condition_variable condition;
    bool pending = false;
    void notify();
  };
  std::shared_ptr<Wakeup> wakeup_ = std::make_shared<Wakeup>();
  std::thread driver_;
};

}  // namespace penumbra::farm
