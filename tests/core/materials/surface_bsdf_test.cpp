// pbrt-v3's materials as SurfaceBsdf lobes: sampling against the density (chi-square), values
// against pbrt-v3's formulas written independently below (in its tan/cos^2 phi form), energy by
// deterministic quadrature, reciprocity, the delta lobes, and finiteness at grazing angles.

#include "core/materials/surface_bsdf.h"

#include <gtest/gtest.h>

#include <complex>
#include <vector>

#include "core/materials/pbrt_material.h"
#include "tests/core/materials/direction_binning.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

using test::Rng;

Material pbrt(MaterialType type) {
  Material m = pbrt_material_defaults(type);
  m.name = "m";
  return m;
}

Vec3 spherical(double theta_deg, double phi_deg) {
  double t = theta_deg * kPi / 180.0, p = phi_deg * kPi / 180.0;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

const Frame kLocal{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

struct Config {
  std::string name;
  Material material;
  PbrtMaterialValues values;
};

std::vector<Config> configs() {
  std::vector<Config> out;
  auto add = [&](std::string name, MaterialType type, auto edit) {
    Config c{name, pbrt(type), {}};
    c.values = constant_material_values(c.material.params);
    edit(c.material, c.values);
    out.push_back(c);
  };
  add("matte", MaterialType::Matte, [](Material&, PbrtMaterialValues& v) {
    v.kd = {0.7, 0.5, 0.3};
  });
  add("oren_nayar_20", MaterialType::Matte, [](Material&, PbrtMaterialValues& v) {
    v.kd = {0.7, 0.5, 0.3};
    v.sigma = 20;
  });
  add("oren_nayar_60", MaterialType::Matte, [](Material&, PbrtMaterialValues& v) {
    v.kd = {0.9, 0.9, 0.9};
    v.sigma = 60;
  });
  add("plastic_remapped", MaterialType::Plastic, [](Material&, PbrtMaterialValues&) {});
  add("plastic_alpha_03", MaterialType::Plastic, [](Material& m, PbrtMaterialValues& v) {
    m.params.remap_roughness = false;
    v.kd = {0.3, 0.3, 0.3};
    v.ks = {0.6, 0.6, 0.6};
    v.uroughness = v.vroughness = 0.3;
  });
  add("substrate_kitchen", MaterialType::Substrate, [](Material& m, PbrtMaterialValues& v) {
    m.params.remap_roughness = false;
    v.kd = {0.58, 0.58, 0.58};
    v.ks = {0.04, 0.04, 0.04};
    v.uroughness = v.vroughness = 0.1;
  });
  add("substrate_anisotropic", MaterialType::Substrate, [](Material& m, PbrtMaterialValues& v) {
    m.params.remap_roughness = false;
    v.kd = {0.3, 0.4, 0.5};
    v.ks = {0.3, 0.3, 0.3};
    v.uroughness = 0.05;
    v.vroughness = 0.4;
  });
  add("metal_steel", MaterialType::Metal, [](Material& m, PbrtMaterialValues& v) {
    m.params.remap_roughness = false;
    v.eta_rgb = {1.65746, 0.880369, 0.521229};
    v.k = {9.223869, 6.269523, 4.837001};
    v.uroughness = v.vroughness = 0.1;
  });
  add("metal_anisotropic", MaterialType::Metal, [](Material& m, PbrtMaterialValues& v) {
    m.params.remap_roughness = false;
    v.eta_rgb = {0.2, 0.92, 1.1};
    v.k = {3.9, 2.45, 2.14};
    v.uroughness = 0.02;
    v.vroughness = 0.25;
  });
  add("uber_blinds", MaterialType::Uber, [](Material&, PbrtMaterialValues& v) {
    v.kd = {0.61, 0.5, 0.38};
    v.ks = {0, 0, 0};
    v.opacity = {0.61, 0.61, 0.61};
  });
  add("uber_glossy", MaterialType::Uber, [](Material&, PbrtMaterialValues& v) {
    v.kd = {0.4, 0.4, 0.4};
    v.ks = {0.5, 0.5, 0.5};
    v.kr = {0.1, 0.1, 0.1};
    v.uroughness = v.vroughness = 0.05;
  });
  return out;
}

// A tilted shading normal (bump or interpolated normals): the defensive lobe is active.
Frame tilted_frame() {
  return Frame::from_normal(normalize(Vec3{0.25, -0.15, 1.0}));
}

struct SamplingCase {
  Config config;
  double wo_degrees;
  bool tilted;
};
void PrintTo(const SamplingCase& c, std::ostream* os) {
  *os << c.config.name;
}

std::vector<SamplingCase> sampling_cases() {
  std::vector<SamplingCase> out;
  for (const Config& c : configs()) {
    out.push_back({c, 35, false});
    if (c.name == "plastic_alpha_03" || c.name == "matte" || c.name == "metal_anisotropic") {
      SamplingCase t{c, 70, true};
      t.config.name += "_tilted";
      out.push_back(t);
    }
  }
  return out;
}

class SurfaceBsdfSampling : public ::testing::TestWithParam<SamplingCase> {};

TEST_P(SurfaceBsdfSampling, SamplesFollowTheReportedDensity) {
  const SamplingCase& c = GetParam();
  Vec3 ng{0, 0, 1};
  Frame shading = c.tilted ? tilted_frame() : kLocal;
  SurfaceBsdf bsdf = make_pbrt_bsdf(c.config.material, c.config.values, shading, ng);
  ASSERT_TRUE(bsdf.has_non_delta());
  Vec3 wo = spherical(c.wo_degrees, 30);
  Vec3 mirror{-wo.x, -wo.y, wo.z};
  test::DirectionBinning binning;
  // Narrow lobes are binned around the mirror direction on a log scale of (1 - cos) / 2.
  binning.frame = Frame::from_normal(mirror);
  binning.log_scale = true;
  binning.y_min = 1e-6;
  const int samples = 200000;
  std::vector<double> observed(binning.y_bins * binning.phi_bins + 1, 0.0);
  Rng rng(99);
  double worst = 0;
  for (int i = 0; i < samples; ++i) {
    auto s = bsdf.sample(wo, rng.uniform2());
    if (!s) {
      observed.back() += 1;
      continue;
    }
    ASSERT_NEAR(length(s->wi), 1.0, 1e-12);
    ASSERT_GT(dot(s->wi, ng), 0.0);
    worst = std::max(worst, test::relative_difference(s->pdf, bsdf.pdf(wo, s->wi)));
    observed[binning.bin(s->wi)] += 1;
  }
  EXPECT_LE(worst, 1e-12) << "a sample's density differs from pdf()";
  std::vector<double> expected =
      binning.integrate([&](const Vec3& wi) { return bsdf.pdf(wo, wi); });
  double total = 0;
  for (double& e : expected) {
    e *= samples;
    total += e;
  }
  EXPECT_LE(total, samples * (1 + 2e-3)) << "density integrates to more than one";
  expected.push_back(std::max(0.0, samples - total));
  auto result = test::chi_square_test(observed, expected);
  EXPECT_TRUE(result.passed) << c.config.name << ": " << result.summary();
}

INSTANTIATE_TEST_SUITE_P(Pbrt, SurfaceBsdfSampling, ::testing::ValuesIn(sampling_cases()),
                         [](const auto& info) { return info.param.config.name; });

// pbrt-v3's formulas in its own trigonometric form (microfacet.cpp, reflection.cpp), for the
// tabulated checks: an implementation independent of the one under test.
namespace reference {

double cos2_phi(const Vec3& w) {
  double s2 = 1 - w.z * w.z;
  return s2 <= 0 ? 1.0 : std::clamp(w.x * w.x / s2, 0.0, 1.0);
}
double sin2_phi(const Vec3& w) {
  double s2 = 1 - w.z * w.z;
  return s2 <= 0 ? 0.0 : std::clamp(w.y * w.y / s2, 0.0, 1.0);
}
double tan2_theta(const Vec3& w) {
  return (1 - w.z * w.z) / (w.z * w.z);
}
double tr_d(const Vec3& h, double ax, double ay) {
  double t2 = tan2_theta(h);
  double cos4 = h.z * h.z * h.z * h.z;
  double e = (cos2_phi(h) / (ax * ax) + sin2_phi(h) / (ay * ay)) * t2;
  return 1 / (kPi * ax * ay * cos4 * (1 + e) * (1 + e));
}
double tr_lambda(const Vec3& w, double ax, double ay) {
  double abs_tan = std::sqrt(tan2_theta(w));
  double alpha = std::sqrt(cos2_phi(w) * ax * ax + sin2_phi(w) * ay * ay);
  double a2t2 = (alpha * abs_tan) * (alpha * abs_tan);
  return (-1 + std::sqrt(1 + a2t2)) / 2;
}
double tr_g(const Vec3& wo, const Vec3& wi, double ax, double ay) {
  return 1 / (1 + tr_lambda(wo, ax, ay) + tr_lambda(wi, ax, ay));
}
double fr_dielectric(double cos_i, double eta_i, double eta_t) {
  if (cos_i < 0) {
    std::swap(eta_i, eta_t);
    cos_i = -cos_i;
  }
  double sin_t = eta_i / eta_t * std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
  if (sin_t >= 1) return 1;
  double cos_t = std::sqrt(std::max(0.0, 1 - sin_t * sin_t));
  double rpar = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  double rper = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  return (rpar * rpar + rper * rper) / 2;
}
// The textbook conductor Fresnel equations with complex arithmetic (not the closed form under
// test): r_s = (cos - n cos_t) / (cos + n cos_t), r_p = (n cos - cos_t) / (n cos + cos_t).
double fr_conductor(double cos_i, double eta, double k) {
  std::complex<double> n(eta, k);
  double sin2 = 1 - cos_i * cos_i;
  std::complex<double> cos_t = std::sqrt(1.0 - sin2 / (n * n));
  std::complex<double> rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  std::complex<double> rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  return 0.5 * (std::norm(rs) + std::norm(rp));
}
double oren_nayar(const Vec3& wo, const Vec3& wi, double sigma_deg) {
  double s = sigma_deg * kPi / 180, s2 = s * s;
  double a = 1 - s2 / (2 * (s2 + 0.33)), b = 0.45 * s2 / (s2 + 0.09);
  double ti = std::acos(wi.z), to = std::acos(wo.z);
  double phi_i = std::atan2(wi.y, wi.x), phi_o = std::atan2(wo.y, wo.x);
  double alpha = std::max(ti, to), beta = std::min(ti, to);
  return (a + b * std::max(0.0, std::cos(phi_i - phi_o)) * std::sin(alpha) * std::tan(beta)) / kPi;
}

}  // namespace reference

TEST(SurfaceBsdfValues, MatchPbrtFormulasAtTabulatedConfigurations) {
  const std::pair<Vec3, Vec3> directions[] = {
      {spherical(10, 0), spherical(20, 180)},  {spherical(45, 30), spherical(45, 210)},
      {spherical(60, 10), spherical(30, 250)}, {spherical(80, 100), spherical(70, 300)},
      {spherical(5, 0), spherical(85, 120)},   {spherical(30, 45), spherical(31, 226)}};
  for (const Config& c : configs()) {
    SurfaceBsdf bsdf = make_pbrt_bsdf(c.material, c.values, kLocal, {0, 0, 1});
    for (const auto& [wo, wi] : directions) {
      Vec3 h = normalize(wo + wi);
      double co = wo.z, ci = wi.z;
      Rgb expected;
      const PbrtMaterialValues& v = c.values;
      double ax = v.uroughness, ay = v.vroughness;
      if (c.material.params.remap_roughness) {
        ax = pbrt_roughness_to_alpha(ax);
        ay = pbrt_roughness_to_alpha(ay);
      }
      double dg = reference::tr_d(h, ax, ay) * reference::tr_g(wo, wi, ax, ay) / (4 * co * ci);
      switch (c.material.type) {
        case MaterialType::Matte:
          expected = v.kd * (v.sigma == 0 ? 1 / kPi : reference::oren_nayar(wo, wi, v.sigma));
          break;
        case MaterialType::Plastic:
          expected = v.kd / kPi + v.ks * (dg * reference::fr_dielectric(dot(wi, h), 1.5, 1));
          break;
        case MaterialType::Substrate: {
          auto p5 = [](double x) { return std::pow(x, 5); };
          Rgb one{1, 1, 1};
          Rgb diffuse =
              28 / (23 * kPi) * v.kd * (one - v.ks) * (1 - p5(1 - ci / 2)) * (1 - p5(1 - co / 2));
          Rgb schlick = v.ks + p5(1 - dot(wi, h)) * (one - v.ks);
          expected = diffuse +
                     schlick * (reference::tr_d(h, ax, ay) / (4 * dot(wi, h) * std::max(ci, co)));
          break;
        }
        case MaterialType::Metal:
          for (int ch = 0; ch < 3; ++ch)
            expected[ch] = dg * reference::fr_conductor(dot(wi, h), v.eta_rgb[ch], v.k[ch]);
          break;
        case MaterialType::Uber:
          expected = v.opacity * v.kd / kPi +
                     v.opacity * v.ks * (dg * reference::fr_dielectric(dot(wi, h), 1, v.eta));
          break;
        default:
          FAIL();
      }
      Rgb got = bsdf.f(wo, wi);
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(got[ch], expected[ch], 1e-9 * std::max(1.0, std::abs(expected[ch])))
            << c.name << " channel " << ch << " wo " << wo.x << "," << wo.y << "," << wo.z;
    }
  }
}

TEST(SurfaceBsdfValues, FresnelAndRoughnessClosedForms) {
  // Normal incidence: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) and ((n - 1) / (n + 1))^2.
  Rgb f = fresnel_conductor(1.0, {1.65746, 0.2, 4.0}, {9.223869, 3.9, 0.0});
  for (int c = 0; c < 3; ++c) {
    double n = Rgb{1.65746, 0.2, 4.0}[c], k = Rgb{9.223869, 3.9, 0.0}[c];
    EXPECT_NEAR(f[c], ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k), 1e-12);
  }
  EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, 1.5), 0.04, 1e-12);
  EXPECT_NEAR(fresnel_dielectric(-1.0, 1.0, 1.5), 0.04, 1e-12);
  // Critical angle from the dense side: asin(1 / 1.5) = 41.81 degrees.
  EXPECT_EQ(fresnel_dielectric(std::cos(42.0 * kPi / 180), 1.5, 1.0), 1.0);
  EXPECT_LT(fresnel_dielectric(std::cos(41.0 * kPi / 180), 1.5, 1.0), 1.0);
  // Grazing incidence reflects everything.
  EXPECT_NEAR(fresnel_dielectric(1e-9, 1.0, 1.5), 1.0, 1e-7);
  EXPECT_NEAR(fresnel_conductor(1e-9, {1.5, 1.5, 1.5}, {3, 3, 3}).x, 1.0, 1e-7);
  // RoughnessToAlpha: x = ln(r); at r = 1 the constant term; r below 1e-3 clamps.
  EXPECT_DOUBLE_EQ(pbrt_roughness_to_alpha(1.0), 1.62142);
  double x = std::log(0.1);
  EXPECT_NEAR(
      pbrt_roughness_to_alpha(0.1),
      1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x,
      1e-15);
  EXPECT_EQ(pbrt_roughness_to_alpha(1e-5), pbrt_roughness_to_alpha(1e-3));
  // pbrt-v3 clamps alpha to 1e-3.
  EXPECT_EQ(TrowbridgeReitz::make(0, 1e-5).alpha_x, 1e-3);
}

