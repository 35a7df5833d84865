// Disk lights sampled by rejection from their bounding square (disk_square_rejection.h).

#include "core/analysis/disk_square_rejection.h"

#include <vector>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"

namespace penumbra {

Rgb estimate_disk_lights_by_square_rejection(const Scene& scene, const ShadingPoint& sp,
                                             const Visibility& visibility, Pattern pattern,
                                             const StreamKey& key, int samples) {
  thread_local std::vector<Vec2> u;
  Rgb total;
  if (samples < 1) return total;
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    const Light& light = scene.lights[l];
    if (light.type != LightType::Disk || !(light.radius > 0)) continue;
    // A one-sided emitter seen from behind or edge-on sends nothing.
    if (!(dot(light.normal, sp.position - light.center) > 0)) continue;

    u.resize(samples);
    StreamKey stream = key;
    stream.stream = 1 + uint32_t(l) * 32;
    generate_2d(pattern, stream, 1.0, u);
    const Frame frame = Frame::from_normal(light.normal);
    const double side = 2.0 * light.radius;
    const double weight = side * side / double(samples);  // 1 / (N p), p = 1 / side^2

    Rgb light_sum;
    for (const Vec2& s : u) {
      // The point on the bounding square; reject it outside the disk.
      double a = 2.0 * s.x - 1.0, b = 2.0 * s.y - 1.0;
      if (a * a + b * b > 1.0) continue;
      Vec3 point = light.center + light.radius * (a * frame.s + b * frame.t);

      // f cos_x Le cos_l / r^2 (Salesin & Jarosz Eq. 1-2 in area measure).
      Vec3 d = point - sp.position;
      double r2 = length_squared(d);
      if (!(r2 > 0)) continue;
      Vec3 wi = d / std::sqrt(r2);
      double cos_x = dot(sp.normal, wi);
      double cos_l = -dot(light.normal, wi);
      if (cos_x <= 0 || cos_l <= 0) continue;
      Rgb le = emitted_radiance(light, point, -wi);
      if (is_black(le)) continue;
      if (visibility.occluded(sp.position, sp.normal, point)) continue;
      Rgb f = eval_bsdf(*sp.material, sp.normal, sp.wo, wi);
      Rgb contribution = f * le * (cos_x * cos_l / r2 * weight);
      if (is_finite(contribution)) light_sum += contribution;
    }
    total += light_sum;
  }
  return total;
}

}  // namespace penumbra
