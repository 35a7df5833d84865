// Salesin & Jarosz's line samples as point samples (line-area, line-sa): chi-square of the
// samples against the strategies' own pdfs (unoccluded, with an occluder, with the light partly
// below the horizon), pdf evaluation equal to the sampler's pdf, unoccluded pdfs equal to the
// point strategies' (1 / area and 1 / solid angle), samples visible, no sample for hidden lines.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "core/lines/line_query.h"
#include "core/strategies/line_area_strategy.h"
#include "core/strategies/line_solid_angle_strategy.h"

namespace penumbra {
namespace {

Light rectangle_light() {
  Light light;
  light.type = LightType::Quad;
  light.origin = {-0.5, 1, -0.3};
  light.edge1 = {1, 0, 0};
  light.edge2 = {0, 0, 0.6};
  light.normal = normalize(cross(light.edge1, light.edge2));  // facing down
  light.area = length(cross(light.edge1, light.edge2));
  light.vertices = {light.origin, light.origin + light.edge1,
                    light.origin + light.edge1 + light.edge2, light.origin + light.edge2};
  light.centroid = light.origin + 0.5 * (light.edge1 + light.edge2);
  return light;
}

// A triangle halfway up with edges oblique to both light edges, and a thin bar across it.
LineQuery occluders(bool present) {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;
  if (present) {
    positions = {{-0.25, 0.5, -0.25}, {0.3, 0.5, -0.2}, {0.02, 0.5, 0.25},
                 {-0.4, 0.7, 0.05},   {0.4, 0.7, 0.08}, {0.4, 0.7, 0.11}};
    indices = {0, 1, 2, 3, 4, 5};
  }
  return LineQuery(positions, indices);
}

struct Setup {
  const char* what;
  bool occluded;
  ShadingPoint sp;
};

std::vector<Setup> setups() {
  ShadingPoint straight{{0.05, 0, 0.02}, {0, 1, 0}, {0, 1, 0}, nullptr};
  // Tilted so that the light's part with x < -0.3 is below the horizon.
  ShadingPoint tilted{{0, 0, 0}, normalize(Vec3{1, 0.3, 0}), {0, 1, 0}, nullptr};
  return {{"unoccluded", false, straight},
          {"occluded", true, straight},
          {"partly below the horizon, occluded", true, tilted}};
}

using Sampler = std::function<std::optional<LightPoint>(const Vec2&, TracedLine&, double&)>;
using Pdf = std::function<double(const Vec3&)>;

// Chi-square of N samples over a grid of the line family's (offset, t) against the pdf
// integrated over each cell: midpoint rule across lines (the probability of a line is smooth in
// its offset) and, along each line, 4-point Gauss-Legendre on every visible piece within the cell
// (exact in where the pieces end: the pdf is smooth inside a piece). Cells expecting fewer than
// 5 samples are pooled. Returns the Wilson-Hilferty z-score of the statistic.
double chi_square_z(const Light& light, const QuadLineFamily& family, const LineQuery& query,
                    const Sampler& sample, const Pdf& pdf, int n, int cells, int sub) {
  std::vector<double> observed(cells * cells, 0), expected(cells * cells, 0);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0, 1);
  int none = 0;
  for (int i = 0; i < n; ++i) {
    TracedLine line;
    double t;
    std::optional<LightPoint> p = sample({unit(rng), unit(rng)}, line, t);
    if (!p) {
      ++none;
      continue;
    }
    Vec2 st = family.coordinates(p->position);
    int is = std::clamp(int(st.x * cells), 0, cells - 1);
    int it = std::clamp(int(st.y * cells), 0, cells - 1);
    observed[is * cells + it] += 1;
  }
  // The density in the offset s of landing in each t-cell: the pdf integrated along the line
  // (times the area element A ds dt), Gauss-Legendre on each visible piece within the cell.
  auto line_masses = [&](double s) {
    static const double gauss_x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                      0.8611363115940526};
    static const double gauss_w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                      0.3478548451374538};
    std::vector<double> masses(cells, 0);
    TracedLine line;
    family.trace(s, query, line);
    for (const Interval& piece : line.visible) {
      for (int it = 0; it < cells; ++it) {
        double lo = std::max(piece.lo, double(it) / cells);
        double hi = std::min(piece.hi, double(it + 1) / cells);
        if (!(lo < hi)) continue;
        double integral = 0;
        for (int k = 0; k < 4; ++k) {
          double t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * gauss_x[k];
          integral += gauss_w[k] * pdf(family.point_at(s, t));
        }
        masses[it] += integral * 0.5 * (hi - lo) * light.area;
      }
    }
    return masses;
  };
  // Adaptive Simpson across offsets: a line's masses jump where it slips off an occluder (a
  // nearly hidden line puts its whole probability into a sliver), so intervals whose masses
  // are not smooth are split down to 1e-7.
  std::function<void(double, double, const std::vector<double>&, const std::vector<double>&,
                     std::vector<double>&)>
      integrate = [&](double a, double b, const std::vector<double>& ma,
                      const std::vector<double>& mb, std::vector<double>& out) {
        double mid = 0.5 * (a + b);
        std::vector<double> mm = line_masses(mid);
        double roughness = 0, scale = 0;
        for (int c = 0; c < cells; ++c) {
          roughness += std::abs(ma[c] + mb[c] - 2 * mm[c]);
          scale += ma[c] + mb[c] + mm[c];
        }
        if (b - a > 1e-7 && roughness > 1e-3 * scale) {
          integrate(a, mid, ma, mm, out);
          integrate(mid, b, mm, mb, out);
          return;
        }
        for (int c = 0; c < cells; ++c) out[c] += (ma[c] + 4 * mm[c] + mb[c]) / 6 * (b - a);
      };
  double total_probability = 0;
  for (int is = 0; is < cells; ++is) {
    std::vector<double> row(cells, 0);
    for (int js = 0; js < sub; ++js) {
      double a = (is + double(js) / sub) / cells, b = (is + double(js + 1) / sub) / cells;
      // Just inside the cell's ends, so that a line on a cell boundary counts in this cell.
      integrate(a, b, line_masses(a), line_masses(std::nextafter(b, a)), row);
    }
    for (int it = 0; it < cells; ++it) {
      expected[is * cells + it] = row[it] * n;
      total_probability += row[it];
    }
  }
  // Lines that are fully hidden give no sample: their share is missing from both sides.
  EXPECT_NEAR(total_probability, double(n - none) / n, 0.01);
  double chi2 = 0, pooled_observed = 0, pooled_expected = 0;
  int bins = 0;
  for (size_t c = 0; c < observed.size(); ++c) {
    if (expected[c] < 5) {
      pooled_observed += observed[c];
      pooled_expected += expected[c];
      continue;
    }
    chi2 += (observed[c] - expected[c]) * (observed[c] - expected[c]) / expected[c];
    ++bins;
  }
  if (pooled_expected >= 5) {
    chi2 +=
        (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
    ++bins;
  } else {
    EXPECT_LE(pooled_observed, 10 + 3 * pooled_expected);
  }
  double dof = bins - 1;
  return (std::cbrt(chi2 / dof) - (1 - 2 / (9 * dof))) / std::sqrt(2 / (9 * dof));
}

