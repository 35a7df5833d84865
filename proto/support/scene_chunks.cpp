#include "proto/support/scene_chunks.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include <algorithm>

#include "core/scene/scene_package.h"

namespace penumbra::farm {

std::string serialize_package(const v1::ScenePackage& package) {
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    package.SerializeToCodedStream(&coded);
  }
  return bytes;
}

bool is_sha256_hex(std::string_view text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

v1::SceneManifest make_scene_manifest(const std::string& scene_hash, std::string_view bytes,
                                      uint32_t chunk_bytes) {
  v1::SceneManifest manifest;
  manifest.set_scene_hash(scene_hash);
  manifest.set_total_bytes(bytes.size());
  manifest.set_chunk_bytes(chunk_bytes);
  for (size_t offset = 0; offset < bytes.size(); offset += chunk_bytes)
    manifest.add_chunk_hashes(sha256_hex(bytes.substr(offset, chunk_bytes)));
  return manifest;
}

void check_scene_manifest(const v1::SceneManifest& manifest, uint64_t max_total_bytes) {
  if (!is_sha256_hex(manifest.scene_hash()))
    throw SceneChunkError("manifest.scene_hash: not a content hash (64 lowercase hex digits)");
  if (manifest.chunk_bytes() < kMinSceneChunkBytes || manifest.chunk_bytes() > kMaxSceneChunkBytes)
    throw SceneChunkError("manifest.chunk_bytes: " + std::to_string(manifest.chunk_bytes()) +
                          " is outside [" + std::to_string(kMinSceneChunkBytes) + ", " +
                          std::to_string(kMaxSceneChunkBytes) + "]");
  if (manifest.total_bytes() == 0) throw SceneChunkError("manifest.total_bytes: 0 (no package)");
  if (manifest.total_bytes() > max_total_bytes)
    throw SceneChunkError("manifest.total_bytes: " + std::to_string(manifest.total_bytes()) +
                          " exceeds " + std::to_string(max_total_bytes));
  const uint64_t chunks =
      (manifest.total_bytes() + manifest.chunk_bytes() - 1) / manifest.chunk_bytes();
  if (uint64_t(manifest.chunk_hashes_size()) != chunks)
    throw SceneChunkError("manifest.chunk_hashes: " + std::to_string(manifest.chunk_hashes_size()) +
                          " hashes for " + std::to_string(manifest.total_bytes()) +
                          " bytes in chunks of " + std::to_string(manifest.chunk_bytes()) +
                          " (expected " + std::to_string(chunks) + ")");
  for (int i = 0; i < manifest.chunk_hashes_size(); ++i)
    if (!is_sha256_hex(manifest.chunk_hashes(i)))
      throw SceneChunkError("manifest.chunk_hashes[" + std::to_string(i) +
                            "]: not a SHA-256 (64 lowercase hex digits)");
}

uint32_t scene_chunk_size(const v1::SceneManifest& manifest, uint32_t index) {
  const uint64_t begin = uint64_t(index) * manifest.chunk_bytes();
  return uint32_t(std::min<uint64_t>(manifest.chunk_bytes(), manifest.total_bytes() - begin));
}

void check_scene_chunk(const v1::SceneManifest& manifest, uint32_t index, std::string_view data) {
  if (index >= uint32_t(manifest.chunk_hashes_size()))
    throw SceneChunkError("chunk.index: " + std::to_string(index) + " is not below the " +
                          std::to_string(manifest.chunk_hashes_size()) + " chunks of the manifest");
  const std::string field = "chunk " + std::to_string(index);
  if (data.size() != scene_chunk_size(manifest, index))
    throw SceneChunkError(field + ": " + std::to_string(data.size()) +
                          " bytes, the manifest says " +
                          std::to_string(scene_chunk_size(manifest, index)));
  if (sha256_hex(data) != manifest.chunk_hashes(int(index)))
    throw SceneChunkError(field + ": its SHA-256 differs from the manifest's");
}

std::string assemble_scene_chunks(const v1::SceneManifest& manifest,
                                  const std::function<std::string(uint32_t index)>& chunk) {
  std::string bytes;
  bytes.reserve(manifest.total_bytes());
  for (uint32_t i = 0; i < uint32_t(manifest.chunk_hashes_size()); ++i) {
    std::string data = chunk(i);
    check_scene_chunk(manifest, i, data);
    bytes += data;
  }
  return bytes;
}

}  // namespace penumbra::farm
