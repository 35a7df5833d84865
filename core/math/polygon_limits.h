#pragma once
// Capacity of the fixed-size arrays in the polygon samplers. A convex polygon light has at most
// kMaxPolygonVertices vertices; clipping at the horizon adds at most one. Fixed arrays keep the
// per-shading-point set-up free of heap allocation (it runs once per shading point and light).

namespace penumbra {

inline constexpr int kMaxPolygonVertices = 16;
inline constexpr int kMaxClippedPolygonVertices = kMaxPolygonVertices + 1;

}  // namespace penumbra
