#pragma once
// A worker's share of one job: the workers table of the job's page (server/status_pages.h),
// filled in by Coordinator::job_workers.

#include <cstdint>
#include <string>

namespace penumbra::farm {

// Counts since this coordinator started (a restart begins them again).
struct JobWorkerActivity {
  std::string worker_id;
  std::string name;         // empty once the worker was forgotten (dead for a long time)
  bool registered = false;  // still in the coordinator's worker list
  bool alive = false;
  uint32_t threads = 0;
  uint32_t tasks_leased = 0;     // this job's tasks the worker holds now
  uint64_t tasks_completed = 0;  // this job's tasks it completed (results accepted)
  double compute_seconds = 0;    // their render seconds (summed over its threads)
  // This job's completions by the worker over the last kJobWorkerRateWindowSeconds (or, when it has
  // been on the job for less, over that time, at least a second), per second.
  double recent_tasks_per_second = 0;
};

inline constexpr int kJobWorkerRateWindowSeconds = 60;

}  // namespace penumbra::farm
