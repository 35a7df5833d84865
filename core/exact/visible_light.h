#pragma once
// The exact direct illumination of a Lambertian receiver by a constant polygonal light with
// occluders: the projected solid angle of the light's visible part from a shading point x with
// unit normal n, integral over the visible directions w of max(0, n.w) dw.
//
// 1. The light polygon is clipped at x's horizon (in the light's plane, the line where x's
//    tangent plane meets it): nothing below contributes.
// 2. The occluders that can cut it come from the shadow-pyramid query (shadow_pyramid.h).
// 3. Each occluder triangle is clipped in 3D to the pyramid's side planes and to the slab of
//    depths s_min <= s <= s_max between x (s = 0) and the light's plane (s = 1), the line
//    query's tolerances (core/lines/shadow_triangle.h: the surface x lies on, and geometry in
//    the light's plane, do not occlude; occluders whose plane passes within s_min of x are seen
//    edge-on). Each clip point on an edge is computed from the edge's endpoints in one canonical
//    order, so two triangles sharing an edge get the same points, bit for bit.
// 4. The clipped part is projected from x onto the light's plane (p = x + (q - x) / s(q)),
//    giving a convex polygon inside the light. Its 2D coordinates in the light's frame are
//    scaled to integers (2^50 across the light: a relative rounding of 1e-15) and the visible
//    region, the light polygon minus the union of the projections, is computed exactly on the
//    integer grid by Clipper (Angus Johnson's library, Debian's libpolyclipping: integer
//    coordinates, 128-bit products, exact predicates; the only rounding is of new intersection
//    points to the grid). Projections of triangles sharing an edge share the integer edge, so
//    the union has no crack between them.
// 5. The visible region's contours (holes wound the other way) go back to 3D and Lambert's
//    formula (core/math/lambert_polygon.h: (1/2) sum_i gamma_i n . unit(v_i x v_{i+1})) is
//    summed over them, holes subtracting by their winding.
//
// Accuracy: the result's relative error is a few 1e-15 times the number of contour vertices,
// plus the grid rounding of intersection points (1e-15 of the light's size each); a visible
// region thinner than the grid (a sliver of width ~1e-15 of the light) is lost or kept whole.

#include <cstdint>
#include <span>
#include <vector>

#include "core/exact/shadow_pyramid.h"
#include "core/lines/line_query.h"
#include "core/math/vec.h"

namespace penumbra {

struct VisibleLightStats {
  uint64_t candidates = 0;  // triangles the pyramid query returned
  uint64_t projected = 0;   // triangles whose clipped part projected to a polygon
  uint64_t contours = 0;    // contours of the visible region
};

// Scratch buffers reused across calls (one per thread).
struct VisibleLightScratch {
  std::vector<uint32_t> candidates;
};

// integral over the visible part of the light of max(0, n.w) dw: 0 when x is not strictly in
// front of the light's emitting side (`emission_normal`). `light_polygon` is convex and planar.
// `query` holds the occluders (lights never occlude).
double visible_projected_solid_angle(const Vec3& x, const Vec3& n,
                                     std::span<const Vec3> light_polygon,
                                     const Vec3& emission_normal, const LineQuery& query,
                                     VisibleLightScratch& scratch,
                                     VisibleLightStats* stats = nullptr);

// The same without occluders (Lambert's formula on the horizon-clipped polygon).
double unoccluded_projected_solid_angle(const Vec3& x, const Vec3& n,
                                        std::span<const Vec3> light_polygon,
                                        const Vec3& emission_normal);

}  // namespace penumbra
