#include "core/strategies/bsdf_strategy.h"

#include <limits>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"

namespace penumbra {

BsdfStrategy::BsdfStrategy(const ShadingPoint& sp, const Light& light)
    : sp_(sp),
      light_(&light),
      active_(sp.material != nullptr && light_faces_point(light, sp.position)) {}

std::optional<LightPoint> BsdfStrategy::sample(const Vec2& u) const {
  if (!active_) return std::nullopt;
  auto bsdf_sample = sample_shading_bsdf(sp_, u);
  if (!bsdf_sample) return std::nullopt;
  auto hit = intersect_light(*light_, sp_.position, bsdf_sample->wi, 0.0,
                             std::numeric_limits<double>::infinity());
  if (!hit) return std::nullopt;
  double cos_light = std::abs(dot(light_->normal, bsdf_sample->wi));
  double pdf_area = bsdf_sample->pdf_solid_angle * cos_light / (hit->distance * hit->distance);
  if (!(pdf_area > 0) || !std::isfinite(pdf_area) || !is_finite(hit->point)) return std::nullopt;
  return LightPoint{hit->point, pdf_area};
}

double BsdfStrategy::pdf(const Vec3& light_point) const {
  if (!active_) return 0;
  Vec3 d = light_point - sp_.position;
  double r_squared = length_squared(d);
  if (!(r_squared > 0)) return 0;
  double r = std::sqrt(r_squared);
  Vec3 wi = d / r;
  double pdf_sa = shading_bsdf_pdf(sp_, wi);
  double pdf_area = pdf_sa * std::abs(dot(light_->normal, wi)) / r_squared;
  return std::isfinite(pdf_area) ? pdf_area : 0.0;
}

}  // namespace penumbra
