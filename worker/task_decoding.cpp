#include "worker/task_decoding.h"

#include <algorithm>
#include <optional>
#include <utility>

#include "core/sampling/pattern.h"

namespace penumbra::farm {

namespace {

[[noreturn]] void refuse(const std::string& field, const std::string& problem) {
  throw TaskDecodingError("task." + field + ": " + problem);
}

// Field values are quoted in messages, cut short and with control bytes escaped, because they
// come off the wire.
std::string quoted(std::string_view text) {
  constexpr size_t kMaxShown = 48;
  std::string out = "\"";
  for (size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c >= 0x7f || c == '"' || c == '\\') {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kMaxShown) out += "...";
  return out + "\"";
}

}  // namespace

bool is_scene_content_hash(std::string_view text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

TaskFields check_task_fields(const v1::Task& task) {
  if (task.job_id().empty()) refuse("job_id", "empty");
  if (task.attempt_token().empty()) refuse("attempt_token", "empty");
  if (!is_scene_content_hash(task.scene_hash()))
    refuse("scene_hash", quoted(task.scene_hash()) + " is not 64 lowercase hex digits");
  TaskFields fields;
  try {
    fields.method = parse_method(task.method());
  } catch (const FormatError& error) {
    refuse("method", error.what());
  }
  const std::optional<Pattern> sampler = parse_pattern(task.sampler());
  if (!sampler) refuse("sampler", "unknown sampler " + quoted(task.sampler()));
  fields.sampler = *sampler;
  if (!task.has_tile()) refuse("tile", "missing");
  const v1::TileRect& tile = task.tile();
  if (tile.x0() < 0 || tile.y0() < 0)
    refuse("tile", "negative corner (" + std::to_string(tile.x0()) + ", " +
                       std::to_string(tile.y0()) + ")");
  if (tile.x1() <= tile.x0() || tile.y1() <= tile.y0())
    refuse("tile", "empty rectangle [" + std::to_string(tile.x0()) + ", " +
                       std::to_string(tile.x1()) + ") x [" + std::to_string(tile.y0()) + ", " +
                       std::to_string(tile.y1()) + ")");
  if (task.pass_end() <= task.pass_begin())
    refuse("pass_end", "pass range [" + std::to_string(task.pass_begin()) + ", " +
                           std::to_string(task.pass_end()) + ") is empty");
  return fields;
}

DecodedTask decode_task(const v1::Task& task, const Scene& scene) {
  return decode_task(task, check_task_fields(task), scene);
}

DecodedTask decode_task(const v1::Task& task, TaskFields fields, const Scene& scene) {
  if (task.scene_hash() != scene.content_hash)
    refuse("scene_hash", quoted(task.scene_hash()) + " is not the hash of the scene given (" +
                             quoted(scene.content_hash) + ")");
  const v1::TileRect& tile = task.tile();
  const Camera& camera = scene.camera;
  if (tile.x1() > camera.width || tile.y1() > camera.height)
    refuse("tile", "rectangle [" + std::to_string(tile.x0()) + ", " + std::to_string(tile.x1()) +
                       ") x [" + std::to_string(tile.y0()) + ", " + std::to_string(tile.y1()) +
                       ") leaves the " + std::to_string(camera.width) + "x" +
                       std::to_string(camera.height) + " image");
  DecodedTask decoded;
  decoded.tile = {tile.x0(), tile.y0(), tile.x1(), tile.y1()};
  decoded.pass_begin = task.pass_begin();
  decoded.pass_end = task.pass_end();
  decoded.method = std::move(fields.method);
  decoded.options.method = task.method();
  decoded.options.sampler = fields.sampler;
  decoded.options.seed = task.seed();
  return decoded;
}

TileAccumulator decode_result_tile(std::string_view bytes, const TileRect& rect, uint32_t passes) {
  TileAccumulator tile;
  try {
    tile = TileAccumulator::deserialize(bytes);
  } catch (const std::invalid_argument& error) {
    throw TaskDecodingError(std::string("tile: ") + error.what());
  }
  if (!(tile.rect() == rect))
    throw TaskDecodingError("tile: the rectangle [" + std::to_string(tile.rect().x0) + ", " +
                            std::to_string(tile.rect().x1) + ") x [" +
                            std::to_string(tile.rect().y0) + ", " + std::to_string(tile.rect().y1) +
                            ") is not the task's");
  const int64_t pixels = rect.pixel_count();
  for (int64_t i = 0; i < pixels; ++i)
    if (tile.count(i) != passes)
      throw TaskDecodingError("tile: pixel " + std::to_string(i) + " has " +
                              std::to_string(tile.count(i)) + " samples, the task asked for " +
                              std::to_string(passes));
  return tile;
}

}  // namespace penumbra::farm
