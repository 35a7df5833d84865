#pragma once
// `sa`: uniform sampling of the solid angle the light subtends at the shading point
// (SCENE_FORMAT.md), returned in area measure: p_area = cos(theta_light) / (r^2 * Omega).
//
// - Rectangular quads (edges perpendicular to 1e-6 relative): Ureña, Fajardo & King 2013
//   (core/math/spherical_rectangle.h); u.x picks the line along edge2, u.y the point on it.
// - Other parallelograms and polygons: Peters 2021 Sec. 5 (SolidAnglePolygonSampler,
//   core/math/solid_angle_polygon.h): the triangle fan around vertex 0, a triangle chosen
//   by its solid angle (van Oosterom & Strackee), then
//   Peters' subtriangle construction of Arvo 1995's map; every fan triangle is prepared once per
//   shading point (no heap allocation). Polygons of more than kMaxPolygonVertices (16) vertices
//   (the scene format allows 1024) use the same construction with each triangle's solid angle
//   recomputed per sample instead of stored.
// - Disks: uniform sampling of the cone of directions bounding the disk (the cone tangent to the
//   disk's bounding sphere, or the whole hemisphere towards the disk when the point is within the
//   radius of the centre); a direction that misses the disk gives no sample. Every point of the
//   disk is reached with the density cos(theta_light) / (r^2 * Omega_cone), so the estimator is
//   unbiased; the misses cost efficiency (about cos(theta_light) of the samples hit far away).
//
// No sample, and density 0, when the shading point is not strictly in front of the light (on its
// plane or behind: the light sends it nothing) or the solid angle is degenerate.

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "core/math/solid_angle_polygon.h"
#include "core/math/spherical_rectangle.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class SolidAngleStrategy {
 public:
  // The strategy's name in the method grammar (SCENE_FORMAT.md).
  static constexpr std::string_view name() { return "sa"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Point;
  static constexpr bool kRectangleStrata = true;
  // Runs on every light and material.
  static std::optional<std::string> refusal(const Scene&, LineDirection) { return std::nullopt; }

  SolidAngleStrategy(const ShadingPoint& sp, const Light& light);
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point of the light (the point is assumed to lie on the light).
  double pdf(const Vec3& light_point) const;
  // Solid angle of the sampled domain (the light's, or the bounding cone's for disks); 0 when
  // the strategy cannot sample.
  double sampled_solid_angle() const { return solid_angle_; }

 private:
  enum class Domain { None, Rectangle, Fan, LargeFan, Cone };
  std::optional<LightPoint> sample_large_fan(const Vec2& u) const;
  double large_fan_triangle(size_t i) const;
  std::optional<LightPoint> sample_cone(const Vec2& u) const;
  std::optional<LightPoint> finish(const Vec3& point) const;
  // The point where the direction from x meets the light's plane, as a sample.
  std::optional<LightPoint> along(const Vec3& direction) const;

  const Light* light_;
  Vec3 x_;
  Domain domain_ = Domain::None;
  double solid_angle_ = 0;
  SphericalRectangle rectangle_;
  std::optional<SolidAnglePolygonSampler> fan_;
  Frame cone_frame_;
  double cone_one_minus_cos_ = 0;
};

}  // namespace penumbra
