#include "core/analysis/stability.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "core/analysis/mean_consistency.h"
#include "core/math/lambert_polygon.h"
#include "core/method/method.h"
#include "core/render/shading.h"
#include "core/scene/scene.h"

namespace penumbra {

namespace {

using json = nlohmann::json;

constexpr double kAlbedo = 0.5;

json vec(const Vec3& v) {
  return json::array({v.x, v.y, v.z});
}

// A light-facing-down rectangle centred at `center` (height y), w along x and h along z:
// edge1 = (w,0,0), edge2 = (0,0,h), so cross(edge1, edge2) = (0,-w h,0) points down.
json down_rectangle(const Vec3& center, double w, double h, double radiance) {
  return {{"type", "quad"},
          {"origin", vec(center - Vec3{w / 2, 0, h / 2})},
          {"edge1", vec({w, 0, 0})},
          {"edge2", vec({0, 0, h})},
          {"radiance", vec({radiance, radiance, radiance})}};
}

json triangles(const std::vector<Vec3>& positions) {
  json p = json::array(), indices = json::array();
  for (size_t i = 0; i < positions.size(); ++i) {
    p.push_back(vec(positions[i]));
    indices.push_back(int(i));
  }
  return {{"type", "triangles"}, {"positions", p}, {"indices", indices}, {"material", "occluder"}};
}

json scene_with(const json& receiver, const json& light, const json& shapes) {
  json scene = {{"format", "penumbra/scene@1"},
                {"name", "stability"},
                {"camera",
                 {{"position", vec({0, 0.5, 3})},
                  {"look_at", vec({0, 0, 0})},
                  {"up", vec({0, 1, 0})},
                  {"fov_y_deg", 40},
                  {"width", 8},
                  {"height", 8}}},
                {"materials",
                 {{"receiver", receiver},
                  {"occluder", {{"type", "lambert"}, {"albedo", vec({0.5, 0.5, 0.5})}}}}},
                {"shapes", shapes},
                {"lights", json::array({light})}};
  // Every scene has at least one shape: a small far-away triangle that occludes nothing.
  if (scene["shapes"].empty())
    scene["shapes"].push_back(triangles({{50, -50, 50}, {51, -50, 50}, {50, -50, 51}}));
  return scene;
}

json lambert_receiver() {
  return {{"type", "lambert"}, {"albedo", vec({kAlbedo, kAlbedo, kAlbedo})}};
}

// albedo * Le * F: a Lambertian receiver under a constant one-sided emitter whose visible part
// is `visible` (the emitter faces x).
Rgb lambert_closed_form(const Vec3& x, const Vec3& n, const std::vector<Vec3>& visible,
                        double radiance) {
  double f = lambert_polygon_form_factor(x, n, visible);
  double value = kAlbedo * radiance * f;
  return {value, value, value};
}

std::vector<Vec3> down_rectangle_vertices(const Vec3& center, double w, double h) {
  Vec3 o = center - Vec3{w / 2, 0, h / 2};
  return {o, o + Vec3{w, 0, 0}, o + Vec3{w, 0, h}, o + Vec3{0, 0, h}};
}

StabilityCase named_case(std::string name, std::string description) {
  StabilityCase c;
  c.name = std::move(name);
  c.description = std::move(description);
  return c;
}

double channel_mean(const Rgb& c) {
  return (c.x + c.y + c.z) / 3;
}
bool finite(const Rgb& c) {
  return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
}

struct Moments {
  uint64_t count = 0, nonfinite = 0;
  double sum = 0, sum_squares = 0;
  double mean() const { return count ? sum / double(count) : 0; }
  double variance() const {
    if (count < 2) return 0;
    double m = mean();
    return std::max(0.0, (sum_squares - double(count) * m * m) / double(count - 1));
  }
  double standard_error() const { return count ? std::sqrt(variance() / double(count)) : 0; }
};

// `trials` estimates of `samples` samples each by `method` at the case's point.
Moments estimate(const StabilityCase& c, size_t case_index, const std::string& method, int trials,
                 int samples, uint64_t seed) {
  auto scene = std::make_shared<Scene>(parse_scene(c.scene_json, ".", c.name));
  SceneShading shading(scene, parse_method(method));  // throws FormatError: refused
  const Material* receiver = nullptr;
  for (const Material& m : scene->materials)
    if (m.name == "receiver") receiver = &m;
  if (!receiver) throw std::logic_error("stability case " + c.name + ": no receiver material");
  ShadingPoint sp;
  sp.position = c.position;
  sp.wo = normalize(c.wo);
  Vec3 n = normalize(c.normal);
  sp.normal = dot(n, sp.wo) < 0 ? -n : n;
  sp.material = receiver;
  Moments moments;
  for (int trial = 0; trial < trials; ++trial) {
    StreamKey key{seed, uint64_t(case_index), uint32_t(trial), 0};
    Rgb value = shading.direct_lighting().estimate(sp, shading, Pattern::Stratified, key, samples);
    if (!finite(value)) {
      ++moments.nonfinite;
      continue;
    }
    double v = channel_mean(value);
    ++moments.count;
    moments.sum += v;
    moments.sum_squares += v * v;
  }
  return moments;
}

std::string format_percent(double fraction) {
  char buffer[32];
  double p = 100 * fraction;
  if (std::abs(p) < 0.005)
    std::snprintf(buffer, sizeof buffer, "0.00%%");
  else
    std::snprintf(buffer, sizeof buffer, "%+.2f%%", p);
  return buffer;
}

}  // namespace

std::vector<StabilityCase> stability_cases() {
  std::vector<StabilityCase> cases;
  const Vec3 origin{0, 0, 0};
  const Vec3 up{0, 1, 0};
  const Vec3 view = normalize(Vec3{0.2, 1, 0.3});
  json none = json::array();

  {  // The shading point lies in the light's plane: the light is seen edge-on, the value is 0.
    StabilityCase c =
        named_case("on-light-plane", "shading point in the light's plane (edge-on light)");
    json light = down_rectangle({1.5, 0, 0}, 1, 1, 10);
    c.scene_json = scene_with(lambert_receiver(), light, none).dump();
    c.position = origin;
    c.normal = {1, 0, 0};
    c.wo = normalize(Vec3{1, 0.2, 0.3});
    c.closed_form = Rgb{0, 0, 0};
    cases.push_back(c);
  }
  {  // 1e-7 below the plane, on the emitting side.
    StabilityCase c = named_case("near-light-plane", "shading point 1e-7 from the light's plane");
    json light = down_rectangle({1.5, 0, 0}, 1, 1, 10);
    c.scene_json = scene_with(lambert_receiver(), light, none).dump();
    c.position = {0, -1e-7, 0};
    c.normal = {1, 0, 0};
    c.wo = normalize(Vec3{1, 0.2, 0.3});
    c.closed_form =
        lambert_closed_form(c.position, c.normal, down_rectangle_vertices({1.5, 0, 0}, 1, 1), 10);
    cases.push_back(c);
  }
  {  // A vertical light (facing -x) whose vertical edges are parallel to the receiver's normal
     // and which crosses the receiver's horizon (Peters Fig. 12's configuration).
    StabilityCase c = named_case("edges-parallel-to-normal",
                                 "light edges parallel to the normal, light crossing the horizon");
    json light = {{"type", "quad"},
                  {"origin", vec({1, -0.5, -0.5})},
                  {"edge1", vec({0, 0, 1})},
                  {"edge2", vec({0, 2, 0})},
                  {"radiance", vec({5, 5, 5})}};
    c.scene_json = scene_with(lambert_receiver(), light, none).dump();
    c.position = origin;
    c.normal = up;
    c.wo = view;
    std::vector<Vec3> vertices{{1, -0.5, -0.5}, {1, -0.5, 0.5}, {1, 1.5, 0.5}, {1, 1.5, -0.5}};
    c.closed_form = lambert_closed_form(c.position, c.normal, vertices, 5);
    cases.push_back(c);
  }
  for (double size : {0.01, 0.001}) {  // Peters Fig. 7: tiny lights 40 m away, an occluder near.
    bool cm = size == 0.01;
    StabilityCase c =
        named_case(cm ? "distant-1cm" : "distant-1mm",
                   std::string(cm ? "1 cm" : "1 mm") + " square light 40 m away, occluder near");
    double radiance = cm ? 1e8 : 1e10;
    json light = down_rectangle({0, 40, 0}, size, size, radiance);
    json shapes = json::array({{{"type", "box"},
                                {"min", vec({0.05, 0, -0.1})},
                                {"max", vec({0.15, 0.3, 0.1})},
                                {"material", "occluder"}}});
    c.scene_json = scene_with(lambert_receiver(), light, shapes).dump();
    c.position = origin;
    c.normal = up;
    c.wo = view;
    c.closed_form = lambert_closed_form(c.position, c.normal,
                                        down_rectangle_vertices({0, 40, 0}, size, size), radiance);
    cases.push_back(c);
  }
  {  // A 200 x 200 light 1e-3 above the point: almost the whole hemisphere.
    StabilityCase c = named_case("huge-light-near", "200 x 200 light 1e-3 above the point");
    json light = down_rectangle({0, 1e-3, 0}, 200, 200, 1);
    c.scene_json = scene_with(lambert_receiver(), light, none).dump();
    c.position = origin;
    c.normal = up;
    c.wo = view;
    c.closed_form = lambert_closed_form(c.position, c.normal,
                                        down_rectangle_vertices({0, 1e-3, 0}, 200, 200), 1);
    cases.push_back(c);
  }
  {  // Occluders of zero area (collinear, repeated vertices) and triangles whose plane contains
     // the shading point (edge-on, two of them coplanar and sharing an edge): they hide a set of
     // measure zero, so the value is the unoccluded one.
    StabilityCase c =
        named_case("degenerate-occluders", "zero-area and edge-on coplanar occluder triangles");
    json light = down_rectangle({0, 1, 0}, 1, 1, 4);
    json shapes = json::array({
        triangles({{-0.2, 0.5, 0.05}, {0, 0.5, 0.05}, {0.2, 0.5, 0.05}}),  // collinear
        triangles({{0, 0.4, 0.1}, {0, 0.4, 0.1}, {0.3, 0.45, 0.2}}),       // repeated vertex
        triangles({{-0.3, 0.3, 0}, {0.3, 0.3, 0}, {0, 0.7, 0}}),           // plane z = 0
        triangles({{0, 0.2, -0.4}, {0, 0.8, -0.4}, {0, 0.8, 0.4}}),        // plane x = 0 ...
        triangles({{0, 0.2, -0.4}, {0, 0.8, 0.4}, {0, 0.2, 0.4}}),         // ... shared edge
    });
    c.scene_json = scene_with(lambert_receiver(), light, shapes).dump();
    c.position = origin;
    c.normal = up;
    c.wo = view;
    c.closed_form =
        lambert_closed_form(c.position, c.normal, down_rectangle_vertices({0, 1, 0}, 1, 1), 4);
    cases.push_back(c);
  }
  {  // A half-plane occluder at y = 0.5 over z < 0 whose edge (z = 0) lies in the shadow
     // triangle of the u-direction line sample through the light's centre line: exactly the
     // light's half z > 0 is visible.
    StabilityCase c = named_case("occluder-edge-in-shadow-triangle",
                                 "occluder edge lying in a line sample's shadow triangle");
    json light = down_rectangle({0, 1, 0}, 1, 1, 4);
    json shapes = json::array({{{"type", "quad"},
                                {"origin", vec({-10, 0.5, -10})},
                                {"edge1", vec({20, 0, 0})},
                                {"edge2", vec({0, 0, 10})},
                                {"material", "occluder"}}});
    c.scene_json = scene_with(lambert_receiver(), light, shapes).dump();
    c.position = origin;
    c.normal = up;
    c.wo = view;
    std::vector<Vec3> visible{{-0.5, 1, 0}, {0.5, 1, 0}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
    c.closed_form = lambert_closed_form(c.position, c.normal, visible, 4);
    cases.push_back(c);
  }
  // Glossy receivers: the mirror direction of wo about the normal points at the light's centre.
  const Vec3 glossy_wo = normalize(Vec3{-0.3, 1, 0});
  const Vec3 glossy_light_center{0.3, 1, 0};
  struct Glossy {
    const char* name;
    const char* description;
    json material;
  };
  for (const Glossy& g : {
           Glossy{"phong-exponent-1e4",
                  "phong receiver, exponent 10^4, light in the lobe",
                  {{"type", "phong"},
                   {"kd", vec({0.05, 0.05, 0.05})},
                   {"ks", vec({0.5, 0.5, 0.5})},
                   {"exponent", 10000}}},
           Glossy{"ggx-roughness-1e-4",
                  "ggx receiver, roughness 1e-4, light in the lobe",
                  {{"type", "ggx"},
                   {"diffuse", vec({0.05, 0.05, 0.05})},
                   {"specular", vec({0.9, 0.9, 0.9})},
                   {"roughness", 1e-4}}},
           Glossy{"ggx-roughness-1",
                  "ggx receiver, roughness 1",
                  {{"type", "ggx"},
                   {"diffuse", vec({0.05, 0.05, 0.05})},
                   {"specular", vec({0.9, 0.9, 0.9})},
                   {"roughness", 1.0}}},
       }) {
    StabilityCase c = named_case(g.name, g.description);
    json light = down_rectangle(glossy_light_center, 0.2, 0.2, 10);
    c.scene_json = scene_with(g.material, light, none).dump();
    c.position = origin;
    c.normal = up;
    c.wo = glossy_wo;
    cases.push_back(c);
  }
  return cases;
}

std::vector<std::string> stability_methods() {
  return {"area",
          "sa",
          "psa",
          "ltc",
          "bsdf",
          "bsdf+sa",
          "bsdf+sa/power",
          "bsdf+psa",
          "line-area:u",
          "line-sa:v",
          "line-sa:u+line-sa:v",
          "line-bd16:u",
          "line-bd16:rand",
          "bsdf+line-sa:v/balance",
          "bsdf+line-sa:v/smooth-fixed",
          "bsdf+line-sa:v/smooth",
          "psa+ltc/weighted",
          "psa+ltc/clamped-optimal"};
}

std::string expected_unconverged(const std::string& method, const std::string& case_name) {
  auto one_of = [&](std::initializer_list<const char*> names) {
    for (const char* name : names)
      if (method == name) return true;
    return false;
  };
  if (case_name == "huge-light-near" &&
      one_of({"area", "line-area:u", "line-bd16:u", "line-bd16:rand"}))
    return "uniform area density over a 200 x 200 light 1e-3 away: the integrand's mass lies in "
           "~1e-10 of the area";
  if (method == "bsdf" &&
      (case_name == "near-light-plane" || case_name == "distant-1cm" || case_name == "distant-1mm"))
    return "BSDF sampling of a light of ~1e-8 sr or less: almost no sample hits it";
  if (case_name == "ggx-roughness-1e-4" &&
      one_of({"area", "sa", "psa", "line-area:u", "line-sa:v", "line-sa:u+line-sa:v"}))
    return "light sampling of a GGX lobe of ~1e-8 sr: almost no sample falls in the lobe";
  return {};
}

const StabilityCell& StabilityTable::cell(const std::string& method,
                                          const std::string& case_name) const {
  for (const StabilityCell& c : cells)
    if (c.method == method && c.case_name == case_name) return c;
  throw std::out_of_range("no stability cell for " + method + " / " + case_name);
}

StabilityTable run_stability(const StabilityOptions& options) {
  StabilityTable table;
  for (const StabilityCase& c : stability_cases()) {
    bool wanted = options.cases.empty();
    for (const std::string& name : options.cases) wanted |= name == c.name;
    if (wanted) table.cases.push_back(c);
  }
  table.methods = options.methods.empty() ? stability_methods() : options.methods;

  int steps = int(table.methods.size() * table.cases.size()), done = 0;
  for (const StabilityCase& c : table.cases) steps += !c.closed_form;
  // References: the closed form, or a converged bsdf+sa estimate with its standard error.
  std::vector<double> reference(table.cases.size()), reference_error(table.cases.size());
  std::vector<int> reference_trials(table.cases.size(), 0);  // 0: exact
  for (size_t i = 0; i < table.cases.size(); ++i) {
    const StabilityCase& c = table.cases[i];
    if (c.closed_form) {
      reference[i] = channel_mean(*c.closed_form);
      table.reference_kind.push_back("closed form");
    } else {
      if (options.progress) options.progress("reference for " + c.name, done++, steps);
      Moments m = estimate(c, i, "bsdf+sa", options.reference_trials, options.reference_samples,
                           options.seed ^ 0xA5A5A5A5ull);
      if (m.nonfinite) throw std::runtime_error("the reference for " + c.name + " is not finite");
      reference[i] = m.mean();
      reference_error[i] = m.standard_error();
      reference_trials[i] = int(m.count);
      table.reference_kind.push_back(
          "bsdf+sa, " +
          std::to_string(uint64_t(options.reference_trials) * uint64_t(options.reference_samples)) +
          " samples");
    }
  }

  for (const std::string& method : table.methods) {
    for (size_t i = 0; i < table.cases.size(); ++i) {
      const StabilityCase& c = table.cases[i];
      if (options.progress) options.progress(method + " on " + c.name, done++, steps);
      StabilityCell cell;
      cell.method = method;
      cell.case_name = c.name;
      cell.reference = reference[i];
      cell.expected_unconverged = expected_unconverged(method, c.name);
      Moments m;
      try {
        m = estimate(c, i, method, options.trials, options.samples, options.seed);
      } catch (const FormatError& error) {
        cell.refused = true;
        cell.refusal = error.what();
        table.cells.push_back(cell);
        continue;
      }
      cell.estimates = m.count + m.nonfinite;
      cell.nonfinite = m.nonfinite;
      cell.mean = m.mean();
      cell.standard_error = m.standard_error();
      double difference = cell.mean - cell.reference;
      double scale = std::abs(cell.reference);
      cell.relative_bias = scale > 0 ? difference / scale : (difference == 0 ? 0 : difference);
      double combined = std::hypot(cell.standard_error, reference_error[i]);
      cell.bias_sigmas =
          combined > 0 ? std::abs(difference) / combined : (difference == 0 ? 0 : INFINITY);
      cell.relative_std = scale > 0 ? std::sqrt(m.variance()) / scale : std::sqrt(m.variance());
      // A zero reference must be met exactly (up to 1e-12 of the light's scale: the estimate
      // of an edge-on light is zero, not noise).
      if (scale == 0)
        cell.consistent = std::abs(cell.mean) <= 1e-12 && cell.nonfinite == 0;
      else if (m.count < 2)
        cell.consistent = false;
      else
        // Welch's t at the false-alarm rate of a 5-sigma normal test, whatever the trial count
        // (core/analysis/mean_consistency.h): with few trials the standard errors are noisy.
        cell.consistent = cell.nonfinite == 0 &&
                          (mean_consistency(cell.mean, cell.standard_error, int(m.count),
                                            cell.reference, reference_error[i], reference_trials[i])
                               .consistent ||
                           std::abs(cell.relative_bias) <= 1e-3);
      table.cells.push_back(cell);
    }
  }
  if (options.progress) options.progress("done", steps, steps);
  return table;
}

std::string stability_markdown(const StabilityTable& table) {
  std::ostringstream out;
  out << "| method |";
  for (const StabilityCase& c : table.cases) out << " " << c.name << " |";
  out << "\n|---|";
  for (size_t i = 0; i < table.cases.size(); ++i) out << "---|";
  out << "\n";
  for (const std::string& method : table.methods) {
    out << "| `" << method << "` |";
    for (const StabilityCase& c : table.cases) {
      const StabilityCell& cell = table.cell(method, c.name);
      out << " ";
      if (cell.refused) {
        out << "refused";
      } else {
        out << format_percent(cell.relative_bias);
        if (cell.nonfinite) out << " NaN:" << cell.nonfinite;
        if (!cell.expected_unconverged.empty())
          out << " ~";
        else if (!cell.consistent)
          out << " !";
      }
      out << " |";
    }
    out << "\n";
  }
  out << "\nCells: relative bias of the mean of the estimates against the reference. `~`: the "
         "method is unbiased but cannot converge here at any practical budget (listed in "
         "core/analysis/stability.cpp); `!`: inconsistent with the reference (Welch's t test at "
         "the false-alarm rate of 5 standard errors, its threshold growing as the trials get "
         "fewer, and more than 0.1%); `NaN:k`: k non-finite estimates.\n";
  out << "\nReferences: ";
  for (size_t i = 0; i < table.cases.size(); ++i)
    out << (i ? "; " : "") << table.cases[i].name << ": " << table.reference_kind[i];
  out << ".\n";
  return out.str();
}

std::string stability_json(const StabilityTable& table) {
  json doc;
  doc["format"] = "penumbra/stability@1";
  doc["cases"] = json::array();
  for (size_t i = 0; i < table.cases.size(); ++i)
    doc["cases"].push_back({{"name", table.cases[i].name},
                            {"description", table.cases[i].description},
                            {"reference", table.reference_kind[i]}});
  doc["methods"] = table.methods;
  doc["cells"] = json::array();
  for (const StabilityCell& c : table.cells) {
    json cell = {{"method", c.method}, {"case", c.case_name}, {"refused", c.refused}};
    if (c.refused) {
      cell["refusal"] = c.refusal;
    } else {
      cell.update({{"estimates", c.estimates},
                   {"nonfinite", c.nonfinite},
                   {"mean", c.mean},
                   {"reference", c.reference},
                   {"standard_error", c.standard_error},
                   {"relative_bias", c.relative_bias},
                   {"bias_sigmas", std::isfinite(c.bias_sigmas) ? json(c.bias_sigmas) : json()},
                   {"relative_std", c.relative_std},
                   {"consistent", c.consistent},
                   {"expected_unconverged", c.expected_unconverged}});
    }
    doc["cells"].push_back(cell);
  }
  return doc.dump(2);
}

}  // namespace penumbra
