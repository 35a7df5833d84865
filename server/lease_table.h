#pragma once
// Leases of tasks to workers. Each lease carries an attempt token; a lease not extended within
// the lease time expires. Only the token of a task's current lease completes it, so a late
// result from an expired lease is recognised and dropped. Time is passed in, never read here.

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "server/scheduler.h"

namespace penumbra::farm {

using SteadyTime = std::chrono::steady_clock::time_point;

struct Lease {
  TaskRef task;
  std::string worker_id;
  std::string token;
  SteadyTime expiry;
};

class LeaseTable {
 public:
  explicit LeaseTable(std::chrono::milliseconds lease_time, uint64_t token_seed);

  std::chrono::milliseconds lease_time() const { return lease_time_; }
  // Grants a lease and returns its token.
  std::string grant(const TaskRef& task, const std::string& worker_id, SteadyTime now);
  // Extends the lease of `token` when it is held by `worker_id`; false when it is not current.
  bool extend(const std::string& token, const std::string& worker_id, SteadyTime now);
  // The current lease with this token, removed (completion or failure); empty when stale.
  std::optional<Lease> release(const std::string& token);
  const Lease* find(const std::string& token) const;
  // Removes and returns the leases whose expiry is before `now`.
  std::vector<Lease> expire(SteadyTime now);
  // Removes and returns the leases of a job (cancelled or failed).
  std::vector<Lease> release_job(uint64_t job_id);
  // Removes and returns the leases a worker holds (it is dead).
  std::vector<Lease> release_worker(const std::string& worker_id);
  size_t count_for_worker(const std::string& worker_id) const;
  size_t count_for_job(uint64_t job_id) const;
  // The leases of a job per worker id (workers that hold none are absent).
  std::map<std::string, size_t> counts_for_job(uint64_t job_id) const;
  size_t size() const { return leases_.size(); }

 private:
  std::chrono::milliseconds lease_time_;
  std::mt19937_64 random_;
  std::unordered_map<std::string, Lease> leases_;  // by token
};

}  // namespace penumbra::farm
