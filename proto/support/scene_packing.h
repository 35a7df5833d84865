#pragma once
// Scene packages on the wire: core's ScenePackage (core/scene/scene_package.h) to and from
// penumbra.v1.ScenePackage, and parsing a wire package without touching the filesystem.

#include <string>

#include "core/scene/scene.h"
#include "core/scene/scene_package.h"
#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

v1::ScenePackage to_wire(const ScenePackage& package);
ScenePackage from_wire(const v1::ScenePackage& package);
// Reads a scene file and its OBJ files (client side). Throws FormatError.
v1::ScenePackage pack_scene_file(const std::string& path);
// Parses a wire package in memory. Throws FormatError.
Scene parse_wire_package(const v1::ScenePackage& package);

}  // namespace penumbra::farm
