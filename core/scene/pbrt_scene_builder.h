#pragma once
// The meaning of pbrt-v3 statements: graphics state (transforms, attributes, named coordinate
// systems, materials, textures, area lights, object instances), shapes into the scene's flat
// triangle arrays, area lights into Penumbra lights, camera, film, sampler, pixel filter and the
// integrator's settings into the Scene. Produces the same `Scene` as the JSON reader
// (scene_parser.h). What the file uses that Penumbra does not model is refused with an error
// naming file:line:column, or, where its effect on direct lighting is nil or can be named,
// accepted with a warning in Scene::warnings. The support table is in the README.

#include <string>

#include "core/scene/scene_parser.h"

namespace penumbra {

// True when `text` looks like a pbrt file rather than a JSON scene (its first non-blank,
// non-comment character is not '{').
bool looks_like_pbrt(const std::string& text);

// Parses a pbrt-v3 scene whose main file is `text` (named `source` in messages). Every file it
// names (Include, PLY meshes, image textures) comes through `read_file` by its normalized path
// relative to the main file's folder, and enters ParsedScene::obj_files and the content hash in
// order of first appearance. Throws FormatError.
ParsedScene parse_pbrt_scene(const std::string& text, const ObjFileReader& read_file,
                             const std::string& source, const SceneLimits& limits);

}  // namespace penumbra
