#pragma once
// A chart of a light for histogram tests: a map from [0,1]^2 onto the light (or onto a rectangle
// around it), its area Jacobian, and the bin of a point. Quads: the parallelogram's (s, t).
// Disks: (rho^2 / R^2, phi / 2 pi), equal-area bins. Polygons: the bounding rectangle in the
// light's plane (points outside the polygon carry no density).

#include <optional>

#include "core/lights/light_geometry.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra::test {

class LightChart {
 public:
  explicit LightChart(const Light& light, int bins = 16) : light_(light), bins_(bins) {
    frame_ = Frame::from_normal(light.normal);
    if (light.type == LightType::Polygon) {
      lo_s_ = lo_t_ = 1e300;
      hi_s_ = hi_t_ = -1e300;
      for (const Vec3& v : light.vertices) {
        double s = dot(v - light.centroid, frame_.s), t = dot(v - light.centroid, frame_.t);
        lo_s_ = std::min(lo_s_, s);
        hi_s_ = std::max(hi_s_, s);
        lo_t_ = std::min(lo_t_, t);
        hi_t_ = std::max(hi_t_, t);
      }
    }
  }
  int bins() const { return bins_; }
  int bin_count() const { return bins_ * bins_; }

  // The point at chart coordinates (a, b) in [0,1]^2, empty when it is not on the light.
  std::optional<Vec3> point(double a, double b) const {
    switch (light_.type) {
      case LightType::Quad:
        return light_.origin + a * light_.edge1 + b * light_.edge2;
      case LightType::Disk: {
        double rho = light_.radius * std::sqrt(a), phi = 2 * kPi * b;
        return light_.center + rho * (std::cos(phi) * frame_.s + std::sin(phi) * frame_.t);
      }
      case LightType::Polygon: {
        Vec3 p = light_.centroid + (lo_s_ + a * (hi_s_ - lo_s_)) * frame_.s +
                 (lo_t_ + b * (hi_t_ - lo_t_)) * frame_.t;
        if (!light_contains(light_, p)) return std::nullopt;
        return p;
      }
    }
    return std::nullopt;
  }
  // Area of the light per unit area of chart coordinates.
  double jacobian() const {
    if (light_.type == LightType::Polygon) return (hi_s_ - lo_s_) * (hi_t_ - lo_t_);
    return light_.area;
  }
  Vec2 coordinates(const Vec3& p) const {
    switch (light_.type) {
      case LightType::Quad: {
        Vec3 n = cross(light_.edge1, light_.edge2);
        Vec3 d = p - light_.origin;
        return {dot(cross(d, light_.edge2), n) / dot(n, n),
                dot(cross(light_.edge1, d), n) / dot(n, n)};
      }
      case LightType::Disk: {
        Vec3 d = p - light_.center;
        double phi = std::atan2(dot(d, frame_.t), dot(d, frame_.s));
        if (phi < 0) phi += 2 * kPi;
        return {length_squared(d) / (light_.radius * light_.radius), phi / (2 * kPi)};
      }
      case LightType::Polygon:
        return {(dot(p - light_.centroid, frame_.s) - lo_s_) / (hi_s_ - lo_s_),
                (dot(p - light_.centroid, frame_.t) - lo_t_) / (hi_t_ - lo_t_)};
    }
    return {0, 0};
  }
  int bin(const Vec3& p) const {
    Vec2 c = coordinates(p);
    int i = std::clamp(static_cast<int>(c.x * bins_), 0, bins_ - 1);
    int j = std::clamp(static_cast<int>(c.y * bins_), 0, bins_ - 1);
    return i * bins_ + j;
  }
  // Integral of an area density over every bin (midpoint rule, sub x sub cells per bin).
  template <class AreaPdf>
  std::vector<double> integrate(const AreaPdf& pdf, int sub = 32) const {
    std::vector<double> mass(bin_count(), 0.0);
    int n = bins_ * sub;
    double cell = jacobian() / (double(n) * n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        if (auto p = point((a + 0.5) / n, (b + 0.5) / n))
          mass[(a / sub) * bins_ + b / sub] += pdf(*p) * cell;
    return mass;
  }

 private:
  Light light_;
  int bins_;
  Frame frame_;
  double lo_s_ = 0, hi_s_ = 1, lo_t_ = 0, hi_t_ = 1;
};

}  // namespace penumbra::test
