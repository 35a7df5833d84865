#include "tools/ltc_fit/ltc_fitter.h"

#include <algorithm>
#include <cmath>

#include "core/materials/ggx.h"

namespace penumbra::ltc_fit {
namespace {

Vec3 view_direction(double cos_theta) {
  return {safe_sqrt(1.0 - cos_theta * cos_theta), 0.0, cos_theta};
}

Vec3 reflect_about(const Vec3& w, const Vec3& axis) {
  return 2.0 * dot(w, axis) * axis - w;
}

// The specular lobe times cosine with F = 1: D G2 / (4 cos_o cos_i) * cos_i; 0 below the horizon.
double lobe_times_cosine(const Vec3& wo, const Vec3& wi, double alpha) {
  if (!(wi.z > 0)) return 0;
  return ggx_specular_without_fresnel(wo, wi, alpha) * wi.z;
}

// Density of wi = reflect(wo, h), h from visible-normal sampling, over the whole sphere (also
// below the horizon, where the sample is wasted but still drawn): G1(wo) D(h) / (4 cos_o) for
// the half vector of a microfacet that exists (h.z > 0) and faces wo; 0 elsewhere. (Near grazing
// views, below-horizon directions also have half vectors with h.z < 0: the sampler never draws
// them, although the formula for D alone would be positive there.)
double visible_normal_reflection_density(const Vec3& wo, const Vec3& wi, double alpha) {
  Vec3 h = wo + wi;
  double h_length = length(h);
  if (!(h_length > 0)) return 0;
  h /= h_length;
  if (!(dot(wo, h) > 0) || !(h.z > 0)) return 0;
  return 0.25 * ggx_g1_over_cos(wo.z, alpha) * ggx_distribution(h, alpha);
}

Vec2 stratum_centre(int i, int j, int n) {
  return {(i + 0.5) / n, (j + 0.5) / n};
}

// Balance-heuristic estimate of integral g(|lobe / albedo - p_M|) dw from n^2 stratified samples
// of each distribution.
template <typename Penalty>
double difference_integral(const LinearlyTransformedCosine& ltc, double alpha, double cos_theta,
                           double albedo, int n, Penalty penalty) {
  Vec3 wo = view_direction(cos_theta);
  double sum = 0;
  auto add = [&](const Vec3& wi) {
    double lobe = lobe_times_cosine(wo, wi, alpha) / albedo;
    double p_ltc = ltc.density(wi);
    double p_lobe = visible_normal_reflection_density(wo, wi, alpha);
    double p_sum = p_ltc + p_lobe;
    if (p_sum > 0 && std::isfinite(p_sum)) sum += penalty(std::abs(lobe - p_ltc)) / p_sum;
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Vec2 u = stratum_centre(i, j, n);
      add(ltc.sample(u));
      add(reflect_about(wo, sample_ggx_visible_normal(wo, alpha, u)));
    }
  return sum / (double(n) * n);
}

}  // namespace

LobeMoments ggx_lobe_moments(double alpha, double cos_theta, int n) {
  Vec3 wo = view_direction(cos_theta);
  LobeMoments moments;
  Vec3 direction_sum{0, 0, 0};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Vec3 h = sample_ggx_visible_normal(wo, alpha, stratum_centre(i, j, n));
      Vec3 wi = reflect_about(wo, h);
      double pdf = visible_normal_reflection_density(wo, wi, alpha);
      if (!(wi.z > 0) || !(pdf > 0)) continue;
      double weight = lobe_times_cosine(wo, wi, alpha) / pdf;
      double schlick = std::pow(std::clamp(1.0 - dot(wi, h), 0.0, 1.0), 5.0);
      moments.albedo += weight;
      moments.fresnel += weight * schlick;
      direction_sum += weight * wi;
    }
  double count = double(n) * n;
  moments.albedo /= count;
  moments.fresnel /= count;
  // Isotropy: the average direction lies in the plane of wo and the normal.
  Vec3 average{direction_sum.x, 0.0, std::max(direction_sum.z, 0.0)};
  double average_length = length(average);
  moments.average_direction = average_length > 0 ? average / average_length : Vec3{0, 0, 1};
  return moments;
}

