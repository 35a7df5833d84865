#pragma once
// A loaded `penumbra/scene@1` (../shared/design/SCENE_FORMAT.md): flat triangle arrays for the
// occluders, materials, lights, camera and regions. Every shape is triangulated at load time;
// lights are kept analytic (they never occlude and are not in the triangle arrays).

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/material_model.h"

namespace penumbra {

// A scene, method, probe or batch that cannot be used. `what()` names the file, the JSON path
// (e.g. "$.lights[2].radius") and the bad value.
class FormatError : public std::runtime_error {
 public:
  FormatError(const std::string& json_path, const std::string& message)
      : std::runtime_error(json_path.empty() ? message : json_path + ": " + message),
        json_path_(json_path) {}
  const std::string& json_path() const { return json_path_; }

 private:
  std::string json_path_;
};

// The pixel filter, importance sampled: each camera sample is offset from the pixel centre by a
// draw from the filter (filter importance sampling), so a pixel's estimate depends on its own
// samples only and tiles stay independent. The default, a box of radius 0.5, is a uniform
// jitter over the pixel.
enum class PixelFilterType { Box, Triangle, Gaussian };
struct PixelFilter {
  PixelFilterType type = PixelFilterType::Box;
  double radius_x = 0.5, radius_y = 0.5;  // in pixels (pbrt-v3's xwidth, ywidth)
  double alpha = 2;                       // gaussian: exp(-alpha x^2) - exp(-alpha r^2)
  bool operator==(const PixelFilter&) const = default;
};

struct Camera {
  Vec3 position{0, 0, 0};
  Vec3 look_at{0, 0, -1};
  Vec3 up{0, 1, 0};
  double fov_y_deg = 40;
  int width = 256;
  int height = 256;
  // pbrt-v3 cameras. Image x runs along cross(forward, up) unless `mirror_x` (a camera whose
  // transform swaps handedness, as pbrt's LookAt does). A screen window [x0, x1] x [y0, y1] in
  // units of tan(fov_y/2) replaces the default [-aspect, aspect] x [-1, 1] when set. A crop
  // renders pixels [crop_x, crop_x + width) x [crop_y, crop_y + height) of a full_width x
  // full_height frame (full_width 0: no crop).
  bool mirror_x = false;
  bool has_screen_window = false;
  double screen_x0 = -1, screen_x1 = 1, screen_y0 = -1, screen_y1 = 1;
  int crop_x = 0, crop_y = 0, full_width = 0, full_height = 0;
  PixelFilter filter;
};

// lambert, phong, ggx: the JSON materials of SCENE_FORMAT.md (their fields below). The others are
// pbrt-v3's materials, with their parameters in `params` (core/scene/material_model.h).
enum class MaterialType {
  Lambert,
  Phong,
  Ggx,
  Matte,
  Plastic,
  Substrate,
  Metal,
  Mirror,
  Glass,
  Uber
};

struct Material {
  std::string name;
  MaterialType type = MaterialType::Lambert;
  Rgb albedo{0.8, 0.8, 0.8};  // lambert
  Rgb kd{0, 0, 0};            // phong diffuse
  Rgb ks{0, 0, 0};            // phong specular
  double exponent = 1;        // phong
  Rgb diffuse{0, 0, 0};       // ggx
  Rgb specular{0, 0, 0};      // ggx F0
  double roughness = 0.5;     // ggx alpha
  MaterialParams params;      // the pbrt-v3 materials
};

// A material of a pbrt-v3 type with pbrt-v3's default parameters (metal: no default eta and k,
// which pbrt-v3 gives as a measured copper spectrum; a reader must set them).
Material pbrt_material_defaults(MaterialType type);

enum class LightType { Quad, Polygon, Disk };
enum class ProfileType { Constant, Gaussian };

struct Light {
  LightType type = LightType::Quad;
  Rgb radiance{1, 1, 1};
  ProfileType profile = ProfileType::Constant;
  double sigma = 0.25;  // gaussian profile, as a fraction of the half-extent
  // Quad: origin + s*edge1 + t*edge2. Polygon: `vertices` (convex, planar, counter-clockwise
  // seen from the emitting side). Quads also fill `vertices` with their 4 corners, in order
  // origin, origin+edge1, origin+edge1+edge2, origin+edge2.
  Vec3 origin, edge1, edge2;
  std::vector<Vec3> vertices;
  // Disk.
  Vec3 center;
  double radius = 0;
  // Derived at load: unit emission normal, area, centroid (disk: its centre).
  Vec3 normal{0, 0, 1};
  double area = 0;
  Vec3 centroid;
};

// Render settings a scene file states (pbrt-v3's Integrator, Sampler and Film): what `render`,
// `submit` and batches use when the command line or spec gives none. (pbrt-v3's maxdepth is
// Scene::max_depth.)
struct SceneRenderDefaults {
  std::string method;   // penumbra/method@1 text; empty: none stated
  std::string sampler;  // a pattern name (core/sampling/pattern.h); empty: none stated
  uint32_t spp = 0;     // samples per pixel; 0: none stated
  double seconds = 0;   // compute seconds (pbrt "max-seconds"); 0: none stated
};

inline constexpr uint8_t kTriangleHasNormals = 1;
inline constexpr uint8_t kTriangleHasUvs = 2;

struct Region {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixel rectangle [x0,x1) x [y0,y1), origin top-left
};

struct Scene {
  std::string name;
  std::string description;
  // SHA-256 (hex) of the canonical scene: the JSON text and every OBJ file it references.
  std::string content_hash;
  Camera camera;
  std::vector<Material> materials;
  // Occluder triangles: 3 indices each into `positions`; one material index per triangle.
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> triangle_materials;
  // Per-vertex shading data, parallel to `positions` when not empty: unit shading normals and
  // (u, v) texture coordinates. Per triangle, `triangle_shading` says which of them it has
  // (kTriangleHasNormals | kTriangleHasUvs; empty: no triangle has either). A triangle without
  // uvs has pbrt-v3's (0,0), (1,0), (1,1) at its three corners; without normals it is flat.
  // Orientation (which side is outside, for dielectrics): where a triangle has normals, the side
  // of its interpolated normal; elsewhere normalize(cross(p1 - p0, p2 - p0)) (a reader bakes
  // pbrt-v3's ReverseOrientation and handedness flips into the winding).
  std::vector<Vec3> normals;
  std::vector<Vec2> uvs;
  std::vector<uint8_t> triangle_shading;
  // The textures the materials' parameters refer to (core/scene/material_model.h).
  std::vector<Texture> textures;
  // Specular chains (pbrt-v3's DirectLightingIntegrator): a hit at depth d (the camera ray's hit
  // is depth 0) follows its delta reflection and transmission lobes when d + 1 < max_depth.
  int max_depth = 5;
  // Texture filtering footprint: the camera ray's differentials (one pixel apart) times this
  // factor (pbrt-v3 scales them by 1 / sqrt(samples per pixel) of the file's sampler).
  double texture_footprint_scale = 1;
  std::vector<Light> lights;
  std::map<std::string, Region> regions;
  // The render settings a pbrt-v3 file states.
  SceneRenderDefaults render_defaults;
  // What the reader ignored or approximated, each as "where: note" (JSON path or
  // file:line:column); printed once and listed in the output EXR's metadata.
  std::vector<std::string> warnings;

