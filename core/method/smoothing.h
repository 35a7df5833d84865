#pragma once
// Salesin & Jarosz 2019's discontinuity-smoothing balance heuristic (Sec. 4.3, Eq. 22-24): the
// BSDF strategy's pdf enters the balance heuristic as p'_B = m^(u) m^(v) p_B, where m^ eases
// from 0 at a discontinuity of the integrand to 1 at distance d_m from it, so that the effective
// integrand w_B f seen by BSDF sampling is continuous. All other strategies keep p'_s = p_s; the
// weights n_s p'_s / sum_k n_k p'_k still sum to one wherever some p'_k > 0 (and fall back to
// the plain balance heuristic where every p'_k is 0).
//
//   m(t) = 2 <t> - <t>^2, <t> = t clamped to [0,1]                      (quadratic ease-out)
//   light edges (Eq. 23):    m((u - u_lo) / d_m) m((u_hi - u) / d_m),    d_m = half the light's
//                                                                       smallest side
//   occluder edges (Eq. 24): m((u - u_r) / (d_m m(d_occ / d_m))), d_occ the length of the
//                            occluded run next to the visible region's boundary u_r: the width
//                            shrinks to 0 where a line slips off an occluder.

#include <algorithm>

#include "core/lines/line_sampling_lines.h"

namespace penumbra {

inline double ease_out(double t) {
  double c = std::clamp(t, 0.0, 1.0);
  return c * (2.0 - c);
}

// m((distance) / width), 1 when the width is 0 (no smoothing) or the distance is beyond it.
inline double ease_out_within(double distance, double width) {
  if (!(width > 0)) return 1.0;
  return ease_out(distance / width);
}

// Light-edge factor along one edge: `position` in [0, side] (world length along the edge).
inline double light_edge_smoothing(double position, double side, double width) {
  return ease_out_within(position, width) * ease_out_within(side - position, width);
}

// Occluder-edge factor (Eq. 24) for a point at t on a traced line of world length
// `line_length`: the boundaries of the visible piece it lies in that are occluder edges (not
// the line's ends, which the light-edge factor handles, and not the horizon, where the
// integrand is continuous) ease in over d_m m(d_occ / d_m). 0 when t is not visible.
double occluder_edge_smoothing(const TracedLine& line, double t, double line_length, double width);

}  // namespace penumbra
