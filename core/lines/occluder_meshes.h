#pragma once
// Procedural occluder meshes for the line query's tests and benchmarks: subdivided boxes,
// icospheres, UV spheres and random triangle soups, as flat position and index arrays like a
// Scene's. Boxes and spheres are closed (watertight) meshes.
//
// Their own namespace: core/scene/shape_mesh.h has a different penumbra::TriangleMesh and a
// penumbra::icosphere_mesh with the same signature. Two definitions under one name would break
// the one-definition rule (the linker keeps one of them for every caller).

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "core/math/vec.h"

namespace penumbra::occluder_meshes {

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;

  size_t triangle_count() const { return indices.size() / 3; }
  void add_triangle(uint32_t i0, uint32_t i1, uint32_t i2) {
    indices.insert(indices.end(), {i0, i1, i2});
  }
  void append(const TriangleMesh& other) {
    uint32_t base = static_cast<uint32_t>(positions.size());
    positions.insert(positions.end(), other.positions.begin(), other.positions.end());
    for (uint32_t index : other.indices) indices.push_back(base + index);
  }
};

// Box [lower, upper], each face an n x n grid of quads (two triangles each). Faces do not share
// vertex indices, but points on shared borders get the same coordinates bit for bit (each
// coordinate is the same function of its grid index), so the mesh is closed.
inline TriangleMesh box_mesh(const Vec3& lower, const Vec3& upper, int subdivisions = 1) {
  TriangleMesh mesh;
  int n = std::max(subdivisions, 1);
  auto coordinate = [&](int axis, int i) {
    if (i == 0) return lower[axis];
    if (i == n) return upper[axis];
    return lower[axis] + (upper[axis] - lower[axis]) * (static_cast<double>(i) / n);
  };
  for (int axis = 0; axis < 3; ++axis) {
    int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      uint32_t base = static_cast<uint32_t>(mesh.positions.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          Vec3 p;
          p[axis] = side == 0 ? lower[axis] : upper[axis];
          p[u_axis] = coordinate(u_axis, i);
          p[v_axis] = coordinate(v_axis, j);
          mesh.positions.push_back(p);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          uint32_t i00 = base + j * (n + 1) + i, i10 = i00 + 1, i01 = i00 + (n + 1), i11 = i01 + 1;
          // Alternate the diagonal so both diagonal directions occur.
          if ((i + j) % 2 == 0) {
            mesh.add_triangle(i00, i10, i11);
            mesh.add_triangle(i00, i11, i01);
          } else {
            mesh.add_triangle(i00, i10, i01);
            mesh.add_triangle(i10, i11, i01);
          }
        }
      }
    }
  }
  return mesh;
}

// Icosphere: an icosahedron subdivided `subdivisions` times, vertices pushed to the sphere
// (20 * 4^subdivisions triangles, shared vertex indices).
inline TriangleMesh icosphere_mesh(const Vec3& center, double radius, int subdivisions) {
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> unit = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                            {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                            {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3& p : unit) p = normalize(p);
  std::vector<std::array<uint32_t, 3>> faces = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto midpoint = [&](uint32_t i, uint32_t j) {
      auto key = std::minmax(i, j);
      auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      unit.push_back(normalize(unit[i] + unit[j]));
      uint32_t index = static_cast<uint32_t>(unit.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<std::array<uint32_t, 3>> finer;
    for (const auto& f : faces) {
      uint32_t m01 = midpoint(f[0], f[1]), m12 = midpoint(f[1], f[2]), m20 = midpoint(f[2], f[0]);
      finer.push_back({f[0], m01, m20});
      finer.push_back({f[1], m12, m01});
      finer.push_back({f[2], m20, m12});
      finer.push_back({m01, m12, m20});
    }
    faces = std::move(finer);
  }
  TriangleMesh mesh;
  for (const Vec3& p : unit) mesh.positions.push_back(center + radius * p);
  for (const auto& f : faces) mesh.add_triangle(f[0], f[1], f[2]);
  return mesh;
}

// UV sphere with `rings` latitude bands and `segments` longitude bands (closed: poles shared,
// the seam shares indices); 2 * segments * (rings - 1) triangles.
inline TriangleMesh uv_sphere_mesh(const Vec3& center, double radius, int rings, int segments) {
  TriangleMesh mesh;
  mesh.positions.push_back(center + Vec3(0, radius, 0));
  for (int r = 1; r < rings; ++r) {
    double theta = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      double phi = 2 * kPi * s / segments;
      mesh.positions.push_back(center + radius * Vec3(std::sin(theta) * std::cos(phi),
                                                      std::cos(theta),
                                                      std::sin(theta) * std::sin(phi)));
    }
  }
  mesh.positions.push_back(center - Vec3(0, radius, 0));
  uint32_t south = static_cast<uint32_t>(mesh.positions.size() - 1);
  auto ring_vertex = [&](int r, int s) {
    return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments));
  };
  for (int s = 0; s < segments; ++s) mesh.add_triangle(0, ring_vertex(1, s + 1), ring_vertex(1, s));
  for (int r = 1; r + 1 < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      mesh.add_triangle(ring_vertex(r, s), ring_vertex(r, s + 1), ring_vertex(r + 1, s + 1));
      mesh.add_triangle(ring_vertex(r, s), ring_vertex(r + 1, s + 1), ring_vertex(r + 1, s));
    }
  }
  for (int s = 0; s < segments; ++s)
    mesh.add_triangle(south, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1));
  return mesh;
}

// `count` random triangles: centres uniform in [lower, upper], vertices within `size` of it.
inline TriangleMesh random_triangles_mesh(size_t count, const Vec3& lower, const Vec3& upper,
                                          double size, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  TriangleMesh mesh;
  mesh.positions.reserve(3 * count);
  for (size_t i = 0; i < count; ++i) {
    Vec3 c(lower.x + (upper.x - lower.x) * unit(rng), lower.y + (upper.y - lower.y) * unit(rng),
           lower.z + (upper.z - lower.z) * unit(rng));
    uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    for (int k = 0; k < 3; ++k) {
      mesh.positions.push_back(c + size * Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) *
                                       2.0);
    }
    mesh.add_triangle(base, base + 1, base + 2);
  }
  return mesh;
}

}  // namespace penumbra::occluder_meshes
