#pragma once
// pbrt-v3 materials and textures onto the material data model (core/scene/material_model.h):
// each parameter a constant or a texture of Scene::textures, pbrt-v3's defaults for what a file
// leaves out (pbrt_material_defaults). What the model has no place for is refused naming
// file:line:column.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/scene/pbrt_params.h"
#include "core/scene/scene.h"

namespace penumbra {

// Texture names in scope -> indices of Scene::textures, by kind (pbrt-v3 keeps float and
// spectrum textures apart); -1 when the name is not defined.
struct PbrtTextureScope {
  std::function<int(const std::string&)> float_texture, spectrum_texture;
};

// A Material from a Material or MakeNamedMaterial statement of pbrt-v3 type `type`. A matte
// with a constant Kd and no roughness or bump map is Penumbra's exact Lambert BSDF (albedo Kd).
Material material_from_pbrt(const std::string& name, const std::string& type, PbrtParams& params,
                            const PbrtTextureScope& scope, std::vector<std::string>& warnings);

// pbrt-v3's default material (matte, Kd 0.5) as the Lambert BSDF.
Material pbrt_default_material();

// A Texture from a Texture statement; image files come through `read_image` (normalized path
// relative to the scene's folder -> shared bytes).
Texture texture_from_pbrt(PbrtParams& params, const PbrtTextureScope& scope,
                          const std::function<std::shared_ptr<const std::string>(
                              const PbrtParameter& where, const std::string& name)>& read_image);

}  // namespace penumbra
