#pragma once
// The coordinator's durable state in SQLite (WAL journal, synchronous=FULL): scenes by content
// hash, jobs, completed task results of passes not yet sealed, the sealed per-tile sums, the
// error-versus-time curve and result EXRs. Every write commits before it returns, so whatever a
// caller acknowledges after a write survives a crash of the process or the machine.
//
// A full disk: every write that fails for lack of space (SQLITE_FULL, ENOSPC) throws
// FarmError(ResourceExhausted, "disk full: ...") and leaves the database as it was (the
// transaction rolls back). So that running jobs can still finish when the disk fills, the store
// keeps a reserve file (data_dir/penumbra.reserve, StoreOptions::reserve_bytes): a write that
// records progress (task results, sealed blocks, finished jobs, job fields) and finds the disk
// full deletes the reserve and tries again once. New work (scenes, jobs) is refused with
// "disk full" while the data disk has less than StoreOptions::min_free_bytes free or the reserve
// cannot be made again; once space returns, the reserve is remade and new work is accepted.
//
// The store knows no protobuf and no gRPC: a job's specification is opaque bytes to it.

#include <sqlite3.h>

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "server/farm_error.h"

namespace penumbra::farm {

struct JobRecord {
  uint64_t id = 0;
  std::string spec;  // serialized penumbra.v1.JobSpec (scene by hash, never the package)
  int priority = 0;
  int state = 0;  // penumbra.v1.JobState
  std::string error;
  int64_t submitted_unix_ms = 0;
  int64_t started_unix_ms = 0;  // first lease; 0 before
  int64_t finished_unix_ms = 0;
  uint32_t blocks_opened = 0;  // pass blocks whose tasks exist
  uint32_t blocks_sealed = 0;  // pass blocks every tile has completed
  double compute_seconds = 0;  // stored: of the sealed blocks (task results hold the rest)
  std::string final_errors;    // serialized errors against the reference (opaque)
};

struct TaskResultRecord {
  uint64_t task_index = 0;
  std::string tile;  // serialized TileAccumulator
  double compute_seconds = 0;
};

struct CurvePoint {
  uint32_t passes = 0;
  double compute_seconds = 0;
  double wall_seconds = 0;
  double mrse = 0;                                      // the full image's
  std::vector<std::pair<std::string, double>> regions;  // (name, MRSE) of each region
};

struct StoreOptions {
  uint64_t reserve_bytes = uint64_t(8) << 20;   // space kept back for progress when the disk fills
  uint64_t min_free_bytes = uint64_t(1) << 20;  // new work needs this much free (plus its size)
};

class Store {
 public:
  // Opens (creating when needed) data_dir/penumbra.sqlite. Throws std::runtime_error naming the
  // file when it cannot.
  explicit Store(const std::string& data_dir, StoreOptions options = {});
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  void put_scene(const std::string& hash, const std::string& package);
  std::optional<std::string> scene(const std::string& hash);
  bool has_scene(const std::string& hash);

  // Chunks of scene uploads in progress, by their SHA-256 (server/scene_transfer.h): kept as they
  // arrive so an interrupted upload resumes; dropped when their scene is stored, or when older
  // than a cutoff (uploads abandoned).
  void put_scene_chunk(const std::string& hash, const std::string& data, int64_t unix_ms);
  bool has_scene_chunk(const std::string& hash);
  std::optional<std::string> scene_chunk(const std::string& hash);
  // Stores the scene and drops the chunks it was assembled from, in one transaction.
  void put_scene_from_chunks(const std::string& hash, const std::string& package,
                             const std::vector<std::string>& chunk_hashes);
  // Drops chunks added before `unix_ms`; returns how many.
  size_t drop_scene_chunks_before(int64_t unix_ms);

  // Inserts the job and returns its id (ids increase with submission order).
  uint64_t add_job(const JobRecord& job);
  // Writes the mutable fields (state, error, times, blocks, compute seconds, final errors).
  void update_job(const JobRecord& job);
  // Writes the job's specification and its mutable fields in one transaction (a batch run
  // given its pass count, server/coordinator.h set_pass_count).
  void update_job_spec(const JobRecord& job);
  std::vector<JobRecord> jobs();

  // Records a completed task durably. Concurrent callers are committed together in one
  // transaction (group commit): each call returns once its own record is on disk.
  void add_task_result(uint64_t job_id, const TaskResultRecord& result);
  std::vector<TaskResultRecord> task_results(uint64_t job_id);

  // Seals a pass block: replaces the job's tile sums with `tiles` (tile index -> serialized
  // accumulator), deletes the task results with index in [first_task, end_task), appends the
  // curve point when given, and writes the job's fields; one transaction.
  void seal_block(const JobRecord& job, const std::map<uint32_t, std::string>& tiles,
                  uint64_t first_task, uint64_t end_task, const std::optional<CurvePoint>& point);
  std::map<uint32_t, std::string> tiles(uint64_t job_id);
  std::vector<CurvePoint> curve(uint64_t job_id);

  // The finished job's EXR and its fields, in one transaction.
  void finish_job(const JobRecord& job, const std::string& exr);
  std::optional<std::string> result(uint64_t job_id);

  // Drops what a finished, failed or cancelled job no longer needs (tile sums, task results).
  void drop_work(const JobRecord& job);
  // A cancelled job: its specification, its fields, its result EXR when given (the sealed
  // passes) and drop_work, in one transaction.
  void cancel_job(const JobRecord& job, const std::optional<std::string>& exr);

  // True while the reserve file exists (false after a full disk used it up, until remade).
  bool has_reserve();

 private:
  class Statement;
  class Transaction;
  void execute(const char* sql);
  void write_job_fields(const JobRecord& job);
  void write_job_spec(const JobRecord& job);
  // Throws FarmError(ResourceExhausted, "disk full: ...") when the last failure of the
  // connection was a lack of space, std::runtime_error otherwise.
  [[noreturn]] void throw_error(int code, const std::string& context);
  // New work: refuses with "disk full" unless `bytes` more fit with room to spare and the
  // reserve exists (remaking it when space allows).
  void require_space_for_new_work(uint64_t bytes);
  // Progress: runs `write` (a whole transaction); on a full disk, spends the reserve and runs
  // it once more.
  template <typename Write>
  void write_progress(Write&& write);
  bool make_reserve();
  bool spend_reserve();

  struct QueuedResult {
    uint64_t job_id;
    TaskResultRecord result;
  };
  struct FailedBatch {
    uint64_t first_ticket, last_ticket;
    std::exception_ptr error;
  };

  std::mutex mutex_;  // the connection
  // Group commit of task results.
  std::mutex group_mutex_;
  std::condition_variable group_done_;
  std::vector<QueuedResult> group_queue_;
  uint64_t group_enqueued_ = 0, group_committed_ = 0;
  bool group_writing_ = false;
  std::vector<FailedBatch> group_failures_;
  sqlite3* db_ = nullptr;
  std::string path_;
  std::string data_dir_;
  std::string reserve_path_;
  StoreOptions options_;
  std::mutex reserve_mutex_;
};

}  // namespace penumbra::farm
