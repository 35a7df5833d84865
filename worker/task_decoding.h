#pragma once
// What a worker checks in a leased task before it renders anything: a pure function of the
// task and its scene, so that a task the coordinator (or anything on the wire) got wrong fails
// with a message naming the field, instead of rendering out of the image, allocating a tile the
// size of the address space or looping for 2^32 passes. Fuzzed by fuzz/task_decoding_fuzz.cpp.

#include <stdexcept>
#include <string>
#include <string_view>

#include "core/method/method.h"
#include "core/render/renderer.h"
#include "core/render/tile.h"
#include "core/scene/scene.h"
#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

// A task that cannot be rendered; what() names the field ("task.tile: ...").
class TaskDecodingError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct DecodedTask {
  TileRect tile;
  uint32_t pass_begin = 0;
  uint32_t pass_end = 0;
  MethodSpec method;      // the parsed method (its text is in options.method)
  RenderOptions options;  // method text, sampler and seed, as the Renderer takes them (with
                          // `method` already parsed)
};

// A content hash as core computes it (scene_package.h): 64 lowercase hex digits. Cache files are
// named by it, so nothing else (no "../", no upper case, no other length) is accepted.
bool is_scene_content_hash(std::string_view text);

// What check_task_fields parsed: the method and the sampler (each parsed once per task).
struct TaskFields {
  MethodSpec method;
  Pattern sampler = Pattern::Stratified;
};

// The checks that need no scene: ids present, scene hash well formed, method and sampler known,
// tile not empty and not negative, pass range not empty. Throws TaskDecodingError.
TaskFields check_task_fields(const v1::Task& task);

// The checks against the task's scene, for fields check_task_fields returned for this task: its
// content hash matches and the tile lies inside the image. Throws TaskDecodingError.
DecodedTask decode_task(const v1::Task& task, TaskFields fields, const Scene& scene);
// check_task_fields, then the above.
DecodedTask decode_task(const v1::Task& task, const Scene& scene);

// A task's result tile as the coordinator should accept it: it deserializes (which refuses sums
// and sums of squares beyond what its counts' samples can reach, core/render/tile.h, so that
// merging the results of any number of tasks cannot overflow the 128-bit fixed-point sums), has
// the task's rect, and every pixel counts exactly `passes` samples. Throws TaskDecodingError
// ("tile: ...").
TileAccumulator decode_result_tile(std::string_view bytes, const TileRect& rect, uint32_t passes);

}  // namespace penumbra::farm
