#include "core/strategies/light_checks.h"

#include "core/lights/polygon_light.h"

namespace penumbra {

std::string_view light_type_name(LightType type) {
  switch (type) {
    case LightType::Quad:
      return "quad";
    case LightType::Polygon:
      return "polygon";
    case LightType::Disk:
      return "disk";
  }
  return "light";
}

std::optional<std::string> first_light_not_quad(const Scene& scene, std::string_view what_and_why) {
  for (size_t l = 0; l < scene.lights.size(); ++l)
    if (scene.lights[l].type != LightType::Quad)
      return std::string(what_and_why) + "; light " + std::to_string(l) + " is a " +
             std::string(light_type_name(scene.lights[l].type));
  return std::nullopt;
}

std::optional<std::string> polygon_lights_only(std::string_view strategy, const Scene& scene) {
  const std::string name(strategy);
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    if (scene.lights[l].type == LightType::Disk)
      return "strategy \"" + name + "\" samples polygons and quads; light " + std::to_string(l) +
             " is a disk (use sa or area)";
    if (!is_polygon_light(scene.lights[l]))
      return "strategy \"" + name + "\" samples polygons of up to " +
             std::to_string(kMaxPolygonVertices) + " vertices; light " + std::to_string(l) +
             " has " + std::to_string(scene.lights[l].vertices.size()) + " (use sa or area)";
  }
  return std::nullopt;
}

std::optional<std::string> edge_direction_only(std::string_view strategy, LineDirection direction) {
  if (direction != LineDirection::Rand) return std::nullopt;
  return "strategy \"" + std::string(strategy) +
         ":rand\" is not defined: a random line direction per shading point has no closed-form "
         "pdf at a point (MIS and Salesin & Jarosz's point interpretation need it), and Ureña's "
         "parametrization follows the light's edges; use :u or :v";
}

}  // namespace penumbra
