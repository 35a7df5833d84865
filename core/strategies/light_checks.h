#pragma once
// The "can it run on this scene" checks several strategies share (and the smoothing
// combinations, which need quads too). Each returns the reason, naming the light, or nothing.

#include <optional>
#include <string>
#include <string_view>

#include "core/scene/scene.h"
#include "core/strategies/registry.h"

namespace penumbra {

std::string_view light_type_name(LightType type);

// "<what_and_why>; light L is a polygon" for the first light that is not a quad.
std::optional<std::string> first_light_not_quad(const Scene& scene, std::string_view what_and_why);

// Peters' polygon samplers (psa, ltc): every light a quad or a convex polygon of at most
// kMaxPolygonVertices vertices.
std::optional<std::string> polygon_lights_only(std::string_view strategy, const Scene& scene);

// Line strategies that follow the light's edges (u or v): a random direction per shading point
// has no closed-form pdf at a point.
std::optional<std::string> edge_direction_only(std::string_view strategy, LineDirection direction);

}  // namespace penumbra
