#include "core/strategies/ltc_strategy.h"

#include <cmath>

#include "core/materials/ggx.h"
#include "core/materials/ltc_ggx_table.h"

namespace penumbra {

MaterialLtc material_ltc(const Material* material, double cos_theta_o) {
  MaterialLtc result;
  if (!material || material->type != MaterialType::Ggx) return result;
  GgxLtc fitted =
      ggx_ltc(std::max(kGgxMinAlpha, material->roughness), std::clamp(cos_theta_o, 0.0, 1.0));
  result.ltc = fitted.ltc;
  result.lobe_albedo = fitted.specular_albedo(material->specular);
  return result;
}

Frame ltc_shading_frame(const Vec3& normal, const Vec3& wo) {
  Vec3 tangential = wo - dot(normal, wo) * normal;
  double tangential_length = length(tangential);
  // wo (unit) along the normal up to rounding: the lobe is isotropic, any tangent will do.
  if (!(tangential_length > 1e-9)) return Frame::from_normal(normal);
  Frame frame;
  frame.n = normal;
  frame.s = tangential / tangential_length;
  frame.t = cross(normal, frame.s);
  return frame;
}

ProjectedSolidAngleSampler LtcStrategy::make_sampler(const Vec3& position, const Frame& frame,
                                                     const PolygonLightGeometry& geometry,
                                                     const LinearlyTransformedCosine& ltc,
                                                     int iterations) {
  if (!geometry.emits_towards(position)) return ProjectedSolidAngleSampler({}, iterations);
  // The polygon relative to the shading point, in the LTC's frame, mapped to the cosine space.
  std::array<Vec3, kMaxPolygonVertices> transformed;
  for (int i = 0; i < geometry.vertex_count; ++i)
    transformed[i] = ltc.to_cosine_space(frame.to_local(geometry.vertices[i] - position));
  return ProjectedSolidAngleSampler({transformed.data(), size_t(geometry.vertex_count)},
                                    iterations);
}

namespace {

MaterialLtc shading_point_ltc(const ShadingPoint& sp) {
  Vec3 n = normalize(sp.normal);
  return material_ltc(sp.material, dot(n, sp.wo));
}

}  // namespace

LtcStrategy::LtcStrategy(const ShadingPoint& sp, const Light& light, int iterations)
    : LtcStrategy(sp, light, shading_point_ltc(sp), iterations) {}

LtcStrategy::LtcStrategy(const ShadingPoint& sp, const Light& light, const MaterialLtc& fitted,
                         int iterations)
    : position_(sp.position),
      frame_(ltc_shading_frame(normalize(sp.normal), sp.wo)),
      geometry_(polygon_light_geometry(light)),
      ltc_(fitted.ltc),
      lobe_albedo_(fitted.lobe_albedo),
      sampler_(make_sampler(position_, frame_, geometry_, ltc_, iterations)) {}

std::optional<LightPoint> LtcStrategy::sample(const Vec2& u) const {
  if (!(sampler_.projected_solid_angle() > 0)) return std::nullopt;
  std::optional<Vec3> cosine_direction = sampler_.sample(u);
  if (!cosine_direction) return std::nullopt;
  Vec3 local = ltc_.from_cosine_space(*cosine_direction);
  Vec3 direction = frame_.to_world(local);
  double distance = 0;
  std::optional<Vec3> point = geometry_.plane_hit(position_, direction, &distance);
  if (!point) return std::nullopt;
  // Solid angle density p_M(w) / I (I = PSA / pi), then area: times cos(theta_light) / r^2.
  double cos_light = -dot(geometry_.normal, direction);
  double pdf_area = ltc_.density(local) / ltc_integral() * cos_light / (distance * distance);
  if (!(pdf_area > 0) || !std::isfinite(pdf_area)) return std::nullopt;
  return LightPoint{*point, pdf_area};
}

double LtcStrategy::pdf(const Vec3& light_point) const {
  double integral = ltc_integral();
  if (!(integral > 0)) return 0.0;
  Vec3 to_light = light_point - position_;
  double r2 = length_squared(to_light);
  if (!(r2 > 0)) return 0.0;
  Vec3 direction = to_light / std::sqrt(r2);
  double cos_light = -dot(geometry_.normal, direction);
  if (!(cos_light > 0) || !geometry_.contains(light_point)) return 0.0;
  double pdf_area = ltc_.density(frame_.to_local(direction)) / integral * cos_light / r2;
  return std::isfinite(pdf_area) ? pdf_area : 0.0;
}

}  // namespace penumbra
