// Geometry of quad, polygon and disk lights: emission, uniform points, ray hits, containment.
//
// Emission is one-sided (SCENE_FORMAT.md): zero towards receivers with dot(normal, to) <= 0.
// Gaussian profile exp(-r^2 / (2 sigma^2)), r the normalized distance from the centre:
//   quads:    r^2 = (2s - 1)^2 + (2t - 1)^2 in the parallelogram's (s, t) (r = 1 at the edge
//             midpoints, so sigma is a fraction of the half-extent along each edge);
//   disks:    r = distance from the centre / radius;
//   polygons: constant emission only (the scene reader refuses a gaussian polygon); a gaussian
//             profile on a polygon is ignored here.
//
// Double precision. Containment tolerances are relative to the light's size and to the
// magnitude of the coordinates, never absolute.

#include "core/lights/light_geometry.h"

#include "core/sampling/pattern.h"

namespace penumbra {
namespace {

// (s, t) with point = origin + s edge1 + t edge2 (least squares for points off the plane).
Vec2 quad_coordinates(const Light& light, const Vec3& point) {
  Vec3 d = point - light.origin;
  double e11 = dot(light.edge1, light.edge1), e12 = dot(light.edge1, light.edge2),
         e22 = dot(light.edge2, light.edge2);
  double d1 = dot(d, light.edge1), d2 = dot(d, light.edge2);
  double det = difference_of_products(e11, e22, e12, e12);
  if (!(det > 0)) return {0.5, 0.5};
  return {difference_of_products(d1, e22, d2, e12) / det,
          difference_of_products(e11, d2, e12, d1) / det};
}

// A point of the light's plane.
const Vec3& plane_anchor(const Light& light) {
  switch (light.type) {
    case LightType::Quad:
      return light.origin;
    case LightType::Polygon:
      return light.vertices.front();
    case LightType::Disk:
      return light.center;
  }
  return light.centroid;
}

// Diameter-like size of the light, the scale of containment tolerances.
double light_extent(const Light& light) {
  switch (light.type) {
    case LightType::Quad:
      return length(light.edge1) + length(light.edge2);
    case LightType::Polygon: {
      double extent = 0;
      for (const Vec3& v : light.vertices) extent = std::max(extent, length(v - light.centroid));
      return 2.0 * extent;
    }
    case LightType::Disk:
      return 2.0 * light.radius;
  }
  return 0;
}

double max_abs_coordinate(const Vec3& p) {
  return std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z)));
}

// Inside test for a point already in the plane; `tolerance` is a distance.
bool inside_in_plane(const Light& light, const Vec3& point, double tolerance) {
  switch (light.type) {
    case LightType::Quad: {
      Vec2 st = quad_coordinates(light, point);
      double ts = tolerance / length(light.edge1), tt = tolerance / length(light.edge2);
      return st.x >= -ts && st.x <= 1.0 + ts && st.y >= -tt && st.y <= 1.0 + tt;
    }
    case LightType::Polygon: {
      // Convex, counter-clockwise about the normal: left of (or on) every edge.
      size_t n = light.vertices.size();
      if (n < 3) return false;
      for (size_t i = 0; i < n; ++i) {
        const Vec3& a = light.vertices[i];
        const Vec3& b = light.vertices[(i + 1) % n];
        Vec3 edge = b - a;
        double edge_length = length(edge);
        double side = dot(cross(edge, point - a), light.normal);
        if (side < -tolerance * edge_length) return false;
      }
      return true;
    }
    case LightType::Disk: {
      Vec3 d = point - light.center;
      d -= dot(d, light.normal) * light.normal;
      double limit = light.radius + tolerance;
      return length_squared(d) <= limit * limit;
    }
  }
  return false;
}

}  // namespace

Rgb emitted_radiance(const Light& light, const Vec3& point_on_light, const Vec3& to_receiver) {
  if (!(dot(light.normal, to_receiver) > 0)) return {0, 0, 0};
  if (light.profile != ProfileType::Gaussian || light.type == LightType::Polygon)
    return light.radiance;
  double r_squared = 0;
  if (light.type == LightType::Quad) {
    Vec2 st = quad_coordinates(light, point_on_light);
    double a = 2.0 * st.x - 1.0, b = 2.0 * st.y - 1.0;
    r_squared = a * a + b * b;
  } else {
    r_squared = length_squared(point_on_light - light.center) / (light.radius * light.radius);
  }
  double sigma = light.sigma;
  if (!(sigma > 0)) return {0, 0, 0};
  double weight = std::exp(-r_squared / (2.0 * sigma * sigma));
  return std::isfinite(weight) ? light.radiance * weight : Rgb{0, 0, 0};
}

Vec3 light_point_uniform(const Light& light, const Vec2& u) {
  switch (light.type) {
    case LightType::Quad:
      return light.origin + u.x * light.edge1 + u.y * light.edge2;
    case LightType::Polygon: {
      // Choose a triangle of the fan around vertex 0 in proportion to its area, then reuse u.x.
      const std::vector<Vec3>& v = light.vertices;
      size_t n = v.size();
      if (n < 3) return n ? v[0] : light.centroid;
      double total = 0;
      for (size_t i = 1; i + 1 < n; ++i) total += length(cross(v[i] - v[0], v[i + 1] - v[0]));
      double target = u.x * total;
      size_t chosen = n - 2;
      double begin = 0, width = 0;
      for (size_t i = 1; i + 1 < n; ++i) {
        width = length(cross(v[i] - v[0], v[i + 1] - v[0]));
        if (target < begin + width || i + 2 == n) {
          chosen = i;
          break;
        }
        begin += width;
      }
      double ux = width > 0 ? std::clamp((target - begin) / width, 0.0, 1.0) : 0.5;
      // Uniform point in the triangle (v0, v_i, v_i+1): square-root map.
      double su = std::sqrt(ux);
      return (1.0 - su) * v[0] + (su * (1.0 - u.y)) * v[chosen] + (su * u.y) * v[chosen + 1];
    }
    case LightType::Disk: {
      Vec2 d = square_to_disk_concentric(u);
      Frame frame = Frame::from_normal(light.normal);
      return light.center + light.radius * (d.x * frame.s + d.y * frame.t);
    }
  }
  return light.centroid;
}

std::optional<LightHit> intersect_light(const Light& light, const Vec3& origin,
                                        const Vec3& direction, double t_min, double t_max) {
  double denominator = dot(light.normal, direction);
  if (!(std::abs(denominator) > 0)) return std::nullopt;  // parallel to the light's plane
  double distance = dot(light.normal, plane_anchor(light) - origin) / denominator;
  if (!(distance > t_min && distance < t_max) || !std::isfinite(distance)) return std::nullopt;
  Vec3 point = origin + distance * direction;
  if (!inside_in_plane(light, point, 0.0)) return std::nullopt;
  return LightHit{distance, point};
}

bool light_contains(const Light& light, const Vec3& point) {
  double tolerance = 1e-9 * light_extent(light) + 1e-12 * max_abs_coordinate(point);
  if (!(std::abs(dot(light.normal, point - plane_anchor(light))) <= tolerance)) return false;
  return inside_in_plane(light, point, tolerance);
}

double light_plane_height(const Light& light, const Vec3& point) {
  return dot(light.normal, point - plane_anchor(light));
}

bool light_faces_point(const Light& light, const Vec3& point) {
  double height = light_plane_height(light, point);
  double scale = light_extent(light) + length(point - light.centroid);
  return height > 1e-12 * scale && std::isfinite(height);
}

}  // namespace penumbra
