#pragma once
// Which task a worker gets next: jobs by priority (higher first), first in first out within a
// priority; within a job, tasks in the order they were queued, with requeued tasks (expired or
// failed leases) first so the pass block they hold back is sealed early.
//
// Groups (a batch's jobs): jobs added with the same nonzero group share the queue position of
// the group's first job and are served round-robin, one task each in turn (the job served
// longest ago first), so that machine noise hits all of an equal-time comparison's methods
// alike.

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <tuple>

namespace penumbra::farm {

struct TaskRef {
  uint64_t job_id = 0;
  uint64_t task_index = 0;
  bool operator==(const TaskRef&) const = default;
};

class Scheduler {
 public:
  // `sequence` orders jobs of equal priority (submission order).
  void add_job(uint64_t job_id, int priority, uint64_t sequence, uint64_t group = 0);
  void remove_job(uint64_t job_id);
  bool has_job(uint64_t job_id) const { return jobs_.count(job_id) != 0; }

  void enqueue(const TaskRef& task);  // at the back of its job's queue
  void requeue(const TaskRef& task);  // at the front of its job's queue
  std::optional<TaskRef> next();      // removes and returns the next task to lease

  size_t queued(uint64_t job_id) const;
  size_t queued_total() const { return queued_total_; }

 private:
  // Ordered so that begin() is the job to serve first.
  struct JobKey {
    int priority;
    uint64_t sequence;
    uint64_t turn;  // grouped jobs: when the job was last served (0: never)
    uint64_t job_id;
    bool operator<(const JobKey& other) const {
      return std::tuple(-int64_t(priority), sequence, turn, job_id) <
             std::tuple(-int64_t(other.priority), other.sequence, other.turn, other.job_id);
    }
  };
  struct JobQueue {
    JobKey key;
    uint64_t group = 0;
    std::deque<uint64_t> tasks;
  };
  std::map<uint64_t, JobQueue> jobs_;
  std::map<uint64_t, uint64_t> group_sequences_;  // group -> the sequence of its first job
  uint64_t turns_ = 0;
  std::set<JobKey> ready_;  // jobs with at least one queued task
  size_t queued_total_ = 0;
};

}  // namespace penumbra::farm
