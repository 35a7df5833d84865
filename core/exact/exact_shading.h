#pragma once
// Exact direct illumination where a closed form exists, a converged estimate elsewhere.
//
// A Lambertian receiver lit by lights that are all constant polygons (quads and polygon lights
// with the constant profile) reflects L = (albedo / pi) sum_lights Le * P, P the projected solid
// angle of the light's visible part (core/exact/visible_light.h): exact up to rounding. Anything
// else (Phong or GGX receivers, disk or gaussian lights) falls back to the fallback method's
// estimate with many samples per shading point, and is reported as not exact.

#include <memory>
#include <optional>
#include <string>

#include "core/exact/visible_light.h"
#include "core/lines/line_query.h"
#include "core/render/shading.h"
#include "core/scene/scene.h"

namespace penumbra {

struct ExactShadingOptions {
  std::string fallback_method = "bsdf+sa";  // penumbra/method@1
  int fallback_samples = 64;                // samples per term and shading point
};

struct ExactSample {
  Rgb radiance;
  bool exact = false;
};

class ExactShading {
 public:
  // Throws FormatError when the fallback method cannot run on the scene.
  ExactShading(std::shared_ptr<const Scene> scene, const ExactShadingOptions& options = {});

  const Scene& scene() const { return shading_.scene(); }
  const SceneShading& shading() const { return shading_; }
  const LineQuery& occluders() const { return occluders_; }
  const ExactShadingOptions& options() const { return options_; }
  // Every light is a constant polygon (else nothing is exact).
  bool lights_have_closed_form() const { return lights_exact_; }

  // The closed form at a shading point, empty when none applies (its material or a light).
  std::optional<Rgb> exact_radiance(const ShadingPoint& sp, VisibleLightScratch& scratch,
                                    VisibleLightStats* stats = nullptr) const;
  // What a camera hit reflects: emitted light seen directly (exact), the closed form, or the
  // fallback estimate with `key` for its random streams.
  ExactSample radiance(const SceneShading::FirstHit& hit, const StreamKey& key,
                       VisibleLightScratch& scratch, VisibleLightStats* stats = nullptr) const;

 private:
  ExactShadingOptions options_;
  SceneShading shading_;
  LineQuery occluders_;
  bool lights_exact_ = false;
};

}  // namespace penumbra
