#pragma once
// Triangulation of the analytic shapes of `penumbra/scene@1` (SCENE_FORMAT.md): quad, box and
// icosphere, plus OBJ meshes read from bytes. Each returns an indexed triangle mesh; the scene
// reader appends it to the scene's flat arrays.

#include <cstdint>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;  // 3 per triangle
  // Optional per-vertex shading normals and texture coordinates: empty, or one per position.
  std::vector<Vec3> normals;
  std::vector<Vec2> uvs;
  size_t triangle_count() const { return indices.size() / 3; }
};

// Appends `mesh` to the scene's flat arrays with one material for all its triangles, dropping
// triangles of exactly zero area (they occlude nothing and would only burden the ray and line
// queries); keeps Scene::normals and Scene::uvs parallel to the positions when the mesh or the
// scene has them, and Scene::triangle_shading saying which each triangle has. Returns the number of
// triangles dropped. Throws std::invalid_argument when a limit would be passed (triangles,
// coordinates, 32-bit vertex indices).
size_t append_mesh_to_scene(Scene& scene, const TriangleMesh& mesh, uint32_t material,
                            const SceneLimits& limits);

// The parallelogram origin + s*edge1 + t*edge2 as 2 triangles wound like cross(edge1, edge2).
TriangleMesh quad_mesh(const Vec3& origin, const Vec3& edge1, const Vec3& edge2);

// The axis-aligned box [min, max] as 12 triangles over 8 shared corners, wound so that every
// face normal points outwards; the mesh is closed (each edge belongs to exactly 2 triangles).
TriangleMesh box_mesh(const Vec3& min, const Vec3& max);

// Number of triangles and vertices of an icosphere with `subdivisions` levels: 20*4^s, 10*4^s+2.
size_t icosphere_triangle_count(int subdivisions);
size_t icosphere_vertex_count(int subdivisions);
// An icosahedron subdivided `subdivisions` times (each triangle into 4, the new vertices pushed
// onto the sphere), outward winding, every vertex on the sphere of `radius` about `center`.
TriangleMesh icosphere_mesh(const Vec3& center, double radius, int subdivisions);

// Parses Wavefront OBJ text (faces triangulated, `mtllib` ignored: no file is opened) and
// applies p' = scale * p + translate. Throws std::invalid_argument saying what is wrong (syntax
// error, index out of range, non-finite coordinate, no triangles).
TriangleMesh obj_mesh(const std::string& obj_bytes, const Vec3& scale, const Vec3& translate);

}  // namespace penumbra
