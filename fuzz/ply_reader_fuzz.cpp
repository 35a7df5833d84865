// libFuzzer target: the PLY reader (core/scene/ply_mesh.h) on arbitrary bytes. Every input must
// either give a mesh whose indices, normals and uvs are consistent and finite, or throw
// std::invalid_argument.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "core/scene/ply_mesh.h"
#include "fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  PlyReadResult result;
  try {
    result = read_ply_mesh(std::string_view(reinterpret_cast<const char*>(data), size), 1 << 16,
                           1 << 16);
  } catch (const std::invalid_argument&) {
    return 0;
  }
  const TriangleMesh& mesh = result.mesh;
  FUZZ_CHECK(mesh.indices.size() % 3 == 0);
  for (uint32_t index : mesh.indices) FUZZ_CHECK(index < mesh.positions.size());
  FUZZ_CHECK(mesh.normals.empty() || mesh.normals.size() == mesh.positions.size());
  FUZZ_CHECK(mesh.uvs.empty() || mesh.uvs.size() == mesh.positions.size());
  for (const Vec3& p : mesh.positions) FUZZ_CHECK(is_finite(p));
  for (const Vec3& n : mesh.normals) FUZZ_CHECK(is_finite(n));
  for (const Vec2& uv : mesh.uvs) FUZZ_CHECK(std::isfinite(uv.x) && std::isfinite(uv.y));
  return 0;
}