template <typename Strategy>
void check_strategy(const char* name) {
  Light light = rectangle_light();
  for (const Setup& setup : setups()) {
    LineQuery query = occluders(setup.occluded);
    for (LineAxis axis : {LineAxis::Edge1, LineAxis::Edge2}) {
      SCOPED_TRACE(std::string(name) + " axis " + std::to_string(int(axis)) + ", " + setup.what);
      Strategy strategy(setup.sp, light, axis, query);
      Sampler sample = [&](const Vec2& u, TracedLine& line, double& t) {
        return strategy.sample(u, line, t);
      };
      Pdf pdf = [&](const Vec3& p) { return strategy.pdf(p); };
      ASSERT_TRUE(strategy.family());
      double z = chi_square_z(light, *strategy.family(), query, sample, pdf, 200000, 12, 4);
      EXPECT_LT(z, 4.0) << name << " axis " << int(axis) << ", " << setup.what;

      // The pdf evaluated at a sample (its own line query through the point) equals the pdf the
      // sampler returned, and the sample is visible (no shadow ray needed).
      std::mt19937_64 rng(3);
      std::uniform_real_distribution<double> unit(0, 1);
      int mismatched = 0, hidden = 0, samples = 0;
      for (int i = 0; i < 5000; ++i) {
        TracedLine line;
        double t;
        std::optional<LightPoint> p = strategy.sample({unit(rng), unit(rng)}, line, t);
        if (!p) continue;
        ++samples;
        double evaluated = strategy.pdf(p->position);
        if (!(std::abs(evaluated - p->pdf_area) <= 1e-9 * p->pdf_area)) ++mismatched;
        if (query.occluded(setup.sp.position, p->position)) ++hidden;
        EXPECT_GT(dot(setup.sp.normal, p->position - setup.sp.position), 0.0) << "below horizon";
      }
      EXPECT_GT(samples, 2000);
      EXPECT_LE(mismatched, samples / 1000) << name << ", " << setup.what;
      EXPECT_LE(hidden, samples / 1000) << name << ", " << setup.what;
    }
  }
}

