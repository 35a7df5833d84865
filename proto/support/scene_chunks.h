#pragma once
// Scene packages in chunks (penumbra.v1.SceneManifest, SceneChunk): what the client uploads, the
// coordinator checks and stores, and workers fetch. A package's bytes are its deterministic
// serialization (same package, same bytes, same chunk hashes: a re-run upload finds the chunks
// the coordinator already has). Chunks are named by their SHA-256, so the coordinator can keep
// them as they arrive and a worker can check each one it receives.
//
// Every check throws SceneChunkError naming the field ("manifest.chunk_hashes[3]: ..."), so the
// coordinator can answer INVALID_ARGUMENT with it and a worker can log it.

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

class SceneChunkError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

inline constexpr uint32_t kSceneChunkBytes = uint32_t(1) << 20;  // what clients and workers use
inline constexpr uint32_t kMinSceneChunkBytes = uint32_t(4) << 10;
inline constexpr uint32_t kMaxSceneChunkBytes = uint32_t(2) << 20;

// The package's bytes as they are chunked and stored (deterministic map order).
std::string serialize_package(const v1::ScenePackage& package);

// True for 64 lowercase hex digits (a SHA-256 as core and the farm write it).
bool is_sha256_hex(std::string_view text);

// The manifest of `bytes` cut into chunks of `chunk_bytes` (the last one shorter).
v1::SceneManifest make_scene_manifest(const std::string& scene_hash, std::string_view bytes,
                                      uint32_t chunk_bytes = kSceneChunkBytes);

// Checks a manifest's shape: a content hash, chunk_bytes within [kMin, kMax]SceneChunkBytes, a
// positive total of at most `max_total_bytes`, exactly ceil(total / chunk_bytes) chunk hashes,
// each a SHA-256 hex. Throws SceneChunkError.
void check_scene_manifest(const v1::SceneManifest& manifest, uint64_t max_total_bytes);

// The size chunk `index` of a checked manifest must have.
uint32_t scene_chunk_size(const v1::SceneManifest& manifest, uint32_t index);

// Checks a chunk against a checked manifest: index in range, size as scene_chunk_size, SHA-256
// as listed. Throws SceneChunkError.
void check_scene_chunk(const v1::SceneManifest& manifest, uint32_t index, std::string_view data);

// The package's bytes from its chunks (`chunk(i)` returns chunk i's bytes; each is checked).
// Throws SceneChunkError.
std::string assemble_scene_chunks(const v1::SceneManifest& manifest,
                                  const std::function<std::string(uint32_t index)>& chunk);

}  // namespace penumbra::farm
