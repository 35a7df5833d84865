// libFuzzer target: what a worker decodes off the wire before rendering (worker/task_decoding.h),
// the result tile the coordinator decodes (TileAccumulator::deserialize), and the scene manifests
// and chunks both check (proto/support/scene_chunks.h).
//
// Input layout: 1 flag byte, a 2-byte little-endian length n, n bytes of a serialized
// penumbra.v1.Task, then the bytes of a serialized tile. Flag bit 0 replaces the task's scene
// hash by the fixed scene's, so the fuzzer reaches the checks behind the hash without finding a
// SHA-256 preimage. Invariants: a decoded task's tile lies inside the image with a non-empty
// pass range; a tile that deserializes serializes back to the same bytes; a fresh tile of a
// decoded rect round-trips.
//
// Flag bit 1: the n bytes are a serialized penumbra.v1.SceneManifest and the rest a chunk of it;
// bit 2 replaces the manifest's first chunk hash by the chunk's SHA-256 (again: no preimage
// needed). Invariants: a manifest that passes the checks has chunks of positive size, at most
// chunk_bytes, summing to total_bytes; a chunk that passes has the listed size and hash; the
// checks throw SceneChunkError naming the field and nothing else.

#include <google/protobuf/stubs/logging.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/scene/scene_package.h"
#include "fuzz/fuzz_check.h"
#include "proto/support/scene_chunks.h"
#include "worker/task_decoding.h"

namespace {

// The scene the tasks refer to: 16 x 12 pixels, so decoded tiles are small.
const penumbra::Scene& fixed_scene() {
  static const penumbra::Scene scene = [] {
    penumbra::ScenePackage package;
    package.source = "task-fuzz.json";
    package.scene_json = R"({
      "format": "penumbra/scene@1",
      "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y_deg": 40,
                 "width": 16, "height": 12},
      "materials": {"matte": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
      "shapes": [{"type": "quad", "origin": [-2, 0, -2], "edge1": [4, 0, 0], "edge2": [0, 0, 4],
                  "material": "matte"}],
      "lights": [{"type": "quad", "origin": [-0.5, 2, -0.5], "edge1": [1, 0, 0],
                  "edge2": [0, 0, 1], "radiance": [4, 4, 4]}]
    })";
    return penumbra::parse_scene_package(package);
  }();
  return scene;
}

// Any bytes: a tile that deserializes serializes back to the same bytes, with finite means and
// variances. For a decoded task, a result that decode_result_tile accepts merges with itself
// (standing for the results of other tasks of the pixel) without overflow.
void check_tile_bytes(std::string_view bytes, const penumbra::farm::DecodedTask* task) {
  using penumbra::TileAccumulator;
  TileAccumulator tile;
  try {
    tile = TileAccumulator::deserialize(bytes);
  } catch (const std::invalid_argument&) {
    return;
  }
  FUZZ_CHECK(tile.rect().width() > 0 && tile.rect().height() > 0);
  FUZZ_CHECK(tile.serialize() == bytes);
  for (int64_t i = 0; i < tile.rect().pixel_count(); ++i) {
    FUZZ_CHECK(is_finite(tile.mean(i)));
    FUZZ_CHECK(is_finite(tile.variance_of_mean(i)));
  }
  if (!task) return;
  TileAccumulator accepted;
  try {
    accepted =
        penumbra::farm::decode_result_tile(bytes, task->tile, task->pass_end - task->pass_begin);
  } catch (const penumbra::farm::TaskDecodingError& error) {
    FUZZ_CHECK(std::string_view(error.what()).rfind("tile: ", 0) == 0);
    return;
  }
  FUZZ_CHECK(accepted == tile);
  TileAccumulator film(task->tile);
  for (int copy = 0; copy < 4; ++copy) film.merge(accepted);
  for (int64_t i = 0; i < film.rect().pixel_count(); ++i) FUZZ_CHECK(is_finite(film.mean(i)));
}

