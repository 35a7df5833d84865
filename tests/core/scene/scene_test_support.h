#pragma once
// Helpers for the scene tests: a temporary folder that removes itself, and file writing.

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

namespace penumbra::testing {

class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("penumbra-scene-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // Writes `bytes` to `relative` (creating folders) and returns the full path.
  std::string write(const std::string& relative, const std::string& bytes) const {
    std::filesystem::path file = path_ / relative;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream out(file, std::ios::binary);
    out << bytes;
    return file.string();
  }

 private:
  std::filesystem::path path_;
};

// A closed tetrahedron with 4 triangles, as OBJ text.
inline std::string tetrahedron_obj() {
  return "# tetrahedron\n"
         "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
         "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
}

// The scene example of SCENE_FORMAT.md, verbatim.
inline const char* kFormatExample = R"json({
  "format": "penumbra/scene@1",
  "name": "cornell-occluders",
  "camera": { "position": [0,1,3.5], "look_at": [0,1,0], "up": [0,1,0],
              "fov_y_deg": 40, "width": 512, "height": 512 },
  "materials": {
    "white": { "type": "lambert", "albedo": [0.8,0.8,0.8] },
    "shiny": { "type": "phong", "kd": [0.1,0.1,0.1], "ks": [0.6,0.6,0.6], "exponent": 200 },
    "metal": { "type": "ggx", "diffuse": [0.05,0.05,0.05], "specular": [0.9,0.9,0.9], "roughness": 0.1 }
  },
  "shapes": [
    { "type": "quad", "origin": [-1,0,-1], "edge1": [2,0,0], "edge2": [0,0,2], "material": "white" },
    { "type": "box", "min": [-0.3,0.4,-0.3], "max": [0.3,0.45,0.3], "material": "white" },
    { "type": "sphere", "center": [0.5,0.3,0], "radius": 0.3, "subdivisions": 4, "material": "metal" },
    { "type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [0,1,2], "material": "white" },
    { "type": "obj", "file": "meshes/bunny.obj", "scale": 1, "translate": [0,0,0], "material": "white" }
  ],
  "lights": [
    { "type": "quad", "origin": [-0.25,1.98,-0.25], "edge1": [0.5,0,0], "edge2": [0,0,0.5],
      "radiance": [10,10,10] },
    { "type": "polygon", "vertices": [[0,2,0],[0.3,2,0.1],[0.2,2,0.4],[-0.1,2,0.3]], "radiance": [5,5,5] },
    { "type": "disk", "center": [0,1.98,0], "normal": [0,-1,0], "radius": 0.2, "radiance": [8,8,8] },
    { "type": "quad", "origin": [0,2,0], "edge1": [1,0,0], "edge2": [0,0,0.02], "radiance": [20,20,20],
      "profile": { "type": "gaussian", "sigma": 0.25 } }
  ],
  "regions": { "penumbra": [120,300,220,400], "glossy": [300,100,400,200] }
})json";

}  // namespace penumbra::testing
