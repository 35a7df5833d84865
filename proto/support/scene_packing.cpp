#include "proto/support/scene_packing.h"

namespace penumbra::farm {

v1::ScenePackage to_wire(const ScenePackage& package) {
  v1::ScenePackage wire;
  wire.set_scene_json(package.scene_json);
  wire.set_source_name(package.source);
  for (const auto& [path, bytes] : package.files) (*wire.mutable_files())[path] = bytes;
  return wire;
}

ScenePackage from_wire(const v1::ScenePackage& wire) {
  ScenePackage package;
  package.source = wire.source_name().empty() ? "<uploaded scene>" : wire.source_name();
  package.scene_json = wire.scene_json();
  for (const auto& [path, bytes] : wire.files()) package.files[path] = bytes;
  return package;
}

v1::ScenePackage pack_scene_file(const std::string& path) {
  return to_wire(collect_scene_package(path));
}

Scene parse_wire_package(const v1::ScenePackage& package) {
  return parse_scene_package(from_wire(package));
}

}  // namespace penumbra::farm
