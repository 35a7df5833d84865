// The shadow-pyramid query over the line query's BVH8 (see the header).

#include "core/exact/shadow_pyramid.h"

#include <cmath>

namespace penumbra {

std::vector<HalfSpace> shadow_pyramid(const Vec3& x, std::span<const Vec3> light_polygon) {
  std::vector<HalfSpace> planes;
  const size_t n = light_polygon.size();
  if (n < 3) return planes;
  Vec3 centroid{0, 0, 0};
  for (const Vec3& v : light_polygon) centroid += v;
  centroid = centroid / double(n);
  // The light's plane, x's side inside.
  Vec3 light_normal =
      cross(light_polygon[1] - light_polygon[0], light_polygon[2] - light_polygon[0]);
  double x_height = dot(light_normal, x - light_polygon[0]);
  if (!(std::abs(x_height) > 0) || !std::isfinite(x_height)) return planes;
  if (x_height > 0) light_normal = -light_normal;  // inside: n.p <= n.v0, x strictly inside
  planes.push_back({light_normal, dot(light_normal, light_polygon[0])});
  for (size_t i = 0; i < n; ++i) {
    const Vec3& a = light_polygon[i];
    const Vec3& b = light_polygon[(i + 1) % n];
    Vec3 normal = cross(a - x, b - x);
    if (!(length_squared(normal) > 0)) continue;  // x on the edge's line: no side there
    if (dot(normal, centroid - x) > 0) normal = -normal;
    planes.push_back({normal, dot(normal, x)});
  }
  return planes;
}

namespace {

Vec3 componentwise_abs(const Vec3& v) {
  return {std::abs(v.x), std::abs(v.y), std::abs(v.z)};
}

// True when the box (centre c, half extent e, padded) lies entirely outside one plane.
bool box_outside(std::span<const HalfSpace> pyramid, const Vec3& c, const Vec3& e) {
  for (const HalfSpace& plane : pyramid) {
    const Vec3 a = componentwise_abs(plane.normal);
    const double reach = a.x * e.x + a.y * e.y + a.z * e.z;
    // The float boxes and the plane offset carry rounding: a margin of a few ulps of the terms.
    const double margin = 1e-12 * (std::abs(plane.offset) + dot(a, componentwise_abs(c)) + reach);
    if (plane.side(c) - reach > margin) return true;
  }
  return false;
}

bool triangle_outside(std::span<const HalfSpace> pyramid, const OccluderTriangle& t) {
  const Vec3 v0 = t.vertex(0), v1 = t.vertex(1), v2 = t.vertex(2);
  for (const HalfSpace& plane : pyramid)
    if (plane.side(v0) > 0 && plane.side(v1) > 0 && plane.side(v2) > 0) return true;
  return false;
}

}  // namespace

void occluders_in_pyramid(const LineQuery& query, std::span<const HalfSpace> pyramid,
                          std::vector<uint32_t>& out) {
  out.clear();
  const std::vector<LineQuery::Node>& nodes = query.nodes();
  const std::vector<OccluderTriangle>& triangles = query.triangles();
  if (nodes.empty() || pyramid.empty()) return;
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t code = stack.back();
    stack.pop_back();
    if (code & LineQuery::kLeafFlag) {
      const uint32_t first = (code & ~LineQuery::kLeafFlag) >> LineQuery::kCountBits;
      const uint32_t count = (code & ((1u << LineQuery::kCountBits) - 1)) + 1;
      for (uint32_t i = first; i < first + count; ++i)
        if (!triangle_outside(pyramid, triangles[i])) out.push_back(i);
      continue;
    }
    const LineQuery::Node& node = nodes[code];
    for (int slot = 0; slot < LineQuery::kWidth; ++slot) {
      if (std::isnan(node.center[0][slot])) continue;  // empty slot
      const Vec3 c{node.center[0][slot], node.center[1][slot], node.center[2][slot]};
      const Vec3 e{node.extent[0][slot], node.extent[1][slot], node.extent[2][slot]};
      if (!box_outside(pyramid, c, e)) stack.push_back(node.child[slot]);
    }
  }
}

}  // namespace penumbra
