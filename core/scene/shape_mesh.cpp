#include "core/scene/shape_mesh.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace penumbra {

size_t append_mesh_to_scene(Scene& scene, const TriangleMesh& mesh, uint32_t material,
                            const SceneLimits& limits) {
  size_t have = scene.triangle_count(), more = mesh.triangle_count();
  if (more > limits.max_triangles || have > limits.max_triangles - more)
    throw std::invalid_argument(
        "too many triangles: this shape adds " + std::to_string(more) + " to " +
        std::to_string(have) +
        ", past the limit max_triangles = " + std::to_string(limits.max_triangles));
  for (const Vec3& p : mesh.positions)
    for (int axis = 0; axis < 3; ++axis)
      if (!(std::abs(p[axis]) <= limits.max_coordinate)) {
        std::ostringstream out;
        out.precision(12);
        out << "a vertex coordinate " << p[axis]
            << " exceeds the limit max_coordinate = " << limits.max_coordinate;
        throw std::invalid_argument(out.str());
      }
  if (scene.positions.size() + mesh.positions.size() > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("too many vertices for 32-bit indices");
  const auto base = static_cast<uint32_t>(scene.positions.size());
  // Shading normals and uvs stay parallel to the positions once any mesh has them.
  const bool keep_normals = !mesh.normals.empty() || !scene.normals.empty();
  const bool keep_uvs = !mesh.uvs.empty() || !scene.uvs.empty();
  if (keep_normals) scene.normals.resize(base);
  if (keep_uvs) scene.uvs.resize(base);
  scene.positions.insert(scene.positions.end(), mesh.positions.begin(), mesh.positions.end());
  if (keep_normals) {
    if (mesh.normals.empty())
      scene.normals.resize(scene.positions.size());
    else
      scene.normals.insert(scene.normals.end(), mesh.normals.begin(), mesh.normals.end());
  }
  if (keep_uvs) {
    if (mesh.uvs.empty())
      scene.uvs.resize(scene.positions.size());
    else
      scene.uvs.insert(scene.uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
  }
  // Grow geometrically: scenes of many meshes append hundreds of times.
  auto make_room = [](auto& array, size_t extra) {
    if (array.capacity() < array.size() + extra)
      array.reserve(std::max(array.size() + extra, 2 * array.capacity()));
  };
  make_room(scene.indices, mesh.indices.size());
  make_room(scene.triangle_materials, more);
  // Which per-vertex data each triangle has (Scene::triangle_shading), once any mesh has some.
  const uint8_t shading =
      (mesh.normals.empty() ? 0 : kTriangleHasNormals) | (mesh.uvs.empty() ? 0 : kTriangleHasUvs);
  const bool keep_shading = shading != 0 || !scene.triangle_shading.empty();
  if (keep_shading) {
    scene.triangle_shading.resize(scene.triangle_count());
    make_room(scene.triangle_shading, more);
  }
  size_t dropped = 0;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.indices[t]];
    const Vec3& b = mesh.positions[mesh.indices[t + 1]];
    const Vec3& c = mesh.positions[mesh.indices[t + 2]];
    if (length_squared(cross(b - a, c - a)) == 0) {
      ++dropped;
      continue;
    }
    scene.indices.push_back(base + mesh.indices[t]);
    scene.indices.push_back(base + mesh.indices[t + 1]);
    scene.indices.push_back(base + mesh.indices[t + 2]);
    scene.triangle_materials.push_back(material);
    if (keep_shading) scene.triangle_shading.push_back(shading);
  }
  return dropped;
}

