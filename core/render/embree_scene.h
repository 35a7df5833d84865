#pragma once
// The Embree scene of a loaded scene's occluder triangles: camera rays, shadow rays, BSDF rays.
// Lights are not in it (they never occlude); camera rays test lights analytically.
//
// Query APIs: single rays (rtcIntersect1 / rtcOccluded1). PERFORMANCE.md measured 16-wide packets
// 2-5x faster on small scenes for coherent camera rays; our shading interleaves light sampling,
// strategy pdfs and MIS per pixel, so rays are issued one at a time. See bench/render_bench.cpp.
//
// Precision: Embree is float; ray origins are offset along the geometric normal by a
// scene-scale-relative epsilon to avoid self-intersection.

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <optional>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

struct SurfaceHit {
  double distance = 0;
  Vec3 position;
  Vec3 geometric_normal;  // unit, not yet flipped
  uint32_t triangle = 0;
  Vec2 barycentric;  // weights of the triangle's vertices 1 and 2
};

class EmbreeScene {
 public:
  explicit EmbreeScene(const Scene& scene);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  std::optional<SurfaceHit> intersect(const Vec3& origin, const Vec3& direction,
                                      double t_max = 1e30) const;
  // True when a surface blocks the segment from `from` (on a surface with normal `normal`,
  // facing the segment) to `to` (on a light). Both ends are excluded by a relative epsilon.
  bool occluded(const Vec3& from, const Vec3& normal, const Vec3& to) const;

  // The Embree scene itself, for benchmarks of other query APIs (packets, streams).
  RTCScene rtc_scene() const { return scene_; }

  // Offset used for ray origins: scene-scale relative.
  double ray_epsilon() const { return ray_epsilon_; }

  // Bytes Embree holds for this scene (BVH and buffers), as its memory monitor reports them.
  size_t memory_bytes() const { return size_t(std::max<int64_t>(0, memory_bytes_.load())); }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  const Scene* source_;
  double ray_epsilon_ = 1e-4;
  std::atomic<int64_t> memory_bytes_{0};
};

}  // namespace penumbra
