#pragma once
// Lambert's closed form for a planar polygon: the form factor from a differential area at x
// (unit normal n) to the polygon, and the unoccluded direct radiance it gives a Lambertian
// receiver under a constant, one-sided Lambertian emitter.
//
// Derivation. The irradiance from a constant radiance Le over the polygon's solid angle P is
// E = Le * integral_P max(0, n.w) dw. With the polygon clipped to the upper hemisphere of n
// (everything below contributes nothing), Stokes' theorem turns the projected solid angle into a
// sum over the edges of the clipped spherical polygon (Lambert 1760; Arvo 1995 Eq. 2):
//   integral_P n.w dw = (1/2) sum_i gamma_i n . unit(v_i x v_{i+1}),
// gamma_i the angle between v_i and v_{i+1} (vectors from x to consecutive vertices). The form
// factor is F = (1/pi) integral_P n.w dw = (1/(2 pi)) |sum_i gamma_i n . unit(v_i x v_{i+1})|
// (the absolute value makes it independent of the winding). Then E = pi Le F and the radiance
// reflected by a Lambertian receiver is L = (albedo / pi) E = albedo * Le * F.
//
// Double precision; no heap allocation for polygons of up to 32 vertices.

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "core/math/horizon_clip.h"
#include "core/math/vec.h"

namespace penumbra {

// (1/(2 pi)) |sum_i gamma_i n . unit(v_i x v_{i+1})| over an already clipped polygon.
inline double clipped_polygon_form_factor(std::span<const Vec3> relative_vertices, const Vec3& n) {
  size_t size = relative_vertices.size();
  if (size < 3) return 0;
  double sum = 0;
  for (size_t i = 0; i < size; ++i) {
    const Vec3& a = relative_vertices[i];
    const Vec3& b = relative_vertices[(i + 1) % size];
    Vec3 c = cross_accurate(a, b);
    double c_length = length(c);
    if (!(c_length > 0)) continue;  // zero-length edge, or an edge through x (degenerate)
    double gamma = std::atan2(c_length, dot(a, b));
    sum += gamma * dot(n, c) / c_length;
  }
  return std::abs(sum) / (2.0 * kPi);
}

// Form factor from the differential area at x (unit normal n) to the polygon `vertices`
// (planar, convex or not, either winding), the polygon clipped at the horizon of x. In [0, 1].
inline double lambert_polygon_form_factor(const Vec3& x, const Vec3& n,
                                          std::span<const Vec3> vertices) {
  size_t size = vertices.size();
  if (size < 3) return 0;
  constexpr size_t kInline = 32;
  std::array<Vec3, kInline> relative_inline;
  std::array<Vec3, kInline + 1> clipped_inline;
  std::vector<Vec3> relative_heap, clipped_heap;
  std::span<Vec3> relative, clipped;
  if (size <= kInline) {
    relative = std::span<Vec3>(relative_inline.data(), size);
    clipped = std::span<Vec3>(clipped_inline.data(), size + 1);
  } else {
    relative_heap.resize(size);
    clipped_heap.resize(size + 1);
    relative = relative_heap;
    clipped = clipped_heap;
  }
  for (size_t i = 0; i < size; ++i) relative[i] = vertices[i] - x;
  // Clip the polygon at the horizon plane of x.
  size_t clipped_size = clip_polygon_to_horizon(relative, n, clipped);
  return std::min(1.0, clipped_polygon_form_factor(clipped.first(clipped_size), n));
}

// Unoccluded radiance reflected towards any direction by a Lambertian receiver (albedo, at x
// with unit normal n) lit by a polygon of constant radiance `emitted` that emits on one side only,
// along `emission_normal`: albedo * emitted * F, and 0 when x is not strictly in front.
inline Rgb lambert_polygon_radiance(const Rgb& albedo, const Rgb& emitted, const Vec3& x,
                                    const Vec3& n, std::span<const Vec3> vertices,
                                    const Vec3& emission_normal) {
  if (vertices.size() < 3 || !(dot(emission_normal, x - vertices[0]) > 0)) return {0, 0, 0};
  return albedo * emitted * lambert_polygon_form_factor(x, n, vertices);
}

}  // namespace penumbra