// Directional albedo int f |cos_i| dwi by deterministic quadrature: a midpoint grid over two
// parametrizations of the hemisphere (cosine-weighted directions and Trowbridge-Reitz half
// vectors), combined by the balance heuristic so each covers what it resolves well.
double directional_albedo(const SurfaceBsdf& bsdf, const Vec3& wo, double alpha, int n = 256) {
  const Vec3 ng{0, 0, 1};
  auto p_cos = [](const Vec3& wi) { return std::max(0.0, wi.z) / kPi; };
  auto p_half = [&](const Vec3& wi) {
    Vec3 h = normalize(wo + wi);
    double wo_h = dot(wo, h);
    if (!(wo_h > 0) || h.z <= 0) return 0.0;
    TrowbridgeReitz tr = TrowbridgeReitz::make(alpha, alpha);
    return tr.d(h) * h.z / (4 * wo_h);
  };
  double sum = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double u1 = (i + 0.5) / n, u2 = (j + 0.5) / n;
      // Cosine-weighted direction.
      double r = std::sqrt(u1), phi = 2 * kPi * u2;
      Vec3 wi{r * std::cos(phi), r * std::sin(phi), std::sqrt(1 - u1)};
      double g = luminance(bsdf.f(wo, wi)) * wi.z;
      double p = p_cos(wi) + p_half(wi);
      if (p > 0 && wi.z > 0) sum += g / p;
      // Half vector with density D(h) cos(theta_h): tan^2 = alpha^2 u1 / (1 - u1).
      double tan2 = alpha * alpha * u1 / (1 - u1);
      double ch = 1 / std::sqrt(1 + tan2);
      Vec3 h{std::sqrt(1 - ch * ch) * std::cos(phi), std::sqrt(1 - ch * ch) * std::sin(phi), ch};
      Vec3 wr = 2 * dot(wo, h) * h - wo;
      if (wr.z > 0 && dot(wo, h) > 0) {
        double gr = luminance(bsdf.f(wo, wr)) * wr.z;
        double pr = p_cos(wr) + p_half(wr);
        if (pr > 0) sum += gr / pr;
      }
    }
  (void)ng;
  return sum / (double(n) * n);
}

