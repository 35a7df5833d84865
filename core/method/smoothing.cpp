#include "core/method/smoothing.h"

namespace penumbra {

double occluder_edge_smoothing(const TracedLine& line, double t, double line_length, double width) {
  int piece = visible_piece_containing(line, t);
  if (piece < 0) return 0;
  const Interval& region = line.visible[size_t(piece)];
  double factor = 1.0;
  // Lower boundary: an occluder edge unless it is the line's start or the horizon.
  if (region.lo > line.horizon_lo) {
    double occluded_from = piece > 0 ? line.visible[size_t(piece) - 1].hi : line.horizon_lo;
    double occluded_run = (region.lo - occluded_from) * line_length;
    factor *= ease_out_within((t - region.lo) * line_length,
                              width * ease_out_within(occluded_run, width));
  }
  if (region.hi < line.horizon_hi) {
    double occluded_to = size_t(piece) + 1 < line.visible.size()
                             ? line.visible[size_t(piece) + 1].lo
                             : line.horizon_hi;
    double occluded_run = (occluded_to - region.hi) * line_length;
    factor *= ease_out_within((region.hi - t) * line_length,
                              width * ease_out_within(occluded_run, width));
  }
  return factor;
}

}  // namespace penumbra
