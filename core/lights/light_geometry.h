#pragma once
// Geometry of a light: points, emitted radiance, ray intersection. Lights are emitters only.

#include <optional>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

// Emitted radiance leaving `point_on_light` towards a receiver in direction `to_receiver`
// (unit, from the light). Zero on the back side. Includes the gaussian profile.
Rgb emitted_radiance(const Light& light, const Vec3& point_on_light, const Vec3& to_receiver);

// Point on the light for parameters (s, t) in [0,1]^2, uniform in area: the parallelogram map for
// quads, a triangle fan chosen by area for polygons, the concentric map for disks.
Vec3 light_point_uniform(const Light& light, const Vec2& u);

struct LightHit {
  double distance = 0;  // along the (unit) ray direction
  Vec3 point;
};
// Nearest intersection of a ray with the light's surface (either side), within (t_min, t_max).
std::optional<LightHit> intersect_light(const Light& light, const Vec3& origin,
                                        const Vec3& direction, double t_min, double t_max);

// True when `point` lies on the light (within a scale-relative tolerance).
bool light_contains(const Light& light, const Vec3& point);

// Signed distance of `point` from the light's plane, positive on the emitting side.
double light_plane_height(const Light& light, const Vec3& point);

// True when `point` is strictly on the emitting side of the light's plane, farther than a
// tolerance relative to the light's size and the point's distance (1e-12). A point on the plane
// or behind it receives nothing from the light; strategies give no sample there.
bool light_faces_point(const Light& light, const Vec3& point);

}  // namespace penumbra