TEST(SurfaceBsdfEnergy, WhiteFurnaceAtMostOne) {
  struct Case {
    std::string name;
    MaterialType type;
    double alpha;
    double sigma;
    double lower;  // the albedo is at least this (so the test sees a lobe that lost energy)
  };
  const Case cases[] = {
      {"lambert", MaterialType::Matte, 0.3, 0, 0.999},
      {"oren_nayar", MaterialType::Matte, 0.3, 40, 0.7},
      {"conductor_smooth", MaterialType::Metal, 0.05, 0, 0.9},
      {"conductor_rough", MaterialType::Metal, 0.6, 0, 0.5},
      {"plastic", MaterialType::Plastic, 0.2, 0, 0.5},
      {"substrate", MaterialType::Substrate, 0.1, 0, 0.3},
      {"substrate_rough", MaterialType::Substrate, 0.5, 0, 0.3},
  };
  for (const Case& c : cases) {
    Material m = pbrt(c.type);
    m.params.remap_roughness = false;
    PbrtMaterialValues v = constant_material_values(m.params);
    v.uroughness = v.vroughness = c.alpha;
    v.sigma = c.sigma;
    v.kd = {1, 1, 1};
    if (c.type == MaterialType::Plastic) v.kd = v.ks = {0.5, 0.5, 0.5};
    if (c.type == MaterialType::Substrate) v.kd = {1, 1, 1}, v.ks = {0.04, 0.04, 0.04};
    // A conductor with F = 1 to within 1e-6 (eta 0, huge k): the bare microfacet lobe.
    v.eta_rgb = {0, 0, 0};
    v.k = {1e4, 1e4, 1e4};
    SurfaceBsdf bsdf = make_pbrt_bsdf(m, v, kLocal, {0, 0, 1});
    for (double theta : {0.0, 30.0, 60.0, 80.0, 89.0}) {
      double albedo = directional_albedo(bsdf, spherical(theta, 20), c.alpha);
      EXPECT_LE(albedo, 1.0 + 2e-3) << c.name << " at " << theta;
      if (theta <= 60) {
        EXPECT_GE(albedo, c.lower) << c.name << " at " << theta;
      }
    }
  }
  // alpha = 1 at normal incidence: D = 1/pi and G = 2 cos_i / (1 + cos_i), so the albedo is
  // (1/2) int_0^1 2 mu / (1 + mu) dmu = 1 - ln 2.
  {
    Material metal = pbrt(MaterialType::Metal);
    metal.params.remap_roughness = false;
    PbrtMaterialValues v = constant_material_values(metal.params);
    v.uroughness = v.vroughness = 1;
    v.eta_rgb = {0, 0, 0};
    v.k = {1e4, 1e4, 1e4};
    EXPECT_NEAR(directional_albedo(make_pbrt_bsdf(metal, v, kLocal, {0, 0, 1}), {0, 0, 1}, 1.0),
                1 - std::log(2.0), 1e-4);
  }
  // Lambert reflects exactly its albedo.
  Material m = pbrt(MaterialType::Matte);
  PbrtMaterialValues v = constant_material_values(m.params);
  v.kd = {1, 1, 1};
  EXPECT_NEAR(directional_albedo(make_pbrt_bsdf(m, v, kLocal, {0, 0, 1}), spherical(50, 0), 0.3),
              1.0, 1e-3);
}

