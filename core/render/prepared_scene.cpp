#include "core/render/prepared_scene.h"

#include "core/materials/pbrt_material.h"

namespace penumbra {

namespace {

template <typename T>
size_t bytes_of(const std::vector<T>& values) {
  return values.capacity() * sizeof(T);
}

size_t scene_memory_bytes(const Scene& scene) {
  size_t bytes = sizeof(Scene) + bytes_of(scene.positions) + bytes_of(scene.indices) +
                 bytes_of(scene.triangle_materials) + bytes_of(scene.normals) +
                 bytes_of(scene.uvs) + bytes_of(scene.triangle_shading) +
                 bytes_of(scene.materials) + bytes_of(scene.textures) + bytes_of(scene.lights);
  for (const Texture& texture : scene.textures)
    if (texture.image) bytes += texture.image->size();
  return bytes;
}

}  // namespace

PreparedScene::PreparedScene(std::shared_ptr<const Scene> scene)
    : scene_(std::move(scene)), embree_(*scene_) {
  bool pbrt_materials = false;
  for (const Material& m : scene_->materials) {
    if (!is_pbrt_material(m.type)) continue;
    pbrt_materials = true;
    if (auto why = pbrt_material_unsupported(m)) throw FormatError("materials", *why);
  }
  if (pbrt_materials) textures_ = std::make_unique<SceneTextures>(*scene_);
  scene_bytes_ = scene_memory_bytes(*scene_);
}

const LineQuery& PreparedScene::line_query() const {
  std::call_once(line_query_once_, [this] {
    line_query_ = std::make_unique<LineQuery>(*scene_);
    line_query_bytes_ = line_query_->memory_bytes();
  });
  return *line_query_;
}

size_t PreparedScene::memory_bytes() const {
  return scene_bytes_ + embree_.memory_bytes() + line_query_bytes_.load();
}

}  // namespace penumbra