  size_t triangle_count() const { return indices.size() / 3; }
};

// Limits past which a scene is refused as absurd (the error says which limit).
struct SceneLimits {
  int max_resolution = 16384;  // per image side
  size_t max_triangles = 20'000'000;
  size_t max_lights = 4096;
  int max_sphere_subdivisions = 8;
  double max_coordinate = 1e7;               // absolute value of any coordinate
  size_t max_polygon_vertices = 1024;        // per polygon light
  size_t max_json_bytes = size_t{64} << 20;  // the scene JSON text (big meshes go in OBJ files)
  size_t max_file_bytes = size_t{1} << 30;   // each OBJ file
  int max_json_depth = 64;                   // nesting of JSON arrays and objects
};

// Related headers: scene_package.h (scene and OBJ bytes in memory, for the farm, and the content
// hash's canonical form), light_setup.h (build lights with their derived fields in code).

// Parses a scene from JSON text. `base_dir` resolves OBJ paths (which may not leave it).
// `source` names the file in error messages. Throws FormatError.
Scene parse_scene(const std::string& json_text, const std::string& base_dir,
                  const std::string& source = "<scene>", const SceneLimits& limits = {});
// Reads and parses a scene file. Throws FormatError (unreadable file included).
Scene load_scene(const std::string& path, const SceneLimits& limits = {});

}  // namespace penumbra
