#include "server/scene_transfer.h"

#include <spdlog/spdlog.h>

#include <utility>

#include "proto/support/scene_chunks.h"

namespace penumbra::farm {

namespace {

// Packages kept in memory for workers' fetches: the scenes of the jobs running now, in practice.
constexpr size_t kServedPackages = 2;

int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

FarmError invalid(const std::string& message) {
  return FarmError(FarmErrorCode::InvalidArgument, message);
}

std::string mib(uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / double(1 << 20));
  return text;
}

}  // namespace

SceneTransfer::SceneTransfer(Store& store, Parser parser, size_t max_scene_bytes,
                             std::chrono::hours abandoned_after)
    : store_(store),
      parser_(std::move(parser)),
      max_scene_bytes_(max_scene_bytes),
      abandoned_after_(abandoned_after) {}

void SceneTransfer::check_manifest(const v1::SceneManifest& manifest) const {
  if (manifest.total_bytes() > max_scene_bytes_)
    throw FarmError(FarmErrorCode::ResourceExhausted,
                    "scene package of " + std::to_string(manifest.total_bytes()) + " bytes (" +
                        mib(manifest.total_bytes()) +
                        ") exceeds the coordinator's scene-size limit of " +
                        std::to_string(max_scene_bytes_) + " bytes (" + mib(max_scene_bytes_) +
                        ", penumbra-coordinator --max-scene-mib)");
  try {
    check_scene_manifest(manifest, max_scene_bytes_);
  } catch (const SceneChunkError& error) {
    throw invalid(error.what());
  }
}

std::vector<uint32_t> SceneTransfer::missing_chunks(const v1::SceneManifest& manifest) {
  std::vector<uint32_t> missing;
  for (int i = 0; i < manifest.chunk_hashes_size(); ++i)
    if (!store_.has_scene_chunk(manifest.chunk_hashes(i))) missing.push_back(uint32_t(i));
  return missing;
}

v1::SceneUploadState SceneTransfer::start(const v1::SceneManifest& manifest) {
  check_manifest(manifest);
  // Uploads abandoned long ago leave chunks nobody will finish; a new upload sweeps them.
  const int64_t cutoff =
      unix_ms_now() -
      std::chrono::duration_cast<std::chrono::milliseconds>(abandoned_after_).count();
  if (size_t dropped = store_.drop_scene_chunks_before(cutoff))
    spdlog::info("dropped {} chunk(s) of scene uploads abandoned for {} h", dropped,
                 abandoned_after_.count());
  v1::SceneUploadState state;
  state.set_scene_hash(manifest.scene_hash());
  if (store_.has_scene(manifest.scene_hash())) {
    state.set_complete(true);
    return state;
  }
  for (uint32_t index : missing_chunks(manifest)) state.add_missing_chunks(index);
  return state;
}

bool SceneTransfer::put_chunk(const v1::SceneManifest& manifest, const v1::SceneChunk& chunk) {
  try {
    check_scene_chunk(manifest, chunk.index(), chunk.data());
  } catch (const SceneChunkError& error) {
    throw invalid(error.what());
  }
  const std::string& hash = manifest.chunk_hashes(int(chunk.index()));
  if (store_.has_scene_chunk(hash)) return false;
  store_.put_scene_chunk(hash, chunk.data(), unix_ms_now());
  return true;
}

v1::SceneUploadState SceneTransfer::finish(const v1::SceneManifest& manifest,
                                           uint32_t chunks_stored) {
  v1::SceneUploadState state;
  state.set_scene_hash(manifest.scene_hash());
  state.set_chunks_stored(chunks_stored);
  if (store_.has_scene(manifest.scene_hash())) {
    state.set_complete(true);
    return state;
  }
  std::vector<uint32_t> missing = missing_chunks(manifest);
  if (!missing.empty()) {
    for (uint32_t index : missing) state.add_missing_chunks(index);
    return state;
  }
  std::string bytes;
  try {
    bytes = assemble_scene_chunks(manifest, [&](uint32_t index) {
      std::optional<std::string> data = store_.scene_chunk(manifest.chunk_hashes(int(index)));
      if (!data)
        throw FarmError(FarmErrorCode::Internal,
                        "chunk " + std::to_string(index) + " vanished from the store");
      return std::move(*data);
    });
  } catch (const SceneChunkError& error) {
    throw invalid(error.what());
  }
  v1::ScenePackage package;
  if (!package.ParseFromString(bytes))
    throw invalid("scene: the uploaded chunks do not form a scene package");
  Scene scene;
  try {
    scene = parser_(package);
  } catch (const FormatError& error) {
    throw invalid(std::string("scene: ") + error.what());
  }
  if (scene.content_hash != manifest.scene_hash())
    throw invalid("manifest.scene_hash: " + manifest.scene_hash() +
                  " is not the uploaded scene's content hash " + scene.content_hash);
  store_.put_scene_from_chunks(manifest.scene_hash(), bytes,
                               {manifest.chunk_hashes().begin(), manifest.chunk_hashes().end()});
  spdlog::info("scene {} ({}) uploaded: {} in {} chunk(s)", scene.name,
               manifest.scene_hash().substr(0, 12), mib(bytes.size()),
               manifest.chunk_hashes_size());
  state.set_complete(true);
  return state;
}

const SceneTransfer::Served& SceneTransfer::served_locked(const std::string& scene_hash) {
  for (auto it = served_.begin(); it != served_.end(); ++it)
    if (it->scene_hash == scene_hash) {
      served_.splice(served_.begin(), served_, it);
      return served_.front();
    }
  std::optional<std::string> stored = store_.scene(scene_hash);
  if (!stored) throw FarmError(FarmErrorCode::NotFound, "no scene " + scene_hash);
  Served served;
  served.scene_hash = scene_hash;
  served.bytes = std::make_shared<const std::string>(std::move(*stored));
  served.manifest = make_scene_manifest(scene_hash, *served.bytes);
  served_.push_front(std::move(served));
  while (served_.size() > kServedPackages) served_.pop_back();
  return served_.front();
}

v1::SceneManifest SceneTransfer::manifest(const std::string& scene_hash) {
  std::lock_guard lock(served_mutex_);
  return served_locked(scene_hash).manifest;
}

v1::SceneChunk SceneTransfer::chunk(const std::string& scene_hash, uint32_t index) {
  std::lock_guard lock(served_mutex_);
  const Served& served = served_locked(scene_hash);
  if (index >= uint32_t(served.manifest.chunk_hashes_size()))
    throw invalid("index: " + std::to_string(index) + " is not below the scene's " +
                  std::to_string(served.manifest.chunk_hashes_size()) + " chunks");
  v1::SceneChunk chunk;
  chunk.set_index(index);
  const size_t begin = size_t(index) * served.manifest.chunk_bytes();
  chunk.set_data(served.bytes->substr(begin, scene_chunk_size(served.manifest, index)));
  return chunk;
}

}  // namespace penumbra::farm