void check_manifest_bytes(std::string_view manifest_bytes, std::string_view chunk,
                          bool fix_first_hash) {
  using namespace penumbra::farm;
  penumbra::v1::SceneManifest manifest;
  if (!manifest.ParseFromArray(manifest_bytes.data(), int(manifest_bytes.size()))) return;
  if (fix_first_hash && manifest.chunk_hashes_size() > 0)
    manifest.set_chunk_hashes(0, penumbra::sha256_hex(chunk));
  const uint64_t limit = uint64_t(64) << 20;
  try {
    check_scene_manifest(manifest, limit);
  } catch (const SceneChunkError& error) {
    FUZZ_CHECK(std::string_view(error.what()).rfind("manifest.", 0) == 0);
    return;
  }
  FUZZ_CHECK(manifest.total_bytes() > 0 && manifest.total_bytes() <= limit);
  uint64_t total = 0;
  for (uint32_t i = 0; i < uint32_t(manifest.chunk_hashes_size()); ++i) {
    const uint32_t size = scene_chunk_size(manifest, i);
    FUZZ_CHECK(size > 0 && size <= manifest.chunk_bytes());
    total += size;
  }
  FUZZ_CHECK(total == manifest.total_bytes());
  for (uint32_t index :
       {0u, uint32_t(manifest.chunk_hashes_size() - 1), uint32_t(manifest.chunk_hashes_size())}) {
    try {
      check_scene_chunk(manifest, index, chunk);
    } catch (const SceneChunkError& error) {
      FUZZ_CHECK(std::string_view(error.what()).rfind("chunk", 0) == 0);
      continue;
    }
    FUZZ_CHECK(chunk.size() == scene_chunk_size(manifest, index));
    FUZZ_CHECK(penumbra::sha256_hex(chunk) == manifest.chunk_hashes(int(index)));
  }
  // A one-chunk manifest of exactly this chunk assembles to it.
  if (manifest.chunk_hashes_size() == 1) {
    try {
      std::string whole =
          assemble_scene_chunks(manifest, [&](uint32_t) { return std::string(chunk); });
      FUZZ_CHECK(whole == chunk);
    } catch (const SceneChunkError&) {
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  // Protobuf logs every invalid UTF-8 string it parses; the fuzzer makes thousands a second.
  static const bool quiet = (google::protobuf::SetLogHandler(nullptr), true);
  (void)quiet;
  if (size < 3) return 0;
  const bool use_scene_hash = data[0] & 1;
  size_t task_size = std::min<size_t>(size - 3, size_t(data[1]) | (size_t(data[2]) << 8));
  std::string_view task_bytes(reinterpret_cast<const char*>(data) + 3, task_size);
  std::string_view tile_bytes(reinterpret_cast<const char*>(data) + 3 + task_size,
                              size - 3 - task_size);

  if (data[0] & 2) {
    check_manifest_bytes(task_bytes, tile_bytes, data[0] & 4);
    return 0;
  }
  const Scene& scene = fixed_scene();
  v1::Task task;
  if (!task.ParseFromArray(task_bytes.data(), int(task_bytes.size()))) {
    check_tile_bytes(tile_bytes, nullptr);
    return 0;
  }
  if (use_scene_hash) task.set_scene_hash(scene.content_hash);
  farm::DecodedTask decoded;
  try {
    decoded = farm::decode_task(task, scene);
  } catch (const farm::TaskDecodingError& error) {
    FUZZ_CHECK(std::string_view(error.what()).rfind("task.", 0) == 0);
    check_tile_bytes(tile_bytes, nullptr);
    return 0;
  }
  const TileRect& rect = decoded.tile;
  FUZZ_CHECK(rect.x0 >= 0 && rect.y0 >= 0 && rect.x0 < rect.x1 && rect.y0 < rect.y1);
  FUZZ_CHECK(rect.x1 <= scene.camera.width && rect.y1 <= scene.camera.height);
  FUZZ_CHECK(decoded.pass_begin < decoded.pass_end);
  FUZZ_CHECK(to_string(decoded.method) == to_string(parse_method(decoded.options.method)));
  TileAccumulator fresh(rect);
  FUZZ_CHECK(TileAccumulator::deserialize(fresh.serialize()) == fresh);
  check_tile_bytes(tile_bytes, &decoded);
  return 0;
}
