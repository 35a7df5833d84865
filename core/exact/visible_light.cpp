// The visible part of a polygonal light, exactly (see the header for the steps and accuracy).

#include "core/exact/visible_light.h"

#include <algorithm>
#include <cmath>
#include <polyclipping/clipper.hpp>

#include "core/lines/shadow_triangle.h"
#include "core/math/lambert_polygon.h"

namespace penumbra {

namespace {

constexpr double kGridBits = 50;  // 2^50 grid units across the light's largest coordinate

// The light's plane frame: origin o (vertex 0), unit axes u, w in the plane, unit normal towards
// x. 2D coordinates of a point p of the plane are (u.(p - o), w.(p - o)).
struct LightFrame {
  Vec3 origin, u, w, normal;
  double scale = 1;  // grid units per scene unit
  ClipperLib::IntPoint to_grid(const Vec3& p) const {
    const Vec3 d = p - origin;
    return {ClipperLib::cInt(std::llround(dot(u, d) * scale)),
            ClipperLib::cInt(std::llround(dot(w, d) * scale))};
  }
  Vec3 from_grid(const ClipperLib::IntPoint& q) const {
    return origin + (double(q.X) / scale) * u + (double(q.Y) / scale) * w;
  }
};

// Signed (1/2) sum_i gamma_i n . unit(v_i x v_{i+1}) over a polygon of vectors from x.
double signed_projected_solid_angle(std::span<const Vec3> relative, const Vec3& n) {
  const size_t size = relative.size();
  double sum = 0;
  for (size_t i = 0; i < size; ++i) {
    const Vec3& a = relative[i];
    const Vec3& b = relative[(i + 1) % size];
    const Vec3 c = cross_accurate(a, b);
    const double c_length = length(c);
    if (!(c_length > 0)) continue;
    sum += std::atan2(c_length, dot(a, b)) * dot(n, c) / c_length;
  }
  return 0.5 * sum;
}

// An edge's point where the linear function f = dot(a, q) - b is zero, computed from the
// endpoints in lexicographic order so that the same edge of two triangles gives the same bits.
Vec3 edge_crossing(const Vec3& p, double fp, const Vec3& q, double fq) {
  const bool swap = std::tie(q.x, q.y, q.z) < std::tie(p.x, p.y, p.z);
  const Vec3& first = swap ? q : p;
  const Vec3& second = swap ? p : q;
  const double f_first = swap ? fq : fp, f_second = swap ? fp : fq;
  const double t = f_first / (f_first - f_second);
  return first + t * (second - first);
}

// Sutherland-Hodgman: keeps f(q) = dot(normal, q) - offset <= 0.
void clip_polygon(std::vector<Vec3>& polygon, const Vec3& normal, double offset,
                  std::vector<Vec3>& scratch) {
  scratch.clear();
  const size_t size = polygon.size();
  for (size_t i = 0; i < size; ++i) {
    const Vec3& p = polygon[i];
    const Vec3& q = polygon[(i + 1) % size];
    const double fp = dot(normal, p) - offset, fq = dot(normal, q) - offset;
    if (fp <= 0) scratch.push_back(p);
    if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) scratch.push_back(edge_crossing(p, fp, q, fq));
  }
  polygon.swap(scratch);
}

// The horizon-clipped light polygon as vectors from x; empty when nothing is above.
std::vector<Vec3> light_above_horizon(const Vec3& x, const Vec3& n,
                                      std::span<const Vec3> light_polygon) {
  std::vector<Vec3> relative(light_polygon.size()), clipped(light_polygon.size() + 1);
  for (size_t i = 0; i < light_polygon.size(); ++i) relative[i] = light_polygon[i] - x;
  clipped.resize(clip_polygon_to_horizon(relative, n, clipped));
  if (clipped.size() < 3) clipped.clear();
  return clipped;
}

}  // namespace

double unoccluded_projected_solid_angle(const Vec3& x, const Vec3& n,
                                        std::span<const Vec3> light_polygon,
                                        const Vec3& emission_normal) {
  if (light_polygon.size() < 3 || !(dot(emission_normal, x - light_polygon[0]) > 0)) return 0;
  const std::vector<Vec3> above = light_above_horizon(x, n, light_polygon);
  return std::abs(signed_projected_solid_angle(above, n));
}

