#pragma once
// Scenes in chunks (penumbra.v1.SceneManifest; proto/support/scene_chunks.h): the coordinator's
// side of a client's upload and of a worker's fetch.
//
// Upload: start() checks the manifest (its size against the scene-size limit first:
// RESOURCE_EXHAUSTED naming both) and answers which chunks the store lacks, by hash; the
// client's stream then delivers those, each checked against the manifest and stored at once, so
// a stream cut short keeps what it delivered. When every chunk is there, finish() assembles the
// package, parses it (INVALID_ARGUMENT for a scene that does not parse, or whose content hash is
// not the manifest's) and stores it as a scene, dropping its chunks. Chunks of uploads never
// finished are dropped after abandoned_after.
//
// Fetch: a stored scene's manifest (chunks of kSceneChunkBytes) and its chunks by index, served
// from the few packages fetched most recently, which are kept in memory.

#include <chrono>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "penumbra/v1/farm.pb.h"
#include "server/farm_error.h"
#include "server/store.h"

namespace penumbra::farm {

class SceneTransfer {
 public:
  using Parser = std::function<Scene(const v1::ScenePackage&)>;
  SceneTransfer(Store& store, Parser parser, size_t max_scene_bytes,
                std::chrono::hours abandoned_after = std::chrono::hours(24));

  // StartSceneUpload. Throws FarmError.
  v1::SceneUploadState start(const v1::SceneManifest& manifest);
  // The manifest of an upload stream: the checks of start(). Throws FarmError.
  void check_manifest(const v1::SceneManifest& manifest) const;
  // One chunk of a stream whose manifest passed check_manifest: checked, then stored unless the
  // store has it. True when it was stored. Throws FarmError (InvalidArgument).
  bool put_chunk(const v1::SceneManifest& manifest, const v1::SceneChunk& chunk);
  // The end of a stream: the scene assembled and stored once every chunk is there; otherwise
  // the chunks still missing. Throws FarmError.
  v1::SceneUploadState finish(const v1::SceneManifest& manifest, uint32_t chunks_stored);

  // Workers: a stored scene in chunks. NotFound for an unknown scene.
  v1::SceneManifest manifest(const std::string& scene_hash);
  v1::SceneChunk chunk(const std::string& scene_hash, uint32_t index);

  size_t max_scene_bytes() const { return max_scene_bytes_; }

 private:
  struct Served {
    std::string scene_hash;
    std::shared_ptr<const std::string> bytes;
    v1::SceneManifest manifest;
  };
  const Served& served_locked(const std::string& scene_hash);
  std::vector<uint32_t> missing_chunks(const v1::SceneManifest& manifest);

  Store& store_;
  Parser parser_;
  size_t max_scene_bytes_;
  std::chrono::hours abandoned_after_;
  std::mutex served_mutex_;
  std::list<Served> served_;  // most recently used first
};

}  // namespace penumbra::farm