TEST(SurfaceBsdfReciprocity, NonDeltaLobesAreSymmetric) {
  Rng rng(5);
  for (const Config& c : configs()) {
    SurfaceBsdf bsdf = make_pbrt_bsdf(c.material, c.values, tilted_frame(), {0, 0, 1});
    for (int i = 0; i < 200; ++i) {
      Vec3 a = spherical(89 * rng.uniform(), 360 * rng.uniform());
      Vec3 b = spherical(89 * rng.uniform(), 360 * rng.uniform());
      Rgb fab = bsdf.f(a, b), fba = bsdf.f(b, a);
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(fab[ch], fba[ch], 1e-10 * std::max(1.0, fab[ch])) << c.name;
    }
  }
}

TEST(SurfaceBsdfRobustness, FiniteAtGrazingAnglesAndTinyRoughness) {
  std::vector<Config> all = configs();
  Config smooth = all[7];                                   // metal
  smooth.values.uroughness = smooth.values.vroughness = 0;  // clamps to 1e-3
  all.push_back(smooth);
  const Vec3 grazing[] = {{1, 0, 0},
                          {std::sqrt(1 - 1e-24), 0, 1e-12},
                          {0, 1, 1e-300},
                          {0, 0, 1},
                          spherical(89.9999, 10)};
  Rng rng(3);
  for (const Config& c : all) {
    for (const Frame& frame : {kLocal, tilted_frame()}) {
      SurfaceBsdf bsdf = make_pbrt_bsdf(c.material, c.values, frame, {0, 0, 1});
      for (const Vec3& wo_raw : grazing)
        for (const Vec3& wi_raw : grazing) {
          Vec3 wo = normalize(wo_raw), wi = normalize(wi_raw);
          EXPECT_TRUE(is_finite(bsdf.f(wo, wi))) << c.name;
          EXPECT_TRUE(is_finite(bsdf.f_for_geometric_cosine(wo, wi))) << c.name;
          EXPECT_TRUE(std::isfinite(bsdf.pdf(wo, wi))) << c.name;
          for (int k = 0; k < 50; ++k) {
            auto s = bsdf.sample(wo, rng.uniform2());
            if (s) {
              EXPECT_TRUE(is_finite(s->wi) && std::isfinite(s->pdf) && s->pdf > 0);
            }
          }
          for (Vec2 u : {Vec2{0, 0}, Vec2{1, 1}, Vec2{0.5, 1}, Vec2{1, 0}}) {
            auto s = bsdf.sample(wo, u);
            if (s) {
              EXPECT_TRUE(is_finite(s->wi) && std::isfinite(s->pdf) && s->pdf > 0);
            }
          }
        }
    }
  }
}

