#pragma once
// PLY meshes (the `plymesh` shape of pbrt-v3): ASCII, binary little-endian and binary
// big-endian files; vertex positions, optional normals (nx ny nz) and texture coordinates
// (u v, s t, texture_u texture_v, texture_s texture_t), faces as index lists. Triangles are kept,
// quads split as pbrt-v3 splits them (v0 v1 v2, v0 v2 v3); other elements and properties are
// skipped. Reads from bytes (no file is opened), so packages and files share it.
//
// Why our own reader: Debian 12 packages no small PLY library (RPly is not in bookworm), and
// assimp's PLY importer, the packaged alternative, took 4.98 s for the kitchen's 294 files
// (43 MB) against our goal of 3 s for the whole load (README, "pbrt-v3 scenes").

#include <string>
#include <string_view>
#include <vector>

#include "core/scene/shape_mesh.h"

namespace penumbra {

struct PlyReadResult {
  TriangleMesh mesh;
  size_t skipped_faces = 0;  // faces with fewer than 3 or more than 4 vertices (pbrt-v3 skips them)
};

// Throws std::invalid_argument saying what is wrong (bad header, unsupported format or type,
// truncated data, index out of range, non-finite coordinate, counts larger than the bytes
// could hold). `max_vertices` and `max_faces` bound what a header may announce.
PlyReadResult read_ply_mesh(std::string_view bytes, size_t max_vertices = size_t{1} << 28,
                            size_t max_faces = size_t{1} << 28);

}  // namespace penumbra
