#include "core/math/projected_solid_angle.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/math/edge_ellipse.h"
#include "core/math/horizon_clip.h"
#include "core/math/plane_vectors.h"

namespace penumbra {

namespace {

// Bisector of the unit directions a and b (at most 180 degrees apart, counter-clockwise from a):
// their sum (Peters Eq. 8), or near 180 degrees the rotated difference, the stable form there.
Vec2 bisector(const Vec2& a, const Vec2& b) {
  return normalize2(dot2(a, b) >= 0 ? add2(a, b) : Vec2{b.y - a.y, a.x - b.x});
}

// The root t of a0 + a1 t + a2 t^2 = 0 that has the sign of `direction` (or is 0) and, of two
// such roots, the smaller one; both roots in the stable form. Empty if there is none. Used for
// steps w = w_n + t R w_n from a direction w_n whose quadratic vanishes at t = 0 when a0 = 0:
// the root selection by the sign of a1 (Blinn; Peters Eq. 6) fails where a1, the density, is
// rounding noise (at the ends of the polygon, where the ellipses meet).
std::optional<double> step_root(double a0, double a1, double a2, double direction) {
  double root = safe_sqrt(difference_of_products(a1, a1, 4.0 * a0, a2));
  double q_half = -0.5 * (a1 + std::copysign(root, a1));
  double t1 = q_half != 0 ? a0 / q_half : 0.0;
  double t2 = a2 != 0 ? q_half / a2 : 0.0;
  bool t1_ok = t1 * direction >= 0 && std::isfinite(t1);
  bool t2_ok = t2 * direction > 0 && std::isfinite(t2);
  if (t1_ok && (!t2_ok || std::abs(t1) <= std::abs(t2))) return t1;
  if (t2_ok) return t2;
  return std::nullopt;
}

// w is a non-zero finite direction in the sector from low to high (counter-clockwise).
bool inside_bracket(const Vec2& low, const Vec2& w, const Vec2& high) {
  double l2 = dot2(w, w);
  return l2 > 0 && std::isfinite(l2) && cross2_plain(low, w) >= 0 && cross2_plain(w, high) >= 0;
}

// dot(N, v0) for the polygon's area vector N: its sign is that of det(v0, v1, v2) for consecutive
// vertices of a planar convex polygon, 0 when the origin lies in the polygon's plane. Formed from
// edge vectors to stay accurate for tiny, distant polygons.
double plane_offset(std::span<const Vec3> v) {
  Vec3 area_vector;
  for (size_t i = 1; i + 1 < v.size(); ++i) area_vector += cross(v[i] - v[0], v[i + 1] - v[0]);
  return dot(area_vector, v[0]);
}

// The polygon clipped to z >= 0 by the one horizon clip (core/math/horizon_clip.h; strict
// crossings only: a vertex on the horizon is kept once, as itself). The number of vertices
// written to `out` (which holds vertices.size() + 1), 0 when fewer than 3 remain.
int clip_to_upper_hemisphere(std::span<const Vec3> vertices, std::span<Vec3> out) {
  int count = int(clip_polygon_to_horizon(vertices, Vec3{0, 0, 1}, out));
  return count < 3 ? 0 : count;
}

}  // namespace

double projected_solid_angle(std::span<const Vec3> vertices_local) {
  int n = static_cast<int>(vertices_local.size());
  if (n < 3 || n > kMaxPolygonVertices) return 0.0;
  // Seen edge-on (the shading point in the polygon's plane): no projected solid angle.
  if (!(plane_offset(vertices_local) != 0)) return 0.0;
  std::array<Vec3, kMaxClippedPolygonVertices> clipped;
  int m = clip_to_upper_hemisphere(vertices_local, clipped);
  // Lambert's formula: each edge contributes the projected solid angle of the spherical triangle
  // (zenith, v_j, v_{j+1}).
  double sum = 0;
  for (int j = 0; j < m; ++j) {
    const Vec3& a = clipped[j];
    const Vec3& b = clipped[(j + 1) % m];
    Vec3 normal = cross_accurate(a, b);
    double l = length(normal);
    if (!(l > 0)) continue;
    sum += normal.z / l * std::atan2(l, dot(a, b));
  }
  double result = 0.5 * std::abs(sum);
  return std::isfinite(result) ? result : 0.0;
}

ProjectedSolidAngleSampler::ProjectedSolidAngleSampler(std::span<const Vec3> vertices_local,
                                                       int iterations)
    : iterations_(iterations) {
  int n = static_cast<int>(vertices_local.size());
  if (n < 3 || n > kMaxPolygonVertices) return;

  // Orientation: the projection is counter-clockwise (seen from +z) iff det(v0, v1, v2) > 0 for
  // consecutive vertices, i.e. iff the plane offset is positive.
  double offset = plane_offset(vertices_local);
  if (!(offset != 0) || !std::isfinite(offset)) return;  // seen edge-on, or not finite

  // Clip the polygon at the horizon (Sec. 3.1).
  std::array<Vec3, kMaxClippedPolygonVertices> clipped;
  int m = clip_to_upper_hemisphere(vertices_local, clipped);
  if (m == 0) return;
  if (offset < 0) std::reverse(clipped.begin(), clipped.begin() + m);

  // Drop vertices in the same direction as their predecessor (a vertex on the horizon that
  // clipping repeated, or a zero-length edge): they would give edges without a great circle.
  std::array<Vec3, kMaxClippedPolygonVertices> v;
  int count = 0;
  for (int i = 0; i < m; ++i) {
    if (count > 0) {
      const Vec3& previous = v[count - 1];
      if (cross(previous, clipped[i]) == Vec3{} && dot(previous, clipped[i]) > 0) continue;
    }
    v[count++] = clipped[i];
  }
  while (count > 1 && cross(v[count - 1], v[0]) == Vec3{} && dot(v[count - 1], v[0]) > 0) --count;
  if (count < 3) return;
  m = count;

  std::array<EdgeEllipse, kMaxClippedPolygonVertices> ellipses;
  bool has_inner = false;
  for (int j = 0; j < m; ++j) {
    ellipses[j] = edge_ellipse(v[j], v[(j + 1) % m]);
    has_inner = has_inner || ellipses[j].c < 0;
  }

  if (!has_inner) {
    // Central case (Fig. 3a): one sector per edge, bounded by that edge's ellipse alone. Edges
    // through the zenith (c == 0) give empty sectors.
    central_ = true;
    for (int j = 0; j < m; ++j)
      add_sector(xy(v[j]), xy(v[(j + 1) % m]), EdgeEllipse{}, ellipses[j]);
  } else {
    // Decentral case (Fig. 3b): edges with c > 0 run counter-clockwise in azimuth and form the
    // outer chain, the others (c <= 0) run back and form the inner chain. Both chains go from
    // the clockwise end of the polygon to its counter-clockwise end; merging their vertices by
    // azimuth gives the sectors, each with one inner and one outer ellipse (Sec. 3.7).
    int start = 0;
    for (int j = 0; j < m; ++j) {
      if (ellipses[j].c > 0 && ellipses[(j + m - 1) % m].c <= 0) {
        start = j;
        break;
      }
    }
    int outer_count = 0;  // edges in the outer chain
    while (outer_count < m && ellipses[(start + outer_count) % m].c > 0) ++outer_count;
    int inner_count = m - outer_count;
    auto outer_vertex = [&](int a) { return xy(v[(start + a) % m]); };
    auto inner_vertex = [&](int b) { return xy(v[(start - b + m) % m]); };
    auto outer_edge = [&](int a) { return ellipses[(start + a) % m]; };
    auto inner_edge = [&](int b) { return ellipses[(start - b - 1 + m) % m]; };
    int a = 0, b = 0;
    Vec2 s0 = outer_vertex(0);
    while (a < outer_count || b < inner_count) {
      bool take_outer;
      if (a == outer_count)
        take_outer = false;
      else if (b == inner_count)
        take_outer = true;
      else
        take_outer = cross2(outer_vertex(a + 1), inner_vertex(b + 1)) >= 0;
      Vec2 s1 = take_outer ? outer_vertex(a + 1) : inner_vertex(b + 1);
      add_sector(s0, s1, inner_edge(std::min(b, inner_count - 1)),
                 outer_edge(std::min(a, outer_count - 1)));
      if (take_outer)
        ++a;
      else
        ++b;
      s0 = s1;
    }
  }
  if (!(total_area_ > 0) || !std::isfinite(total_area_)) {
    total_area_ = 0;
    sector_count_ = 0;
  }
}

void ProjectedSolidAngleSampler::add_sector(const Vec2& s0, const Vec2& s1,
                                            const EdgeEllipse& inner, const EdgeEllipse& outer) {
  Sector& s = sectors_[sector_count_++];
  // Areas use the vertices' xy as they are (normalizing them costs accuracy in horizon slivers);
  // the initialization and the safeguard use unit directions.
  s.s0 = s0;
  s.s1 = s1;
  s.s0_unit = normalize2(s0);
  s.s1_unit = normalize2(s1);
  s.half = bisector(s.s0_unit, s.s1_unit);
  s.inner = inner;
  s.outer = outer;
  // Sector areas by Peters Eq. 1; the difference of outer and inner in the decentral case. A
  // single ellipse also keeps its angle in the circle it maps to (for Sec. 3.2's inversion).
  double area;
  if (inner.c == 0) {
    double abs_c = std::abs(outer.c);
    s.angle =
        std::max(0.0, std::atan2(abs_c * cross2(s.s0, s.s1), ellipse_form(outer, s.s0, s.s1)));
    area = 0.5 * abs_c * s.angle;
  } else {
    area = area_up_to(s, s.s1);
  }
  s.area = std::isfinite(area) ? std::max(0.0, area) : 0.0;
  total_area_ += s.area;
}

double ProjectedSolidAngleSampler::area_up_to(const Sector& s, const Vec2& w) const {
  if (s.inner.c == 0) return ellipse_sector_area(s.outer, s.s0, w);
  // Outer minus inner ellipse sector (Eq. 1 twice), rearranged so that nearly equal ellipses do
  // not cancel: with alpha_l = atan2(|c_l| cross(s0, w), s0^T C_l w),
  //   (|c_o| alpha_o - |c_i| alpha_i) / 2 = ((|c_o| - |c_i|) alpha_o + |c_i| (alpha_o - alpha_i)) /
  //   2,
  // |c_o| - |c_i| = (|m_i|^2 - |m_o|^2) / (|c_o| + |c_i|) (unit normals), and alpha_o - alpha_i
  // as one arctangent. For a sliver between the horizon (m_o = 0) and an edge just above it
  // every term keeps its relative precision, where the plain difference loses all of it.
  const EdgeEllipse& o = s.outer;
  const EdgeEllipse& i = s.inner;
  double co = std::abs(o.c), ci = std::abs(i.c);
  double cr = cross2(s.s0, w);
  double xo = ellipse_form(o, s.s0, w), xi = ellipse_form(i, s.s0, w);
  double yo = co * cr, yi = ci * cr;
  // |c_o| - |c_i|: directly where the ellipses are thin (great circles near the zenith, small
  // |c|, where |m|^2 ~ 1 and the m form cancels), else from the m's (the form above); each is
  // used where its rounding error, eps max(|c|) or eps max(|m|^2) / (|c_o| + |c_i|), is smaller.
  double mi2 = dot2(i.m, i.m), mo2 = dot2(o.m, o.m);
  double c_difference =
      std::max(co, ci) * (co + ci) < std::max(mi2, mo2) ? co - ci : (mi2 - mo2) / (co + ci);
  double mi = dot2(i.m, s.s0) * dot2(i.m, w), mo = dot2(o.m, s.s0) * dot2(o.m, w);
  // |c_o| x_i - |c_i| x_o, the factor of sin(alpha_o - alpha_i) besides cross(s0, w).
  double mixed = -co * ci * c_difference * dot2(s.s0, w) + co * mi - ci * mo;
  double alpha_o = std::atan2(yo, xo);
  double alpha_difference = std::atan2(cr * mixed, xo * xi + yo * yi);
  return 0.5 * (c_difference * alpha_o + ci * alpha_difference);
}

int ProjectedSolidAngleSampler::select_sector(double u0, double* area_in_sector) const {
  double target = u0 * total_area_;
  double before = 0, chosen_before = 0;
  int chosen = -1;
  for (int i = 0; i < sector_count_; ++i) {
    if (!(sectors_[i].area > 0)) continue;
    chosen = i;
    chosen_before = before;
    if (target < before + sectors_[i].area) break;
    before += sectors_[i].area;
  }
  if (chosen < 0) return -1;
  // Past the end by rounding of the running sum: the last sector, at its end.
  *area_in_sector = std::clamp(target - chosen_before, 0.0, sectors_[chosen].area);
  return chosen;
}

Vec2 ProjectedSolidAngleSampler::single_ellipse_direction(const Sector& s, double area) const {
  // Central case (Sec. 3.2): the linear map that takes the ellipse to a unit circle turns the
  // sector area into an angle, alpha = angle * area / sector area. Solving Peters' 2x2 system
  //   (|c| cross(s0, w), s0^T C w) ~ (sin alpha, cos alpha)
  // gives w = |c| cos(alpha) s0 + sin(alpha) R C s0.
  double alpha = s.area > 0 ? s.angle * std::clamp(area / s.area, 0.0, 1.0) : 0.0;
  Vec2 c_s0 = apply_ellipse(s.outer, s.s0);
  return add2(scale2(s.s0, std::abs(s.outer.c) * std::cos(alpha)),
              scale2(rotate90(c_s0), std::sin(alpha)));
}

Vec2 ProjectedSolidAngleSampler::two_ellipse_direction(const Sector& s, double area) const {
  const EdgeEllipse& inner = s.inner;
  const EdgeEllipse& outer = s.outer;
  const Vec2& s0 = s.s0_unit;
  const Vec2& s1 = s.s1_unit;
  const Vec2& half = s.half;

  // Two-quad initialization (Sec. 3.4): the points where the rays through s0, s_h and s1 meet
  // the inner and outer ellipses span two quads; the quad that holds the area is sampled
  // uniformly (area rescaled from the sector to the quads).
  auto radius = [](const EdgeEllipse& e, const Vec2& direction) {
    return std::sqrt(ellipse_radius_squared(e, direction));
  };
  double inner_r0 = radius(inner, s0), inner_rh = radius(inner, half), inner_r1 = radius(inner, s1);
  double outer_r0 = radius(outer, s0), outer_rh = radius(outer, half), outer_r1 = radius(outer, s1);
  Vec2 inner0 = scale2(s0, inner_r0), inner_half = scale2(half, inner_rh),
       inner1 = scale2(s1, inner_r1);
  Vec2 outer0 = scale2(s0, outer_r0), outer_half = scale2(half, outer_rh),
       outer1 = scale2(s1, outer_r1);
  double quad0 = 0.5 * (cross2_plain(outer0, outer_half) - cross2_plain(inner0, inner_half));
  double quad1 = 0.5 * (cross2_plain(outer_half, outer1) - cross2_plain(inner_half, inner1));
  double quads = quad0 + quad1;
  double quad_area = (s.area > 0 && quads > 0) ? area * (quads / s.area) : 0.0;
  bool second = quad_area > quad0;
  // Measured from s1, clockwise: a negative signed area (never positive by rounding).
  if (second) quad_area = std::min(0.0, quad_area - quads);
  Vec2 inner_k = second ? inner1 : inner0;
  Vec2 outer_k = second ? outer1 : outer0;
  // Quad edges r_l^T q = D_l (Peters Supplement A.4, scaled by c_l^2): r_l = C (p_h + p_k),
  // D_l = p_h^T r_l. Peters' Q = D_o R p_ok r_i^T - (D_i R p_ik + 2 A_q r_i) r_o^T, written for
  // w = s_k + t R s_k (s_k unit) as b0 + b1 t + b2 t^2 = 0 and solved for the small root like
  // the iteration below: at the polygon's ends the two roots of Q coincide (p_ik = p_ok).
  Vec2 r_inner = apply_ellipse(inner, add2(inner_half, inner_k));
  Vec2 r_outer = apply_ellipse(outer, add2(outer_half, outer_k));
  double d_inner = dot2(inner_half, r_inner);
  double d_outer = dot2(outer_half, r_outer);
  const Vec2& boundary = second ? s1 : s0;
  Vec2 normal = rotate90(boundary);
  double ia = dot2(r_inner, boundary), ie = dot2(r_inner, normal);
  double oa = dot2(r_outer, boundary), oe = dot2(r_outer, normal);
  double outer_length = second ? outer_r1 : outer_r0;
  double inner_length = second ? inner_r1 : inner_r0;
  double b0 = -2.0 * quad_area * ia * oa;
  double b1 = d_outer * outer_length * ia - d_inner * inner_length * oa -
              2.0 * quad_area * (ia * oe + ie * oa);
  double b2 = d_outer * outer_length * ie - d_inner * inner_length * oe - 2.0 * quad_area * ie * oe;
  std::optional<double> t0 = step_root(b0, b1, b2, quad_area);
  Vec2 w = t0 ? add2(boundary, scale2(normal, *t0)) : half;
  // Safeguard (ours, not in the paper): the area up to w grows monotonically with the angle, so
  // the residual's sign tells on which side of w the answer lies. An iterate that leaves the
  // sector (or is not finite) is replaced by the bisector of the bracket those signs give. This
  // only acts where rounding swamps the area: slivers of ~1e-17 sr at the horizon or seen
  // nearly edge-on, where tangent lines become parallel (Sec. 3.5).
  Vec2 low = s0, high = s1;
  if (!inside_bracket(s0, w, s1)) w = half;

  // Tangent-line iteration (Sec. 3.3): replace both ellipses by their tangents at the current
  // direction w_n and find w_{n+1} such that the area between the tangents in the sector
  // (w_n, w_{n+1}) is the residual A_delta (Eq. 7). In the scaled form (C_l -> c_l^2 C_l) the
  // condition is w^T T w = 0 with (Eq. 5)
  //   T = R w_n g^T - 2 A_delta p q^T,  g = c_o^2 C_i w_n - c_i^2 C_o w_n,  p = C_o w_n,
  //   q = C_i w_n.
  // Instead of Peters' Eq. 6 we solve it for the step t in w = w_n + t R w_n:
  //   a0 + a1 t + a2 t^2 = 0,  a0 = -2 A_delta (p.w_n)(q.w_n),
  //   a1 = g.w_n - 2 A_delta ((p.w_n)(q.e) + (p.e)(q.w_n)),  a2 = g.e - 2 A_delta (p.e)(q.e),
  // with e = R w_n, taking the root that vanishes with A_delta (the one Eq. 6 selects). The
  // reason is precision: in thin slivers (inner and outer ellipse nearly equal; a small light
  // seen at a grazing angle) the two roots of Eq. 5 nearly coincide and Eq. 6's discriminant
  // cancels, leaving ~1e-5 backward errors in double; the step form keeps full precision.
  double co2 = outer.c * outer.c, ci2 = inner.c * inner.c;
  double converged = 1e-13 * s.area;
  Vec2 best = w;
  double best_residual = std::numeric_limits<double>::infinity();
  bool unverified_risky_step = false;
  for (int iteration = 0; iteration < iterations_; ++iteration) {
    // Past two iterations, a step only runs if the previous residual was large: convergence is
    // cubic (Sec. 3.5), so from a residual below 1e-6 of the sector the step just taken left
    // ~1e-12 (measured in projected_solid_angle_test.cpp). This keeps the third iteration's two
    // arctangents for the few percent of samples that need it.
    if (iteration >= 2 && std::abs(best_residual) <= 1e-6 * s.area) break;
    Vec2 wn = normalize2(w);
    double residual = area - area_up_to(s, wn);
    unverified_risky_step = false;
    // Where the density vanishes (the polygon's clockwise and counter-clockwise ends, Sec. 3.5,
    // above all a clipped vertex where an edge's ellipse touches the horizon circle) the tangent
    // lines are a poor model and a step can make things worse; the best iterate is kept.
    if (std::abs(residual) < std::abs(best_residual)) {
      best = wn;
      best_residual = residual;
    }
    // Converged to rounding level: further steps would only move w by rounding noise.
    if (std::abs(residual) <= converged) {
      w = wn;
      break;
    }
    if (residual > 0)
      low = wn;
    else
      high = wn;
    Vec2 e = rotate90(wn);
    Vec2 p = apply_ellipse(outer, wn), q = apply_ellipse(inner, wn);
    // g = c_o^2 C_i w_n - c_i^2 C_o w_n; its c_o^2 c_i^2 w_n terms cancel exactly, so they are
    // left out (they would swamp g for a sliver along the horizon, where g is tiny).
    Vec2 g =
        sub2(scale2(inner.m, co2 * dot2(inner.m, wn)), scale2(outer.m, ci2 * dot2(outer.m, wn)));
    double pw = dot2(p, wn), qw = dot2(q, wn), pe = dot2(p, e), qe = dot2(q, e);
    double a0 = -2.0 * residual * pw * qw;
    double a1 = dot2(g, wn) - 2.0 * residual * (pw * qe + pe * qw);
    double a2 = dot2(g, e) - 2.0 * residual * pe * qe;
    // The step goes the way the residual asks (counter-clockwise for a positive residual).
    std::optional<double> step = step_root(a0, a1, a2, residual);
    Vec2 next = step ? add2(wn, scale2(e, *step)) : Vec2{};  // none: bisect below
    // Risky: the quadratic term dominates (vanishing density), so the model decides the step.
    unverified_risky_step = !(a1 * a1 > 16.0 * std::abs(a0 * a2));
    // A step that leaves the sector (or is not finite) is replaced by bisection.
    if (!inside_bracket(s0, next, s1)) {
      next = bisector(normalize2(low), normalize2(high));
      unverified_risky_step = true;
    }
    w = next;
  }
  // The last step was not checked by a following iteration: check it if it was risky.
  if (unverified_risky_step) {
    double residual = area - area_up_to(s, normalize2(w));
    if (!(std::abs(residual) < std::abs(best_residual))) w = best;
  } else if (std::abs(best_residual) <= converged) {
    w = best;
  }
  return w;
}

std::optional<Vec3> ProjectedSolidAngleSampler::sample(const Vec2& u) const {
  double area = 0;
  int index = select_sector(u.x, &area);
  if (index < 0) return std::nullopt;
  const Sector& s = sectors_[index];
  bool single = s.inner.c == 0;
  Vec2 w = single ? single_ellipse_direction(s, area) : two_ellipse_direction(s, area);
  // Radius: rho^2 uniform between the inner and outer ellipse (Sec. 3.3), z from 1 - rho^2
  // formed without cancellation (Eq. 2).
  double inner_r2 = 0.0, inner_z2 = 1.0, outer_r2, outer_z2;
  if (!single) radius_squared_and_complement(s.inner, w, &inner_r2, &inner_z2);
  radius_squared_and_complement(s.outer, w, &outer_r2, &outer_z2);
  double rho2 = (1.0 - u.y) * inner_r2 + u.y * outer_r2;
  double z2 = (1.0 - u.y) * inner_z2 + u.y * outer_z2;
  Vec2 w_unit = normalize2(w);
  double rho = std::sqrt(std::max(0.0, rho2));
  // rho^2 + z^2 = 1 up to rounding (r^2 and 1 - r^2 share their denominator): no normalization.
  Vec3 direction{rho * w_unit.x, rho * w_unit.y, std::sqrt(std::max(0.0, z2))};
  if (!is_finite(direction)) return std::nullopt;
  return direction;
}

std::optional<Vec2> ProjectedSolidAngleSampler::invert(const Vec3& direction) const {
  if (!(total_area_ > 0) || !(direction.z >= 0)) return std::nullopt;
  double l2 = length_squared(direction);
  if (!(l2 > 0)) return std::nullopt;
  Vec2 w = xy(direction);
  double rho2 = dot2(w, w) / l2;
  // The sector holding w's azimuth, and the area of the sectors before it.
  int index = -1, first = -1, last = -1;
  double before = 0, before_index = 0, before_last = 0;
  for (int i = 0; i < sector_count_; ++i) {
    const Sector& s = sectors_[i];
    if (!(s.area > 0)) continue;
    if (first < 0) first = i;
    last = i;
    before_last = before;
    bool inside = (rho2 == 0 && central_) ||
                  (cross2(s.s0, w) >= 0 && cross2(w, s.s1) >= 0 && dot2(w, s.half) >= 0);
    if (inside && index < 0) {
      index = i;
      before_index = before;
    }
    before += s.area;
  }
  if (index < 0 && first >= 0) {
    // Just outside the polygon's clockwise or counter-clockwise end by rounding (a sample drawn
    // at u.x = 0 or 1): the end itself. Farther out, w is not in the polygon.
    Vec2 unit = normalize2(w);
    const double kRounding = 1e-9;
    if (std::abs(cross2(sectors_[first].s0_unit, unit)) <= kRounding &&
        dot2(sectors_[first].s0_unit, unit) > 0) {
      index = first;
      before_index = 0;
    } else if (std::abs(cross2(sectors_[last].s1_unit, unit)) <= kRounding &&
               dot2(sectors_[last].s1_unit, unit) > 0) {
      index = last;
      before_index = before_last;
    } else {
      return std::nullopt;
    }
  }
  if (index < 0) return std::nullopt;
  const Sector& s = sectors_[index];
  bool single = s.inner.c == 0;
  double area = rho2 == 0 ? 0.0 : std::clamp(area_up_to(s, w), 0.0, s.area);
  double inner_r2 = single ? 0.0 : ellipse_radius_squared(s.inner, w);
  double outer_r2 = rho2 == 0 ? 1.0 : ellipse_radius_squared(s.outer, w);
  double u1 = outer_r2 > inner_r2 ? (rho2 - inner_r2) / (outer_r2 - inner_r2) : 0.0;
  return Vec2{std::clamp((before_index + area) / total_area_, 0.0, 1.0), std::clamp(u1, 0.0, 1.0)};
}

double ProjectedSolidAngleSampler::area_cancellation(double u0) const {
  double area = 0;
  int index = select_sector(u0, &area);
  if (index < 0) return 1.0;
  const Sector& s = sectors_[index];
  return std::abs(ellipse_sector_area(s.outer, s.s0, s.s1)) / s.area;
}

double ProjectedSolidAngleSampler::backward_error(const Vec2& u, const Vec3& direction) const {
  double area = 0;
  int index = select_sector(u.x, &area);
  if (index < 0) return 0.0;
  const Sector& s = sectors_[index];
  return std::abs(area - area_up_to(s, xy(direction))) / s.area;
}

}  // namespace penumbra