double visible_projected_solid_angle(const Vec3& x, const Vec3& n,
                                     std::span<const Vec3> light_polygon,
                                     const Vec3& emission_normal, const LineQuery& query,
                                     VisibleLightScratch& scratch, VisibleLightStats* stats) {
  if (light_polygon.size() < 3 || !is_finite(x) || !is_finite(n) ||
      !(dot(emission_normal, x - light_polygon[0]) > 0))
    return 0;
  // 1. The light above x's horizon (vectors from x), back to points.
  std::vector<Vec3> above = light_above_horizon(x, n, light_polygon);
  if (above.empty()) return 0;
  std::vector<Vec3> light_points(above.size());
  for (size_t i = 0; i < above.size(); ++i) light_points[i] = x + above[i];

  // 2. Candidate occluders.
  const std::vector<HalfSpace> pyramid = shadow_pyramid(x, light_points);
  if (pyramid.empty()) return 0;
  occluders_in_pyramid(query, pyramid, scratch.candidates);
  if (stats) stats->candidates += scratch.candidates.size();
  if (scratch.candidates.empty()) return std::abs(signed_projected_solid_angle(above, n));

  // The light's frame and grid.
  LightFrame frame;
  frame.origin = light_polygon[0];
  frame.normal =
      normalize(cross(light_polygon[1] - light_polygon[0], light_polygon[2] - light_polygon[0]));
  if (dot(frame.normal, x - frame.origin) < 0) frame.normal = -frame.normal;
  frame.u = normalize(light_polygon[1] - light_polygon[0]);
  frame.w = cross(frame.normal, frame.u);
  double extent = 0;
  for (const Vec3& p : light_polygon) {
    const Vec3 d = p - frame.origin;
    extent = std::max({extent, std::abs(dot(frame.u, d)), std::abs(dot(frame.w, d))});
  }
  if (!(extent > 0)) return 0;
  frame.scale = std::ldexp(1.0, int(kGridBits)) / extent;
  const double distance = dot(frame.normal, x - frame.origin);  // > 0: x in front
  const ShadowTriangleTolerances tolerances;

  ClipperLib::Paths light_path(1);
  for (const Vec3& p : light_points) light_path[0].push_back(frame.to_grid(p));
  if (!ClipperLib::Orientation(light_path[0])) ClipperLib::ReversePath(light_path[0]);

  // 3-4. Each occluder's part inside the pyramid and the depth slab, projected onto the light.
  // depth s(q) = normal.(x - q) / distance: 0 at x, 1 on the light's plane.
  const Vec3 depth_gradient = -frame.normal / distance;
  const double depth_at_origin = dot(frame.normal, x) / distance;  // s(q) = this + gradient.q
  ClipperLib::Paths shadows;
  std::vector<Vec3> polygon, clip_scratch;
  const std::vector<OccluderTriangle>& triangles = query.triangles();
  for (uint32_t index : scratch.candidates) {
    const OccluderTriangle& triangle = triangles[index];
    const Vec3 v0 = triangle.vertex(0), v1 = triangle.vertex(1), v2 = triangle.vertex(2);
    // Seen edge-on: its plane passes within s_min of the way to the light from x.
    const Vec3 plane = cross(v1 - v0, v2 - v0);
    const double plane_length = length(plane);
    if (!(plane_length > 0)) continue;
    if (std::abs(dot(plane, x - v0)) <= tolerances.self_occlusion_epsilon * distance * plane_length)
      continue;
    polygon.assign({v0, v1, v2});
    // s >= s_min:  -gradient.q <= depth_at_origin - s_min;  s <= s_max: gradient.q <= ...
    clip_polygon(polygon, -depth_gradient, depth_at_origin - tolerances.self_occlusion_epsilon,
                 clip_scratch);
    if (polygon.size() >= 3)
      clip_polygon(polygon, depth_gradient, (1 - tolerances.light_plane_epsilon) - depth_at_origin,
                   clip_scratch);
    for (size_t k = 1; k < pyramid.size() && polygon.size() >= 3; ++k)
      clip_polygon(polygon, pyramid[k].normal, pyramid[k].offset, clip_scratch);
    if (polygon.size() < 3) continue;
    ClipperLib::Path path;
    path.reserve(polygon.size());
    for (const Vec3& q : polygon) {
      const double s = depth_at_origin + dot(depth_gradient, q);
      if (!(s > 0)) break;
      const ClipperLib::IntPoint point = frame.to_grid(x + (q - x) / s);
      if (path.empty() || !(path.back() == point)) path.push_back(point);
    }
    if (path.size() >= 3 && path.front() == path.back()) path.pop_back();
    if (path.size() < 3 || ClipperLib::Area(path) == 0) continue;
    if (!ClipperLib::Orientation(path)) ClipperLib::ReversePath(path);
    shadows.push_back(std::move(path));
  }
  if (stats) stats->projected += shadows.size();
  if (shadows.empty()) return std::abs(signed_projected_solid_angle(above, n));

  // The visible region, exactly on the grid: the light minus the union of the shadows.
  ClipperLib::Clipper clipper;
  clipper.AddPaths(light_path, ClipperLib::ptSubject, true);
  clipper.AddPaths(shadows, ClipperLib::ptClip, true);
  ClipperLib::Paths visible;
  clipper.Execute(ClipperLib::ctDifference, visible, ClipperLib::pftNonZero,
                  ClipperLib::pftNonZero);
  if (stats) stats->contours += visible.size();

  // 5. Lambert's formula over the contours; holes subtract by their winding.
  double total = 0;
  std::vector<Vec3> relative;
  for (const ClipperLib::Path& contour : visible) {
    relative.clear();
    for (const ClipperLib::IntPoint& q : contour) relative.push_back(frame.from_grid(q) - x);
    total += signed_projected_solid_angle(relative, n);
  }
  // The light's own winding on the grid fixes the sign of a positive result.
  std::vector<Vec3> light_relative;
  for (const ClipperLib::IntPoint& q : light_path[0])
    light_relative.push_back(frame.from_grid(q) - x);
  const double light_sign = signed_projected_solid_angle(light_relative, n) >= 0 ? 1.0 : -1.0;
  return std::max(0.0, light_sign * total);
}

}  // namespace penumbra
