#include "core/scene/light_setup.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace penumbra {

namespace {

std::string format_vec(const Vec3& v) {
  std::ostringstream out;
  out.precision(9);
  out << "[" << v.x << ", " << v.y << ", " << v.z << "]";
  return out.str();
}

void require_finite(const Vec3& v, const char* what) {
  if (!is_finite(v)) throw std::invalid_argument(std::string(what) + " is not finite");
}

void check_radiance(const Rgb& radiance) {
  if (!is_finite(radiance)) throw std::invalid_argument("radiance is not finite");
  if (radiance.x < 0 || radiance.y < 0 || radiance.z < 0)
    throw std::invalid_argument("radiance is negative: " + format_vec(radiance));
}

// True when a and b are (nearly) parallel or one of them is zero: |a x b| <= eps |a| |b|.
bool nearly_parallel(const Vec3& a, const Vec3& b) {
  double scale = length(a) * length(b);
  return !(length(cross(a, b)) > kDegenerateSine * scale);
}

void derive_quad(Light& light) {
  require_finite(light.origin, "origin");
  require_finite(light.edge1, "edge1");
  require_finite(light.edge2, "edge2");
  if (!(length(light.edge1) > 0)) throw std::invalid_argument("edge1 has zero length");
  if (!(length(light.edge2) > 0)) throw std::invalid_argument("edge2 has zero length");
  if (nearly_parallel(light.edge1, light.edge2))
    throw std::invalid_argument("edge1 and edge2 are parallel: the quad has zero area");
  Vec3 normal = cross(light.edge1, light.edge2);
  light.area = length(normal);
  light.normal = normal / light.area;
  light.vertices = {light.origin, light.origin + light.edge1,
                    light.origin + light.edge1 + light.edge2, light.origin + light.edge2};
  light.centroid = light.origin + 0.5 * (light.edge1 + light.edge2);
}

void derive_polygon(Light& light) {
  const std::vector<Vec3>& v = light.vertices;
  const size_t n = v.size();
  if (n < 3)
    throw std::invalid_argument("a polygon needs at least 3 vertices, got " + std::to_string(n));
  for (const Vec3& p : v) require_finite(p, "a vertex");

  // Size of the polygon, the scale of every tolerance below.
  double extent = 0;
  for (const Vec3& p : v) extent = std::max(extent, length(p - v[0]));
  if (!(extent > 0))
    throw std::invalid_argument("all vertices coincide: the polygon has zero area");

  // The emission normal per the format: cross(v1 - v0, v2 - v0).
  Vec3 edge01 = v[1] - v[0], edge02 = v[2] - v[0];
  if (nearly_parallel(edge01, edge02))
    throw std::invalid_argument(
        "vertices 0, 1, 2 are collinear (or coincide), so the normal cross(v1-v0, v2-v0) is "
        "undefined");
  Vec3 normal = normalize(cross(edge01, edge02));

  // Planarity: every vertex within a relative distance of the plane through v0, v1, v2.
  for (size_t i = 3; i < n; ++i) {
    double off_plane = std::abs(dot(v[i] - v[0], normal));
    if (off_plane > kPlanarityTolerance * extent) {
      std::ostringstream out;
      out << "non-planar polygon: vertex " << i << " is " << off_plane
          << " off the plane of vertices 0, 1, 2 (tolerance " << kPlanarityTolerance * extent
          << ")";
      throw std::invalid_argument(out.str());
    }
  }

  // Convexity: every corner turns the same way (left about the normal), no corner is straight
  // or folded back, and the boundary winds around exactly once (a pentagram turns left at
  // every corner but winds twice).
  double total_turn = 0;
  for (size_t i = 0; i < n; ++i) {
    Vec3 incoming = v[i] - v[(i + n - 1) % n];
    Vec3 outgoing = v[(i + 1) % n] - v[i];
    if (!(length(incoming) > kDegenerateSine * extent))
      throw std::invalid_argument("vertices " + std::to_string((i + n - 1) % n) + " and " +
                                  std::to_string(i) + " coincide");
    double sine = dot(cross(incoming, outgoing), normal);
    double cosine = dot(incoming, outgoing);
    if (!(sine > kDegenerateSine * length(incoming) * length(outgoing))) {
      if (std::abs(sine) <= kDegenerateSine * length(incoming) * length(outgoing) && cosine > 0)
        throw std::invalid_argument("collinear vertices around vertex " + std::to_string(i) +
                                    " (a straight corner)");
      throw std::invalid_argument("non-convex polygon: it turns the wrong way at vertex " +
                                  std::to_string(i) +
                                  " (vertices must run counter-clockwise about "
                                  "cross(v1-v0, v2-v0))");
    }
    total_turn += std::atan2(sine, cosine);
  }
  if (total_turn > 3 * kPi)
    throw std::invalid_argument("non-convex polygon: its boundary winds around more than once");

  // Area and centroid from the triangle fan about v0.
  double area = 0;
  Vec3 weighted_centroid;
  for (size_t i = 1; i + 1 < n; ++i) {
    double triangle_area = 0.5 * dot(cross(v[i] - v[0], v[i + 1] - v[0]), normal);
    area += triangle_area;
    weighted_centroid += triangle_area * (v[0] + v[i] + v[i + 1]) / 3.0;
  }
  if (!(area > 0)) throw std::invalid_argument("the polygon has zero area");
  light.normal = normal;
  light.area = area;
  light.centroid = weighted_centroid / area;
}

void derive_disk(Light& light) {
  require_finite(light.center, "center");
  require_finite(light.normal, "normal");
  if (!std::isfinite(light.radius) || !(light.radius > 0))
    throw std::invalid_argument("radius must be positive, got " + std::to_string(light.radius));
  double normal_length = length(light.normal);
  if (!(normal_length > 0) || !std::isfinite(normal_length))
    throw std::invalid_argument("normal is zero: the disk has no emitting side");
  light.normal = light.normal / normal_length;
  light.area = kPi * light.radius * light.radius;
  light.centroid = light.center;
  light.vertices.clear();
}

}  // namespace

void derive_light_geometry(Light& light) {
  check_radiance(light.radiance);
  if (light.profile == ProfileType::Gaussian) {
    if (light.type == LightType::Polygon)
      throw std::invalid_argument("a gaussian profile is defined for quad and disk lights only");
    if (!std::isfinite(light.sigma) || !(light.sigma > 0))
      throw std::invalid_argument("gaussian sigma must be positive, got " +
                                  std::to_string(light.sigma));
  }
  switch (light.type) {
    case LightType::Quad:
      derive_quad(light);
      break;
    case LightType::Polygon:
      derive_polygon(light);
      break;
    case LightType::Disk:
      derive_disk(light);
      break;
  }
}

Light make_quad_light(const Vec3& origin, const Vec3& edge1, const Vec3& edge2,
                      const Rgb& radiance) {
  Light light;
  light.type = LightType::Quad;
  light.origin = origin;
  light.edge1 = edge1;
  light.edge2 = edge2;
  light.radiance = radiance;
  derive_light_geometry(light);
  return light;
}

Light make_polygon_light(const std::vector<Vec3>& vertices, const Rgb& radiance) {
  Light light;
  light.type = LightType::Polygon;
  light.vertices = vertices;
  light.radiance = radiance;
  derive_light_geometry(light);
  return light;
}

Light make_disk_light(const Vec3& center, const Vec3& normal, double radius, const Rgb& radiance) {
  Light light;
  light.type = LightType::Disk;
  light.center = center;
  light.normal = normal;
  light.radius = radius;
  light.radiance = radiance;
  derive_light_geometry(light);
  return light;
}

}  // namespace penumbra
