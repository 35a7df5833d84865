#include <cmath>

#include "core/sampling/pattern.h"

namespace penumbra {

// Shirley & Chiu 1997: concentric squares map to concentric circles. The square [-1,1]^2 is split
// into four triangular wedges by its diagonals; in the wedge of the x axis, (a, b) goes to radius
// r = a at angle (pi/4) (b/a), and the other wedges follow by symmetry. Area ratios are kept
// (the Jacobian is constant, pi/4), so strata of the square stay strata of equal area.
Vec2 square_to_disk_concentric(const Vec2& u) {
  double a = 2.0 * u.x - 1.0;
  double b = 2.0 * u.y - 1.0;
  // The centre: both wedge formulas divide by zero there.
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  double radius;
  double angle;
  if (std::abs(a) > std::abs(b)) {
    radius = a;
    angle = (kPi / 4.0) * (b / a);
  } else {
    radius = b;
    angle = (kPi / 2.0) - (kPi / 4.0) * (a / b);
  }
  return {radius * std::cos(angle), radius * std::sin(angle)};
}

}  // namespace penumbra
