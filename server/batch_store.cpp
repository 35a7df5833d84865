#include "server/batch_store.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace penumbra::farm {

namespace {

constexpr const char* kCacheFile = "reference-cache.pb";

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in.good() && !in.eof()) throw std::runtime_error("cannot read " + path.string());
  return bytes.str();
}

}  // namespace

uint64_t parse_batch_number(const std::string& batch_id) {
  if (batch_id.rfind("batch-", 0) != 0) return 0;
  std::string digits = batch_id.substr(6);
  if (digits.empty() || digits.size() > 18 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return 0;
  return std::stoull(digits);
}

std::string batch_name(uint64_t number) {
  return "batch-" + std::to_string(number);
}

BatchStore::BatchStore(const std::string& data_dir)
    : folder_((std::filesystem::path(data_dir) / "batches").string()) {
  std::error_code error;
  std::filesystem::create_directories(folder_, error);
  if (error) throw std::runtime_error("cannot create " + folder_ + ": " + error.message());
}

std::vector<v1::StoredBatch> BatchStore::load_all() const {
  std::map<uint64_t, v1::StoredBatch> batches;
  for (const auto& entry : std::filesystem::directory_iterator(folder_)) {
    std::string file = entry.path().filename().string();
    if (entry.path().extension() != ".pb" || file == kCacheFile) continue;
    v1::StoredBatch batch;
    try {
      if (!batch.ParseFromString(read_file(entry.path())))
        throw std::runtime_error("not a stored batch");
    } catch (const std::exception& error) {
      spdlog::error("batch store: skipping {}: {}", entry.path().string(), error.what());
      continue;
    }
    uint64_t number = parse_batch_number(batch.status().batch_id());
    if (number == 0) {
      spdlog::error("batch store: skipping {}: no batch id", entry.path().string());
      continue;
    }
    batches[number] = std::move(batch);
  }
  std::vector<v1::StoredBatch> out;
  for (auto& [number, batch] : batches) out.push_back(std::move(batch));
  return out;
}

void BatchStore::save(const v1::StoredBatch& batch) const {
  write_atomically(batch.status().batch_id() + ".pb", batch.SerializeAsString());
}

std::map<std::string, std::string> BatchStore::reference_cache() const {
  std::filesystem::path path = std::filesystem::path(folder_) / kCacheFile;
  if (!std::filesystem::exists(path)) return {};
  v1::StoredReferenceCache cache;
  if (!cache.ParseFromString(read_file(path))) {
    spdlog::error("batch store: {} is unreadable; starting an empty reference cache",
                  path.string());
    return {};
  }
  return {cache.jobs().begin(), cache.jobs().end()};
}

void BatchStore::save_reference_cache(const std::map<std::string, std::string>& entries) const {
  v1::StoredReferenceCache cache;
  for (const auto& [key, job] : entries) (*cache.mutable_jobs())[key] = job;
  write_atomically(kCacheFile, cache.SerializeAsString());
}

void BatchStore::write_atomically(const std::string& name, const std::string& bytes) const {
  std::filesystem::path path = std::filesystem::path(folder_) / name;
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + temporary.string());
  }
  std::filesystem::rename(temporary, path);
}

}  // namespace penumbra::farm
