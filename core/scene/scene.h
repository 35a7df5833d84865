#pragma once
// A loaded `penumbra/scene@1` (../shared/design/SCENE_FORMAT.md): flat triangle arrays for the
// occluders, materials, lights, camera and regions. Every shape is triangulated at load time;
// lights are kept analytic (they never occlude and are not in the triangle arrays).

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/math/vec.h"

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

struct Camera {
  Vec3 position{0, 0, 0};
  Vec3 look_at{0, 0, -1};
  Vec3 up{0, 1, 0};
  double fov_y_deg = 40;
  int width = 256;
  int height = 256;
};

enum class MaterialType { Lambert, Phong, Ggx };

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
};

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
  std::vector<Light> lights;
  std::map<std::string, Region> regions;
  // Unknown optional keys the reader ignored (forward compatibility), each as "JSON path: note".
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