Matrix3 ltc_matrix(const LtcParameters& p, const Vec3& average_direction) {
  double c = std::cos(p[3]), s = std::sin(p[3]);
  Vec3 z_axis{c * average_direction.x + s * average_direction.z, 0.0,
              c * average_direction.z - s * average_direction.x};
  Vec3 y_axis{0, 1, 0};
  Vec3 x_axis = cross(y_axis, z_axis);
  Matrix3 frame;
  frame.m = {x_axis.x, y_axis.x, z_axis.x, x_axis.y, y_axis.y,
             z_axis.y, x_axis.z, y_axis.z, z_axis.z};
  Matrix3 shape;
  shape.m = {p[0], 0, p[2], 0, p[1], 0, 0, 0, 1};
  return frame * shape;
}

double ltc_fit_error(const LinearlyTransformedCosine& ltc, double alpha, double cos_theta,
                     double albedo, int n) {
  return difference_integral(ltc, alpha, cos_theta, albedo, n, [](double d) { return d; });
}

NelderMeadResult nelder_mead(const std::function<double(const LtcParameters&)>& f,
                             const LtcParameters& start, double step, int max_evaluations,
                             double tolerance) {
  constexpr int kDimension = 4;
  std::array<LtcParameters, kDimension + 1> simplex;
  std::array<double, kDimension + 1> values;
  NelderMeadResult result;
  auto evaluate = [&](const LtcParameters& x) {
    ++result.evaluations;
    return f(x);
  };
  simplex[0] = start;
  for (int i = 0; i < kDimension; ++i) {
    simplex[i + 1] = start;
    simplex[i + 1][i] += std::max(step, step * std::abs(start[i]));
  }
  for (int i = 0; i <= kDimension; ++i) values[i] = evaluate(simplex[i]);
  auto combine = [](const LtcParameters& a, const LtcParameters& b, double t) {
    LtcParameters x;
    for (int i = 0; i < kDimension; ++i) x[i] = a[i] + t * (b[i] - a[i]);
    return x;
  };
  while (result.evaluations < max_evaluations) {
    // Order the vertices by value.
    std::array<int, kDimension + 1> order{0, 1, 2, 3, 4};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return values[a] < values[b]; });
    auto sorted_simplex = simplex;
    auto sorted_values = values;
    for (int i = 0; i <= kDimension; ++i) {
      simplex[i] = sorted_simplex[order[i]];
      values[i] = sorted_values[order[i]];
    }
    if (std::abs(values[kDimension] - values[0]) <=
        tolerance * (std::abs(values[0]) + std::abs(values[kDimension])) + 1e-300)
      break;
    LtcParameters centroid{0, 0, 0, 0};
    for (int i = 0; i < kDimension; ++i)
      for (int k = 0; k < kDimension; ++k) centroid[k] += simplex[i][k] / kDimension;
    const LtcParameters& worst = simplex[kDimension];
    // Reflect, expand, contract, shrink.
    LtcParameters reflected = combine(centroid, worst, -1.0);
    double reflected_value = evaluate(reflected);
    if (reflected_value < values[0]) {
      LtcParameters expanded = combine(centroid, worst, -2.0);
      double expanded_value = evaluate(expanded);
      if (expanded_value < reflected_value) {
        simplex[kDimension] = expanded, values[kDimension] = expanded_value;
      } else {
        simplex[kDimension] = reflected, values[kDimension] = reflected_value;
      }
      continue;
    }
    if (reflected_value < values[kDimension - 1]) {
      simplex[kDimension] = reflected, values[kDimension] = reflected_value;
      continue;
    }
    bool outside = reflected_value < values[kDimension];
    LtcParameters contracted = combine(centroid, outside ? reflected : worst, 0.5);
    double contracted_value = evaluate(contracted);
    if (contracted_value < std::min(reflected_value, values[kDimension])) {
      simplex[kDimension] = contracted, values[kDimension] = contracted_value;
      continue;
    }
    for (int i = 1; i <= kDimension; ++i) {
      simplex[i] = combine(simplex[0], simplex[i], 0.5);
      values[i] = evaluate(simplex[i]);
    }
  }
  int best = int(std::min_element(values.begin(), values.end()) - values.begin());
  result.minimum = simplex[best];
  result.value = values[best];
  return result;
}

