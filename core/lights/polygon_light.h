#pragma once
// The geometry the polygon strategies (core/strategies: psa, ltc) share: a quad or
// polygon light as a convex vertex list with its emission normal, the one-sided emission test,
// the step from a sampled direction to a point on the light's plane, and the point-in-polygon
// test behind pdf(point).

#include <array>
#include <optional>
#include <span>

#include "core/math/polygon_limits.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

// True for lights the polygon strategies can sample: quads, and polygons of 3 to
// kMaxPolygonVertices vertices. Disks are not polygons.
bool is_polygon_light(const Light& light);

struct PolygonLightGeometry {
  std::array<Vec3, kMaxPolygonVertices> vertices{};
  int vertex_count = 0;
  Vec3 normal;      // unit emission normal; the vertices run counter-clockwise around it
  double size = 0;  // longest edge, the length scale of tolerances

  std::span<const Vec3> vertex_span() const { return {vertices.data(), size_t(vertex_count)}; }
  // The light emits towards x (x strictly on the side its normal points to).
  bool emits_towards(const Vec3& x) const;
  // The point where the ray x + t direction (unit direction) meets the light's plane, and t;
  // empty if the ray runs parallel to it or away from it.
  std::optional<Vec3> plane_hit(const Vec3& x, const Vec3& direction, double* distance) const;
  // `point` (assumed on the light's plane) lies in the polygon, up to a tolerance of 1e-9 of the
  // light's size (a point the strategy itself produced is never refused for rounding).
  bool contains(const Vec3& point) const;
};

// The light's polygon (quads: origin, origin+edge1, origin+edge1+edge2, origin+edge2) and its
// normal as SCENE_FORMAT.md defines it. Throws std::invalid_argument for lights that
// is_polygon_light refuses, saying why.
PolygonLightGeometry polygon_light_geometry(const Light& light);

}  // namespace penumbra
