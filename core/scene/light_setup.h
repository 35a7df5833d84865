#pragma once
// Building lights with their derived fields (vertices, normal, area, centroid) and the checks
// that refuse degenerate emitters. The scene reader uses these; tests and tools that build
// lights in code should too, so that every Light in the program obeys scene.h's invariants.
//
// Each function throws std::invalid_argument saying what is wrong (zero area, parallel edges,
// collinear, non-planar or non-convex polygon, zero normal, ...). Tolerances are relative to the
// light's own size, so a 1 mm light and a 100 m light are judged alike.

#include <vector>

#include "core/scene/scene.h"

namespace penumbra {

// Relative tolerances of the checks (SCENE_FORMAT.md uses 1e-6 for "perpendicular edges").
inline constexpr double kPlanarityTolerance = 1e-6;  // off-plane distance / polygon extent
inline constexpr double kDegenerateSine = 1e-9;      // |a x b| / (|a| |b|) below this: parallel

// Quad light origin + s*edge1 + t*edge2; emits along normalize(cross(edge1, edge2)).
Light make_quad_light(const Vec3& origin, const Vec3& edge1, const Vec3& edge2,
                      const Rgb& radiance);
// Convex planar polygon light, vertices in the given order; emits along
// normalize(cross(v1 - v0, v2 - v0)), so the vertices run counter-clockwise seen from that side.
Light make_polygon_light(const std::vector<Vec3>& vertices, const Rgb& radiance);
// Disk light; `normal` need not be unit length (it is normalized) but must not be zero.
Light make_disk_light(const Vec3& center, const Vec3& normal, double radius, const Rgb& radiance);

// Fills the derived fields of a light whose defining fields are set (type, origin/edges,
// vertices, or center/normal/radius), checking them as the functions above do.
void derive_light_geometry(Light& light);

}  // namespace penumbra
