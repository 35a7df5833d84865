#pragma once
// Billen & Dutré 2016: analytic line samples on an area light (`line-bd16`).
//
// One estimate: pick a line direction d in the light's plane (Sec. 5.1.1), sample the line's
// perpendicular offset w with density proportional to the chord length l(w) of the light along
// d (Sec. 5.1.2), query the visible intervals of that chord from x (core/lines/line_query.h),
// integrate them in closed form (core/lines/line_integrals.h) and divide by p(w):
//   L ~= integral_visible f G Le dl / p(w),   p(w) = l(w) / area.
//
// Offset density for any convex polygon (quads, triangles, convex polygons) and any direction.
// Project the vertices onto the perpendicular axis p = normal x d: l(w) is piecewise linear and
// concave in w with breakpoints at the projected vertices (between two consecutive breakpoints
// the chord runs between the same two edges). So p(w) is a chain of trapezoids: constant for a
// parallelogram along one of its edges, a triangle (zero at the extremes, 2/A at the middle
// vertex: the paper's triangular pdf) for a triangle, and a trapezoid (rise, plateau, fall) for
// a rotated parallelogram. Sampling picks a piece by its area (the CDF at the breakpoints) and
// inverts the quadratic CDF inside it: with l rising linearly from l0 to l1 over the piece and
// xi in [0,1) the fraction of the piece's area, the fraction s of its width solves
//   l0 s + (l1 - l0) s^2 / 2 = xi (l0 + l1) / 2,  s = xi (l0 + l1) / (l0 + sqrt(l0^2 + xi (l1^2 -
//   l0^2)))
// (the cancellation-free root; s = sqrt(xi) when l0 = 0). The thresholds between pieces are
// the exact cumulative areas of the same trapezoids the density is evaluated from, so the
// sampled histogram and pdf_of_offset agree at the breakpoints (tests: chi-square with many
// samples near them).
//
// Supported: quad and polygon lights (convex, >= 3 vertices) of constant profile, lambert and
// phong receivers. Refused (unsupported() gives the reason): disk lights, gaussian profiles
// (the closed forms assume constant radiance), ggx and any other material.

#include <optional>
#include <string>
#include <vector>

#include "core/lines/line_integrals.h"
#include "core/lines/line_query.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

enum class Bd16Direction {
  U,       // lines along edge1 (quads) or v1 - v0 (polygons), fixed per light
  V,       // lines along edge2 (quads) or v_{last} - v0 (polygons), fixed per light
  Random,  // one direction per shading point: angle pi * direction_u.x from the U direction
};

// A line's perpendicular offset distribution on a polygonal light, for one line direction.
// Offsets w are measured along normalize(cross(light.normal, direction)) from the light's
// first vertex.
class LineOffsetDistribution {
 public:
  LineOffsetDistribution() = default;
  LineOffsetDistribution(const Light& light, const Vec3& direction);

  struct Line {
    double offset = 0;  // w
    double pdf = 0;     // p(w) = l(w) / area, per unit offset length
    Vec3 a, b;          // the chord's endpoints (a -> b along the direction)
  };
  // The line for a uniform u in [0,1): inverse CDF (monotone: stratified u stay stratified).
  // Empty when the light has no area across this direction.
  std::optional<Line> sample(double u) const;
  // p(w), zero outside the light.
  double pdf(double offset) const;
  // Chord of the light at offset w (empty when w is outside).
  std::optional<Line> chord(double offset) const;

  double min_offset() const { return breakpoints_.empty() ? 0 : breakpoints_.front(); }
  double max_offset() const { return breakpoints_.empty() ? 0 : breakpoints_.back(); }
  const std::vector<double>& breakpoints() const { return breakpoints_; }
  const Vec3& direction() const { return direction_; }

 private:
  Vec3 origin_, direction_, across_;
  std::vector<double> along_, offsets_;  // vertex coordinates along d and across (offset)
  std::vector<double> breakpoints_;      // sorted distinct vertex offsets
  std::vector<double> chords_;           // l at each breakpoint
  std::vector<double> cumulative_;       // area up to each breakpoint
  double total_ = 0;                     // area (sum of the trapezoids)
};

// p(w) of the offset of lines along `direction` (in the light's plane) on a polygonal light,
// w measured as in LineOffsetDistribution. For the chi-square test.
double pdf_of_offset(const Light& light, const Vec3& direction, double offset);

// The unit line direction of a mode on a light (direction_u used only by Random).
Vec3 bd16_line_direction(const Light& light, Bd16Direction mode, const Vec2& direction_u);

// Prepared per (shading point, light, direction mode). Usage by the direct-lighting method:
//   if (auto why = Bd16LineSampler::unsupported(light, material)) refuse(*why);
//   Bd16LineSampler sampler(light, material, x, n, wo, Bd16Direction::Random);
//   for each of the N samples: sum += sampler.estimate(offset_u[i], direction_u, query);
//   L = sum / N   (offset_u from generate_1d: stratified offsets; direction_u fixed per point)
// Each estimate is unbiased for the light's direct radiance at x towards wo (unshadowed by
// anything except the LineQuery's occluders), finite for any finite input.
class Bd16LineSampler {
 public:
  // The reason the light or the material cannot be used by line-bd16, empty when supported.
  static std::optional<std::string> unsupported(const Light& light, const Material& material);

  // n: unit shading normal on the side of wo. The light and material must be supported.
  Bd16LineSampler(const Light& light, const Material& material, const Vec3& x, const Vec3& n,
                  const Vec3& wo, Bd16Direction mode);

  // One line sample: offset_u in [0,1) picks the offset, direction_u (Random mode: the same for
  // every sample of the shading point) the direction. Returns integral / p(offset).
  Rgb estimate(double offset_u, const Vec2& direction_u, const LineQuery& query) const;
  // The same without occluders (every line fully visible).
  Rgb estimate_unoccluded(double offset_u, const Vec2& direction_u) const;

 private:
  Rgb estimate_with(double offset_u, const Vec2& direction_u, const LineQuery* query) const;
  const LineOffsetDistribution& distribution_for(const Vec2& direction_u) const;

  const Light* light_;
  LineReceiver receiver_;
  Bd16Direction mode_;
  bool facing_ = false;
  LineOffsetDistribution fixed_;  // U and V modes
  // Random mode: the distribution of the last direction_u (a sampler belongs to one shading
  // point and one thread; estimate() is not for concurrent use).
  mutable LineOffsetDistribution random_;
  mutable double random_key_ = -1;
};

}  // namespace penumbra
