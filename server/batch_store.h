#pragma once
// Persistence of the coordinator's batches: one file per batch (a serialized v1::StoredBatch)
// and one file for the auto-reference cache, in <data_dir>/batches/. Every write goes to a
// temporary file that is then renamed, so a crash leaves the previous version or the new one.
// The coordinator's jobs live in its own SQLite store (server/store.h); a batch refers to them
// by id.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

class BatchStore {
 public:
  // Creates <data_dir>/batches when missing. Throws std::runtime_error when it cannot.
  explicit BatchStore(const std::string& data_dir);

  // Every stored batch, by id (unreadable files are skipped with a logged error).
  std::vector<v1::StoredBatch> load_all() const;
  void save(const v1::StoredBatch& batch) const;

  std::map<std::string, std::string> reference_cache() const;
  void save_reference_cache(const std::map<std::string, std::string>& cache) const;

  const std::string& folder() const { return folder_; }

 private:
  void write_atomically(const std::string& name, const std::string& bytes) const;
  std::string folder_;
};

// "batch-3" -> 3; 0 when the text is not a batch id.
uint64_t parse_batch_number(const std::string& batch_id);
std::string batch_name(uint64_t number);

}  // namespace penumbra::farm