TEST(SurfaceBsdfDelta, MirrorAndGlassBranches) {
  Vec3 wo = spherical(40, 30);
  Material mirror = pbrt(MaterialType::Mirror);
  SurfaceBsdf m =
      make_pbrt_bsdf(mirror, constant_material_values(mirror.params), kLocal, {0, 0, 1});
  EXPECT_FALSE(m.has_non_delta());
  SpecularBranch out[SurfaceBsdf::kMaxLobes];
  ASSERT_EQ(m.specular_branches(wo, out), 1);
  EXPECT_NEAR(length(out[0].wi - Vec3{-wo.x, -wo.y, wo.z}), 0, 1e-15);
  EXPECT_EQ(out[0].weight, (Rgb{0.9, 0.9, 0.9}));  // pbrt's default Kr, no Fresnel
  EXPECT_EQ(luminance(m.f(wo, Vec3{-wo.x, -wo.y, wo.z})), 0.0);

  Material glass = pbrt(MaterialType::Glass);
  PbrtMaterialValues v = constant_material_values(glass.params);
  SurfaceBsdf g = make_pbrt_bsdf(glass, v, kLocal, {0, 0, 1});
  for (double theta : {0.0, 30.0, 60.0, 85.0}) {
    // From outside: reflected F, transmitted (1 - F) / eta^2 (radiance), Snell's law.
    Vec3 w = spherical(theta, 30);
    ASSERT_EQ(g.specular_branches(w, out), 2);
    double f = reference::fr_dielectric(w.z, 1, 1.5);
    EXPECT_NEAR(out[0].weight.x, f, 1e-12);
    EXPECT_NEAR(out[1].weight.x, (1 - f) / (1.5 * 1.5), 1e-12);
    double sin_t = std::sqrt(1 - out[1].wi.z * out[1].wi.z);
    EXPECT_LT(out[1].wi.z, 0);
    EXPECT_NEAR(1.5 * sin_t, std::sin(theta * kPi / 180), 1e-12);
    // From inside, back along the refracted direction: out along w, the same Fresnel
    // (reciprocal), radiance scaled up by eta^2.
    Vec3 inside = out[1].wi;
    ASSERT_EQ(g.specular_branches(inside, out), 2);
    EXPECT_NEAR(length(out[1].wi - w), 0, 1e-12);
    EXPECT_NEAR(out[1].weight.x, (1 - f) * 1.5 * 1.5, 1e-9);
  }
  // Total internal reflection from inside beyond the critical angle: reflection only, F = 1.
  Vec3 inside = spherical(50, 0);
  inside.z = -inside.z;
  ASSERT_EQ(g.specular_branches(inside, out), 1);
  EXPECT_EQ(out[0].weight.x, 1.0);

  // Uber's pass-through: 1 - opacity straight on, with eta 1.
  Material uber = pbrt(MaterialType::Uber);
  PbrtMaterialValues u = constant_material_values(uber.params);
  u.opacity = {0.25, 0.5, 1.0};
  u.ks = {0, 0, 0};
  SurfaceBsdf ub = make_pbrt_bsdf(uber, u, kLocal, {0, 0, 1});
  ASSERT_EQ(ub.specular_branches(wo, out), 1);
  EXPECT_NEAR(length(out[0].wi + wo), 0, 1e-15);
  EXPECT_NEAR(out[0].weight.x, 0.75, 1e-15);
  EXPECT_NEAR(out[0].weight.y, 0.5, 1e-15);
  // A fully transparent channel: its lambert lobe is scaled by the opacity.
  EXPECT_NEAR(ub.f(wo, spherical(20, 0)).x, 0.25 * 0.25 / kPi, 1e-15);
}

TEST(SurfaceBsdfDelta, RoughGlassWithTransmissionIsRefused) {
  Material glass = pbrt(MaterialType::Glass);
  EXPECT_FALSE(pbrt_material_unsupported(glass));
  glass.params.uroughness.value = 0.1;
  auto why = pbrt_material_unsupported(glass);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("rough transmission"), std::string::npos);
  glass.params.kt.value = {0, 0, 0};
  EXPECT_FALSE(pbrt_material_unsupported(glass));
}

}  // namespace
}  // namespace penumbra