TEST(LineSampling, LineAreaSamplesFollowTheirPdf) {
  check_strategy<LineAreaStrategy>("line-area");
}

TEST(LineSampling, LineSolidAngleSamplesFollowTheirPdf) {
  check_strategy<LineSolidAngleStrategy>("line-sa");
}

TEST(LineSampling, UnoccludedPdfsArePointSamplingPdfs) {
  Light light = rectangle_light();
  LineQuery query = occluders(false);
  ShadingPoint sp = setups()[0].sp;
  auto rectangle = SphericalRectangle::prepare(sp.position, light.origin, light.edge1, light.edge2);
  ASSERT_TRUE(rectangle);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> unit(0, 1);
  for (LineAxis axis : {LineAxis::Edge1, LineAxis::Edge2}) {
    LineAreaStrategy area(sp, light, axis, query);
    LineSolidAngleStrategy solid_angle(sp, light, axis, query);
    for (int i = 0; i < 1000; ++i) {
      Vec3 p = light.origin + unit(rng) * light.edge1 + unit(rng) * light.edge2;
      EXPECT_NEAR(area.pdf(p), 1.0 / light.area, 1e-12 / light.area);
      Vec3 d = p - sp.position;
      double expected =
          std::abs(dot(light.normal, d)) / std::pow(length(d), 3) / rectangle->solid_angle;
      EXPECT_NEAR(solid_angle.pdf(p), expected, 1e-9 * expected);
    }
  }
}

TEST(LineSampling, HiddenLinesGiveNoSampleAndHiddenPointsZeroPdf) {
  Light light = rectangle_light();
  // A large plate covers the whole light.
  LineQuery query({{-5, 0.5, -5}, {5, 0.5, -5}, {0, 0.5, 5}}, {0, 1, 2});
  ShadingPoint sp = setups()[0].sp;
  for (LineAxis axis : {LineAxis::Edge1, LineAxis::Edge2}) {
    LineAreaStrategy area(sp, light, axis, query);
    LineSolidAngleStrategy solid_angle(sp, light, axis, query);
    TracedLine line;
    double t;
    EXPECT_FALSE(area.sample({0.3, 0.6}, line, t));
    EXPECT_FALSE(solid_angle.sample({0.3, 0.6}, line, t));
    Vec3 p = light.centroid;
    EXPECT_EQ(area.pdf(p), 0.0);
    EXPECT_EQ(solid_angle.pdf(p), 0.0);
  }
}

TEST(LineSampling, BehindOrInThePlaneOfTheLightNoSamples) {
  Light light = rectangle_light();
  LineQuery query = occluders(false);
  for (Vec3 position : {Vec3{0, 1, 0}, Vec3{0, 2, 0}, Vec3{3, 1, 0}}) {
    ShadingPoint sp{position, {0, -1, 0}, {0, -1, 0}, nullptr};
    for (LineAxis axis : {LineAxis::Edge1, LineAxis::Edge2}) {
      LineAreaStrategy area(sp, light, axis, query);
      LineSolidAngleStrategy solid_angle(sp, light, axis, query);
      TracedLine line;
      double t;
      EXPECT_FALSE(area.sample({0.5, 0.5}, line, t));
      EXPECT_FALSE(solid_angle.sample({0.5, 0.5}, line, t));
      EXPECT_EQ(area.pdf(light.centroid), 0.0);
      EXPECT_EQ(solid_angle.pdf(light.centroid), 0.0);
    }
  }
}

}  // namespace
}  // namespace penumbra