TriangleMesh quad_mesh(const Vec3& origin, const Vec3& edge1, const Vec3& edge2) {
  TriangleMesh mesh;
  mesh.positions = {origin, origin + edge1, origin + edge1 + edge2, origin + edge2};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

TriangleMesh box_mesh(const Vec3& min, const Vec3& max) {
  TriangleMesh mesh;
  // Corner i has x = max.x when bit 0 is set, y = max.y for bit 1, z = max.z for bit 2.
  for (int corner = 0; corner < 8; ++corner)
    mesh.positions.push_back(
        {(corner & 1) ? max.x : min.x, (corner & 2) ? max.y : min.y, (corner & 4) ? max.z : min.z});
  // Each face as 4 corners counter-clockwise seen from outside: -x, +x, -y, +y, -z, +z.
  constexpr std::array<std::array<uint32_t, 4>, 6> kFaces{{
      {0, 4, 6, 2},
      {1, 3, 7, 5},
      {0, 1, 5, 4},
      {2, 6, 7, 3},
      {0, 2, 3, 1},
      {4, 5, 7, 6},
  }};
  for (const auto& face : kFaces)
    mesh.indices.insert(mesh.indices.end(), {face[0], face[1], face[2], face[0], face[2], face[3]});
  return mesh;
}

size_t icosphere_triangle_count(int subdivisions) {
  return size_t{20} << (2 * subdivisions);
}

size_t icosphere_vertex_count(int subdivisions) {
  return (size_t{10} << (2 * subdivisions)) + 2;
}

TriangleMesh icosphere_mesh(const Vec3& center, double radius, int subdivisions) {
  // The icosahedron: cyclic permutations of (0, +-1, +-phi), on the unit sphere.
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> unit = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                            {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                            {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3& p : unit) p = normalize(p);
  std::vector<uint32_t> indices = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                   1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                   3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                   4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};

  // Split every triangle into 4; the midpoint of an edge is shared by its two triangles.
  for (int level = 0; level < subdivisions; ++level) {
    std::unordered_map<uint64_t, uint32_t> midpoints;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      uint64_t key = (uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      auto [it, inserted] = midpoints.try_emplace(key, static_cast<uint32_t>(unit.size()));
      if (inserted) unit.push_back(normalize(unit[a] + unit[b]));
      return it->second;
    };
    std::vector<uint32_t> finer;
    finer.reserve(indices.size() * 4);
    for (size_t t = 0; t < indices.size(); t += 3) {
      uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
      uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    indices = std::move(finer);
  }

  TriangleMesh mesh;
  mesh.positions.reserve(unit.size());
  for (const Vec3& p : unit) mesh.positions.push_back(center + radius * p);
  mesh.indices = std::move(indices);
  return mesh;
}

namespace {

// tinyobjloader reads a vertex coordinate it cannot parse ("nan", "1e999", "x") as 0 and a
// missing one as 0 too, which silently moves the vertex. Every `v` line must therefore hold at
// least 3 numbers, each a finite double (a trailing `# comment` is allowed).
void check_obj_vertex_lines(std::string_view text) {
  size_t line_number = 0;
  while (!text.empty()) {
    ++line_number;
    size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    auto is_blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
    size_t start = 0;
    while (start < line.size() && is_blank(line[start])) ++start;
    // tinyobjloader's vertex weights (`vw`) cast a parsed double to int unchecked (undefined for
    // 1e999, found by fuzz_obj_package): we have no use for them, so they are refused.
    if (line.size() >= start + 3 && line[start] == 'v' && line[start + 1] == 'w' &&
        is_blank(line[start + 2]))
      throw std::invalid_argument("OBJ line " + std::to_string(line_number) +
                                  ": vertex weights ('vw') are not supported");
    if (line.size() < start + 2 || line[start] != 'v' || !is_blank(line[start + 1])) continue;
    // The fields after "v", up to a comment.
    line = line.substr(start + 1);
    line = line.substr(0, line.find('#'));
    int numbers = 0;
    size_t position = 0;
    while (true) {
      while (position < line.size() && is_blank(line[position])) ++position;
      if (position == line.size()) break;
      size_t token_end = position;
      while (token_end < line.size() && !is_blank(line[token_end])) ++token_end;
      std::string_view token = line.substr(position, token_end - position);
      std::string_view digits = token.front() == '+' ? token.substr(1) : token;
      double value = 0;
      auto [parsed_end, error] =
          std::from_chars(digits.data(), digits.data() + digits.size(), value);
      if (error != std::errc() || parsed_end != digits.data() + digits.size() ||
          !std::isfinite(value))
        throw std::invalid_argument("OBJ line " + std::to_string(line_number) +
                                    ": vertex coordinate '" + std::string(token.substr(0, 32)) +
                                    "' is not a finite number");
      ++numbers;
      position = token_end;
    }
    if (numbers < 3)
      throw std::invalid_argument("OBJ line " + std::to_string(line_number) +
                                  ": a vertex needs 3 " + "coordinates, got " +
                                  std::to_string(numbers));
  }
}

}  // namespace

TriangleMesh obj_mesh(const std::string& obj_bytes, const Vec3& scale, const Vec3& translate) {
  check_obj_vertex_lines(obj_bytes);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  std::istringstream stream(obj_bytes);
  // No material reader: `mtllib` lines are ignored, so parsing never touches the filesystem.
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &stream,
                             /*readMatFn=*/nullptr, /*triangulate=*/true,
                             /*default_vcols_fallback=*/false);
  if (!ok) throw std::invalid_argument("OBJ parse error: " + error);
  if (attrib.vertices.size() % 3 != 0) throw std::invalid_argument("OBJ vertex array is ragged");

  TriangleMesh mesh;
  size_t vertex_count = attrib.vertices.size() / 3;
  mesh.positions.reserve(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    Vec3 p{attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]};
    if (!is_finite(p))
      throw std::invalid_argument("OBJ vertex " + std::to_string(v + 1) + " is not finite");
    mesh.positions.push_back(scale * p + translate);
  }
  for (const tinyobj::shape_t& shape : shapes) {
    const auto& face_sizes = shape.mesh.num_face_vertices;
    size_t offset = 0;
    for (size_t face = 0; face < face_sizes.size(); ++face) {
      size_t corners = face_sizes[face];
      if (offset + corners > shape.mesh.indices.size())
        throw std::invalid_argument("OBJ face list of '" + shape.name + "' is truncated");
      // Triangulation is on, so faces have 3 corners; points and lines (1-2) are skipped.
      if (corners == 3) {
        for (size_t k = 0; k < 3; ++k) {
          int index = shape.mesh.indices[offset + k].vertex_index;
          if (index < 0 || static_cast<size_t>(index) >= vertex_count)
            throw std::invalid_argument("OBJ face " + std::to_string(face + 1) + " of '" +
                                        shape.name + "' has vertex index out of range");
          mesh.indices.push_back(static_cast<uint32_t>(index));
        }
      }
      offset += corners;
    }
  }
  if (mesh.indices.empty()) throw std::invalid_argument("OBJ file has no triangles");
  return mesh;
}

}  // namespace penumbra