CellFit fit_ggx_ltc_cell(double alpha, double cos_theta, std::span<const LtcParameters> initials,
                         const FitOptions& options) {
  LobeMoments moments = ggx_lobe_moments(alpha, cos_theta, options.moment_samples_per_axis);
  CellFit fit;
  auto objective = [&](const LtcParameters& p) {
    if (!(p[0] > 0) || !(p[1] > 0) || !std::isfinite(p[2]) || !(std::abs(p[3]) < 1.5)) return 1e300;
    LinearlyTransformedCosine ltc(ltc_matrix(p, moments.average_direction));
    return difference_integral(ltc, alpha, cos_theta, moments.albedo,
                               options.objective_samples_per_axis,
                               [](double d) { return d * d * d; });
  };
  // From each start two rounds (a restart from the first minimum escapes a collapsed simplex);
  // the lowest objective wins.
  NelderMeadResult best;
  best.value = 1e300;
  fit.evaluations = 0;
  for (const LtcParameters& initial : initials) {
    NelderMeadResult first = nelder_mead(objective, initial, 0.05, options.max_evaluations, 1e-8);
    NelderMeadResult second =
        nelder_mead(objective, first.minimum, 0.02, options.max_evaluations / 2, 1e-10);
    fit.evaluations += first.evaluations + second.evaluations;
    for (const NelderMeadResult* candidate : {&first, &second})
      if (candidate->value < best.value) best = *candidate;
  }
  fit.parameters = best.minimum;

  Matrix3 m = ltc_matrix(fit.parameters, moments.average_direction);
  Matrix3 m_inverse = inverse(m);
  // Scale so that the (1, 1) entry is 1 (the density does not depend on the scale).
  double scale = 1.0 / m_inverse(1, 1);
  fit.cell.inverse_00 = m_inverse(0, 0) * scale;
  fit.cell.inverse_02 = m_inverse(0, 2) * scale;
  fit.cell.inverse_20 = m_inverse(2, 0) * scale;
  fit.cell.inverse_22 = m_inverse(2, 2) * scale;
  fit.cell.albedo = moments.albedo;
  fit.cell.fresnel = moments.fresnel;
  // The error of what the table will hold (the rounded, rescaled matrix).
  LinearlyTransformedCosine stored(inverse(ggx_ltc_inverse_matrix(
      fit.cell.inverse_00, fit.cell.inverse_02, fit.cell.inverse_20, fit.cell.inverse_22)));
  fit.cell.fit_error =
      ltc_fit_error(stored, alpha, cos_theta, moments.albedo, options.fit_error_samples_per_axis);
  return fit;
}

std::vector<CellFit> fit_ggx_ltc_table(const FitOptions& options,
                                       const std::function<void(int row)>& progress) {
  constexpr int n = kGgxLtcTableSize;
  std::vector<CellFit> table(size_t(n) * n);
  for (int row = n - 1; row >= 0; --row) {
    double alpha = ggx_ltc_table_alpha(row);
    for (int column = 0; column < n; ++column) {
      double cos_theta = ggx_ltc_table_cos_theta(column);
      // Starts: the rougher neighbour's solution scaled to this roughness (Heitz et al.), and
      // the same untilted. Narrow lobes need the second: a tilt that suited the rougher lobe
      // can miss a narrow one entirely, where the objective is flat.
      std::array<LtcParameters, 2> initials;
      initials[0] = {alpha, alpha, 0.0, 0.0};
      if (row + 1 < n) {
        const LtcParameters& rougher = table[size_t((row + 1) * n + column)].parameters;
        double ratio = alpha / ggx_ltc_table_alpha(row + 1);
        initials[0] = {rougher[0] * ratio, rougher[1] * ratio, rougher[2] * ratio,
                       rougher[3] * ratio};
      } else if (column > 0) {
        initials[0] = table[size_t(row * n + column - 1)].parameters;
      }
      initials[1] = initials[0];
      initials[1][3] = 0.0;
      table[size_t(row * n + column)] = fit_ggx_ltc_cell(alpha, cos_theta, initials, options);
    }
    if (progress) progress(row);
  }
  return table;
}

}  // namespace penumbra::ltc_fit
