#include "server/scheduler.h"

#include <stdexcept>
#include <string>

namespace penumbra::farm {

void Scheduler::add_job(uint64_t job_id, int priority, uint64_t sequence, uint64_t group) {
  if (jobs_.count(job_id)) return;
  JobQueue& queue = jobs_[job_id];
  if (group != 0) sequence = group_sequences_.emplace(group, sequence).first->second;
  queue.key = JobKey{priority, sequence, 0, job_id};
  queue.group = group;
}

void Scheduler::remove_job(uint64_t job_id) {
  auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return;
  queued_total_ -= it->second.tasks.size();
  ready_.erase(it->second.key);
  jobs_.erase(it);
}

void Scheduler::enqueue(const TaskRef& task) {
  auto it = jobs_.find(task.job_id);
  if (it == jobs_.end())
    throw std::logic_error("scheduler: task of unknown job " + std::to_string(task.job_id));
  it->second.tasks.push_back(task.task_index);
  ready_.insert(it->second.key);
  ++queued_total_;
}

void Scheduler::requeue(const TaskRef& task) {
  auto it = jobs_.find(task.job_id);
  if (it == jobs_.end()) return;  // the job ended meanwhile: nothing to redo
  it->second.tasks.push_front(task.task_index);
  ready_.insert(it->second.key);
  ++queued_total_;
}

std::optional<TaskRef> Scheduler::next() {
  if (ready_.empty()) return std::nullopt;
  JobQueue& queue = jobs_.at(ready_.begin()->job_id);
  TaskRef task{queue.key.job_id, queue.tasks.front()};
  queue.tasks.pop_front();
  --queued_total_;
  if (queue.group != 0) {
    // Round-robin within the group: this job goes behind its group's other jobs.
    ready_.erase(queue.key);
    queue.key.turn = ++turns_;
    if (!queue.tasks.empty()) ready_.insert(queue.key);
  } else if (queue.tasks.empty()) {
    ready_.erase(queue.key);
  }
  return task;
}

size_t Scheduler::queued(uint64_t job_id) const {
  auto it = jobs_.find(job_id);
  return it == jobs_.end() ? 0 : it->second.tasks.size();
}

}  // namespace penumbra::farm
