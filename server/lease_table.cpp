#include "server/lease_table.h"

#include <cstdio>

namespace penumbra::farm {

LeaseTable::LeaseTable(std::chrono::milliseconds lease_time, uint64_t token_seed)
    : lease_time_(lease_time), random_(token_seed) {}

std::string LeaseTable::grant(const TaskRef& task, const std::string& worker_id, SteadyTime now) {
  std::string token;
  do {
    char text[40];
    std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(random_()),
                  static_cast<unsigned long long>(random_()));
    token = text;
  } while (leases_.count(token));
  leases_[token] = Lease{task, worker_id, token, now + lease_time_};
  return token;
}

bool LeaseTable::extend(const std::string& token, const std::string& worker_id, SteadyTime now) {
  auto it = leases_.find(token);
  if (it == leases_.end() || it->second.worker_id != worker_id) return false;
  it->second.expiry = now + lease_time_;
  return true;
}

std::optional<Lease> LeaseTable::release(const std::string& token) {
  auto it = leases_.find(token);
  if (it == leases_.end()) return std::nullopt;
  Lease lease = std::move(it->second);
  leases_.erase(it);
  return lease;
}

const Lease* LeaseTable::find(const std::string& token) const {
  auto it = leases_.find(token);
  return it == leases_.end() ? nullptr : &it->second;
}

std::vector<Lease> LeaseTable::expire(SteadyTime now) {
  std::vector<Lease> expired;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.expiry < now) {
      expired.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  return expired;
}

std::vector<Lease> LeaseTable::release_job(uint64_t job_id) {
  std::vector<Lease> released;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.task.job_id == job_id) {
      released.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  return released;
}

std::vector<Lease> LeaseTable::release_worker(const std::string& worker_id) {
  std::vector<Lease> released;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.worker_id == worker_id) {
      released.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  return released;
}

size_t LeaseTable::count_for_worker(const std::string& worker_id) const {
  size_t count = 0;
  for (const auto& [token, lease] : leases_) count += lease.worker_id == worker_id;
  return count;
}

size_t LeaseTable::count_for_job(uint64_t job_id) const {
  size_t count = 0;
  for (const auto& [token, lease] : leases_) count += lease.task.job_id == job_id;
  return count;
}

std::map<std::string, size_t> LeaseTable::counts_for_job(uint64_t job_id) const {
  std::map<std::string, size_t> counts;
  for (const auto& [token, lease] : leases_)
    if (lease.task.job_id == job_id) ++counts[lease.worker_id];
  return counts;
}

}  // namespace penumbra::farm
