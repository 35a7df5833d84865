#include "core/lights/polygon_light.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace penumbra {

bool is_polygon_light(const Light& light) {
  if (light.type == LightType::Quad) return true;
  if (light.type == LightType::Polygon)
    return light.vertices.size() >= 3 && light.vertices.size() <= size_t(kMaxPolygonVertices);
  return false;
}

PolygonLightGeometry polygon_light_geometry(const Light& light) {
  PolygonLightGeometry g;
  if (light.type == LightType::Disk)
    throw std::invalid_argument(
        "polygon strategies (psa, Peters sa) need a quad or polygon light; "
        "a disk is not a polygon");
  if (light.type == LightType::Quad) {
    g.vertices[0] = light.origin;
    g.vertices[1] = light.origin + light.edge1;
    g.vertices[2] = light.origin + light.edge1 + light.edge2;
    g.vertices[3] = light.origin + light.edge2;
    g.vertex_count = 4;
    g.normal = normalize(cross(light.edge1, light.edge2));
  } else {
    size_t n = light.vertices.size();
    if (n < 3 || n > size_t(kMaxPolygonVertices))
      throw std::invalid_argument("polygon light with " + std::to_string(n) +
                                  " vertices; the polygon strategies take 3 to " +
                                  std::to_string(kMaxPolygonVertices));
    for (size_t i = 0; i < n; ++i) g.vertices[i] = light.vertices[i];
    g.vertex_count = int(n);
    g.normal = normalize(
        cross(light.vertices[1] - light.vertices[0], light.vertices[2] - light.vertices[0]));
  }
  for (int i = 0; i < g.vertex_count; ++i)
    g.size = std::max(g.size, length(g.vertices[(i + 1) % g.vertex_count] - g.vertices[i]));
  if (!is_finite(g.normal) || !(g.size > 0))
    throw std::invalid_argument("degenerate polygon light (zero area or non-finite vertices)");
  return g;
}

bool PolygonLightGeometry::emits_towards(const Vec3& x) const {
  return dot(normal, x - vertices[0]) > 0;
}

std::optional<Vec3> PolygonLightGeometry::plane_hit(const Vec3& x, const Vec3& direction,
                                                    double* distance) const {
  double height = dot(normal, x - vertices[0]);  // > 0 on the emitting side
  double cos_light = -dot(normal, direction);
  if (!(cos_light > 0) || !(height > 0)) return std::nullopt;
  double t = height / cos_light;
  if (!std::isfinite(t)) return std::nullopt;
  *distance = t;
  return x + direction * t;
}

bool PolygonLightGeometry::contains(const Vec3& point) const {
  double tolerance = 1e-9 * size;
  for (int i = 0; i < vertex_count; ++i) {
    Vec3 a = vertices[i];
    Vec3 edge = vertices[(i + 1) % vertex_count] - a;
    // Signed distance from the edge's line, positive inside (counter-clockwise about normal).
    double inside = dot(cross(edge, point - a), normal) / length(edge);
    if (inside < -tolerance) return false;
  }
  return true;
}

}  // namespace penumbra
