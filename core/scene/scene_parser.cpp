#include "core/scene/scene_parser.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/scene/json_node.h"
#include "core/scene/light_setup.h"
#include "core/scene/pbrt_scene_builder.h"
#include "core/scene/scene_package.h"
#include "core/scene/scene_path.h"
#include "core/scene/shape_mesh.h"

namespace penumbra {

namespace {

constexpr std::string_view kSceneFormat = "penumbra/scene@1";
// Past this a radiance component is refused as absurd: 1e15 leaves room for tiny bright lights
// (the renderer tests use 1e9 on a 1 mm light at 40 m; bundled scenes stay below 1e4) and keeps
// every estimator's products far from overflowing a double.
constexpr double kMaxRadiance = 1e15;

std::string number_text(double x) {
  std::ostringstream out;
  out.precision(12);
  out << x;
  return out.str();
}

class SceneParser {
 public:
  SceneParser(const ObjFileReader& read_obj, const std::string& source, const SceneLimits& limits)
      : read_obj_(read_obj), source_(source), limits_(limits) {}

  ParsedScene parse(const std::string& json_text) {
    if (json_text.size() > limits_.max_json_bytes)
      throw FormatError("$", "the scene has " + std::to_string(json_text.size()) +
                                 " bytes, more than the limit max_json_bytes = " +
                                 std::to_string(limits_.max_json_bytes) + " (in " + source_ + ")");
    nlohmann::json document = parse_json_document(json_text, source_, limits_.max_json_depth);
    JsonNode root(document, "$", source_);
    root.expect_object();
    check_format(root.required("format"));
    root.collect_unknown_keys(
        {"format", "name", "description", "camera", "materials", "shapes", "lights", "regions"},
        scene().warnings);

    if (auto name = root.optional("name"))
      scene().name = name->string();
    else
      scene().name = default_name();
    if (auto description = root.optional("description"))
      scene().description = description->string();
    parse_camera(root.required("camera"));
    parse_materials(root.required("materials"));
    parse_shapes(root.required("shapes"));
    parse_lights(root.required("lights"));
    if (auto regions = root.optional("regions")) parse_regions(*regions);

    result_.scene.content_hash = scene_content_hash(json_text, result_.obj_files);
    return std::move(result_);
  }

 private:
  Scene& scene() { return result_.scene; }
  const Scene& scene() const { return result_.scene; }

  // Without a "name" key, a scene is named for its file: "scenes/cornell-box.json" ->
  // "cornell-box".
  std::string default_name() const {
    std::filesystem::path path(source_);
    return path.extension() == ".json" ? path.stem().string() : std::string();
  }

  void check_format(const JsonNode& node) {
    std::string format = node.string();
    if (format == kSceneFormat) return;
    if (format.rfind("penumbra/scene@", 0) == 0)
      node.fail("unsupported scene format version '" + format + "' (this reader reads " +
                std::string(kSceneFormat) + ")");
    node.fail("not a scene: format is '" + format + "', expected '" + std::string(kSceneFormat) +
              "'");
  }

  // A point or vector of the scene: finite, and within the absurd-coordinate limit.
  Vec3 coordinate(const JsonNode& node) const {
    Vec3 v = node.vec3();
    for (int axis = 0; axis < 3; ++axis)
      if (std::abs(v[axis]) > limits_.max_coordinate)
        node.fail("coordinate " + number_text(v[axis]) +
                  " exceeds the limit max_coordinate = " + number_text(limits_.max_coordinate));
    return v;
  }

  // The point of a raw [x, y, z] when it is valid (finite numbers within the coordinate limit),
  // else empty: the caller then goes through coordinate() for the error.
  std::optional<Vec3> plain_coordinate(const nlohmann::json& value) const {
    if (!value.is_array() || value.size() != 3) return std::nullopt;
    Vec3 p;
    for (int axis = 0; axis < 3; ++axis) {
      const nlohmann::json& c = value[axis];
      if (!c.is_number()) return std::nullopt;
      p[axis] = c.get<double>();
      if (!(std::abs(p[axis]) <= limits_.max_coordinate)) return std::nullopt;
    }
    return p;
  }

  double positive(const JsonNode& node, const char* what) const {
    double x = node.number();
    if (!(x > 0)) node.fail(std::string(what) + " must be positive, got " + node.quoted_value());
    return x;
  }

  // An RGB reflectance, each component in [0, 1].
  Rgb reflectance(const JsonNode& node) const {
    Rgb c = node.vec3();
    for (int i = 0; i < 3; ++i)
      if (c[i] < 0 || c[i] > 1)
        node.fail("reflectance components must lie in [0, 1], got " + node.quoted_value());
    return c;
  }

  Rgb radiance(const JsonNode& node) const {
    Rgb c = node.vec3();
    for (int i = 0; i < 3; ++i)
      if (c[i] < 0) node.fail("negative radiance " + node.quoted_value());
    for (int i = 0; i < 3; ++i)
      if (c[i] > kMaxRadiance)
        node.fail("radiance " + node.quoted_value() +
                  " exceeds the limit max_radiance = " + number_text(kMaxRadiance));
    return c;
  }

  int image_size(const JsonNode& node) const {
    int64_t size = node.integer();
    if (size < 1) node.fail("image size must be at least 1, got " + node.quoted_value());
    if (size > limits_.max_resolution)
      node.fail("image size " + node.quoted_value() +
                " exceeds the limit max_resolution = " + std::to_string(limits_.max_resolution));
    return static_cast<int>(size);
  }

  void parse_camera(const JsonNode& node) {
    node.expect_object();
    node.collect_unknown_keys({"position", "look_at", "up", "fov_y_deg", "width", "height"},
                              scene().warnings);
    Camera& camera = scene().camera;
    camera.position = coordinate(node.required("position"));
    camera.look_at = coordinate(node.required("look_at"));
    if (auto up = node.optional("up")) camera.up = up->vec3();
    JsonNode fov = node.required("fov_y_deg");
    camera.fov_y_deg = fov.number();
    if (!(camera.fov_y_deg > 0 && camera.fov_y_deg < 180))
      fov.fail("fov_y_deg (the full vertical angle) must lie in (0, 180), got " +
               fov.quoted_value());
    camera.width = image_size(node.required("width"));
    camera.height = image_size(node.required("height"));

    Vec3 view = camera.look_at - camera.position;
    double scale = std::max(length(camera.position), length(camera.look_at));
    if (!(length(view) > 1e-12 * scale) || length(view) == 0)
      node.required("look_at").fail("look_at coincides with position: no view direction");
    if (!(length(cross(view, camera.up)) > kDegenerateSine * length(view) * length(camera.up)))
      node.fail("up [" + number_text(camera.up.x) + ", " + number_text(camera.up.y) + ", " +
                number_text(camera.up.z) + "] is zero or parallel to the view direction");
  }

  void parse_materials(const JsonNode& node) {
    node.expect_object();
    for (const std::string& name : node.keys()) {
      JsonNode entry = node.member(name);
      if (name.empty()) entry.fail("a material needs a non-empty name");
      entry.expect_object();
      Material material;
      material.name = name;
      JsonNode type = entry.required("type");
      std::string type_name = type.string();
      if (type_name == "lambert") {
        material.type = MaterialType::Lambert;
        entry.collect_unknown_keys({"type", "albedo"}, scene().warnings);
        material.albedo = reflectance(entry.required("albedo"));
      } else if (type_name == "phong") {
        // Billen & Dutré Eq. 9: kd/pi + ks (n+2)/(2 pi) cos^n. kd defaults to black.
        material.type = MaterialType::Phong;
        entry.collect_unknown_keys({"type", "kd", "ks", "exponent"}, scene().warnings);
        if (auto kd = entry.optional("kd")) material.kd = reflectance(*kd);
        material.ks = reflectance(entry.required("ks"));
        material.exponent = positive(entry.required("exponent"), "exponent");
      } else if (type_name == "ggx") {
        // diffuse/pi plus a GGX microfacet lobe; `diffuse` defaults to black.
        material.type = MaterialType::Ggx;
        entry.collect_unknown_keys({"type", "diffuse", "specular", "roughness"}, scene().warnings);
        if (auto diffuse = entry.optional("diffuse")) material.diffuse = reflectance(*diffuse);
        material.specular = reflectance(entry.required("specular"));
        JsonNode roughness = entry.required("roughness");
        material.roughness = roughness.number();
        if (!(material.roughness > 0 && material.roughness <= 1))
          roughness.fail("roughness (GGX alpha) must lie in (0, 1], got " +
                         roughness.quoted_value());
      } else {
        type.fail("unknown material type '" + type_name + "' (expected lambert, phong or ggx)");
      }
      material_index_[name] = static_cast<uint32_t>(scene().materials.size());
      scene().materials.push_back(std::move(material));
    }
  }

  uint32_t material_reference(const JsonNode& node) const {
    std::string name = node.string();
    auto found = material_index_.find(name);
    if (found == material_index_.end())
      node.fail("unknown material '" + name + "' (not defined in $.materials)");
    return found->second;
  }

  void check_triangle_budget(const JsonNode& shape, size_t more_triangles) const {
    size_t have = scene().triangle_count();
    if (more_triangles > limits_.max_triangles || have > limits_.max_triangles - more_triangles)
      shape.fail("too many triangles: this shape adds " + std::to_string(more_triangles) + " to " +
                 std::to_string(have) +
                 ", past the limit max_triangles = " + std::to_string(limits_.max_triangles));
  }

  // Appends a mesh to the scene's flat arrays (append_mesh_to_scene: zero-area triangles
  // dropped with a warning).
  void append_mesh(const TriangleMesh& mesh, uint32_t material, const JsonNode& shape) {
    size_t dropped = 0;
    try {
      dropped = append_mesh_to_scene(scene(), mesh, material, limits_);
    } catch (const std::invalid_argument& error) {
      shape.fail(error.what());
    }
    if (dropped > 0)
      scene().warnings.push_back(shape.path() + ": dropped " + std::to_string(dropped) +
                                 " zero-area triangle(s)");
  }

  void parse_shapes(const JsonNode& node) {
    for (size_t i = 0; i < node.size(); ++i) parse_shape(node.at(i));
  }

  void parse_shape(const JsonNode& node) {
    node.expect_object();
    JsonNode type = node.required("type");
    std::string type_name = type.string();
    if (type_name == "quad") {
      node.collect_unknown_keys({"type", "origin", "edge1", "edge2", "material"}, scene().warnings);
      Vec3 origin = coordinate(node.required("origin"));
      Vec3 edge1 = coordinate(node.required("edge1"));
      Vec3 edge2 = coordinate(node.required("edge2"));
      if (!(length(cross(edge1, edge2)) > kDegenerateSine * length(edge1) * length(edge2)))
        node.fail("degenerate quad: edge1 and edge2 are zero or parallel (zero area)");
      append_mesh(quad_mesh(origin, edge1, edge2), material_reference(node.required("material")),
                  node);
    } else if (type_name == "box") {
      node.collect_unknown_keys({"type", "min", "max", "material"}, scene().warnings);
      Vec3 min = coordinate(node.required("min"));
      Vec3 max = coordinate(node.required("max"));
      for (int axis = 0; axis < 3; ++axis)
        if (!(min[axis] < max[axis]))
          node.required("max").fail("box max must exceed min on every axis (axis " +
                                    std::to_string(axis) + ": min " + number_text(min[axis]) +
                                    ", max " + number_text(max[axis]) + "): empty box");
      append_mesh(box_mesh(min, max), material_reference(node.required("material")), node);
    } else if (type_name == "sphere") {
      node.collect_unknown_keys({"type", "center", "radius", "subdivisions", "material"},
                                scene().warnings);
      Vec3 center = coordinate(node.required("center"));
      JsonNode radius_node = node.required("radius");
      double radius = positive(radius_node, "radius");
      if (radius > limits_.max_coordinate)
        radius_node.fail("radius exceeds the limit max_coordinate = " +
                         number_text(limits_.max_coordinate));
      int subdivisions = 3;
      if (auto node_subdivisions = node.optional("subdivisions")) {
        int64_t s = node_subdivisions->integer();
        if (s < 0)
          node_subdivisions->fail("subdivisions must be >= 0, got " +
                                  node_subdivisions->quoted_value());
        if (s > limits_.max_sphere_subdivisions)
          node_subdivisions->fail("subdivisions " + node_subdivisions->quoted_value() +
                                  " exceeds the limit max_sphere_subdivisions = " +
                                  std::to_string(limits_.max_sphere_subdivisions));
        subdivisions = static_cast<int>(s);
      }
      check_triangle_budget(node, icosphere_triangle_count(subdivisions));
      uint32_t material = material_reference(node.required("material"));
      append_mesh(icosphere_mesh(center, radius, subdivisions), material, node);
    } else if (type_name == "triangles") {
      node.collect_unknown_keys({"type", "positions", "indices", "material"}, scene().warnings);
      JsonNode positions = node.required("positions");
      JsonNode indices = node.required("indices");
      size_t index_count = indices.size();
      if (index_count == 0 || index_count % 3 != 0)
        indices.fail("indices must hold 3 per triangle and at least one triangle, got " +
                     std::to_string(index_count));
      check_triangle_budget(node, index_count / 3);
      TriangleMesh mesh;
      const size_t vertex_count = positions.size();
      if (vertex_count > std::numeric_limits<uint32_t>::max())
        positions.fail("too many positions for 32-bit indices");
      // Inline meshes can be large: take valid entries straight from the JSON and build a
      // JsonNode (with its path) only to report a bad one.
      mesh.positions.reserve(vertex_count);
      for (size_t v = 0; v < vertex_count; ++v) {
        std::optional<Vec3> p = plain_coordinate(positions.value()[v]);
        mesh.positions.push_back(p ? *p : coordinate(positions.at(v)));
      }
      mesh.indices.reserve(index_count);
      for (size_t k = 0; k < index_count; ++k) {
        const nlohmann::json& raw = indices.value()[k];
        if (raw.is_number_unsigned() && raw.get<uint64_t>() < vertex_count) {
          mesh.indices.push_back(static_cast<uint32_t>(raw.get<uint64_t>()));
          continue;
        }
        JsonNode index = indices.at(k);
        int64_t value = index.integer();
        if (value < 0 || static_cast<uint64_t>(value) >= vertex_count)
          index.fail("index " + index.quoted_value() + " out of range [0, " +
                     std::to_string(vertex_count) + ")");
        mesh.indices.push_back(static_cast<uint32_t>(value));
      }
      append_mesh(mesh, material_reference(node.required("material")), node);
    } else if (type_name == "obj") {
      node.collect_unknown_keys({"type", "file", "scale", "translate", "material"},
                                scene().warnings);
      Vec3 scale{1, 1, 1};
      if (auto scale_node = node.optional("scale")) {
        if (scale_node->value().is_array())
          scale = scale_node->vec3();
        else
          scale = Vec3(1, 1, 1) * scale_node->number();
        if (!(scale.x > 0 && scale.y > 0 && scale.z > 0))
          scale_node->fail("scale must be positive, got " + scale_node->quoted_value());
      }
      Vec3 translate;
      if (auto translate_node = node.optional("translate")) translate = coordinate(*translate_node);
      uint32_t material = material_reference(node.required("material"));
      JsonNode file = node.required("file");
      const std::string& bytes = obj_bytes(file);
      TriangleMesh mesh;
      try {
        mesh = obj_mesh(bytes, scale, translate);
      } catch (const std::invalid_argument& error) {
        file.fail("OBJ file '" + file.string() + "' cannot be used: " + error.what());
      }
      append_mesh(mesh, material, node);
    } else {
      type.fail("unknown shape type '" + type_name +
                "' (expected quad, box, sphere, triangles or obj)");
    }
  }

  // The bytes of the OBJ file named at `file`, read once per distinct path and recorded for the
  // content hash in order of first appearance.
  const std::string& obj_bytes(const JsonNode& file) {
    std::string relative;
    try {
      relative = normalize_scene_relative_path(file.string());
    } catch (const std::invalid_argument& error) {
      file.fail(std::string("refused OBJ path: ") + error.what());
    }
    for (const auto& [path, bytes] : result_.obj_files)
      if (path == relative) return bytes;
    std::string bytes;
    try {
      bytes = read_obj_(relative);
    } catch (const std::invalid_argument& error) {
      file.fail(std::string("OBJ file cannot be read: ") + error.what());
    }
    if (bytes.size() > limits_.max_file_bytes)
      file.fail("OBJ file '" + relative +
                "' exceeds the limit max_file_bytes = " + std::to_string(limits_.max_file_bytes));
    result_.obj_files.emplace_back(relative, std::move(bytes));
    return result_.obj_files.back().second;
  }

  void parse_lights(const JsonNode& node) {
    size_t count = node.size();
    if (count == 0) node.fail("a scene needs at least one light");
    if (count > limits_.max_lights)
      node.fail("too many lights: " + std::to_string(count) +
                " exceeds the limit max_lights = " + std::to_string(limits_.max_lights));
    for (size_t i = 0; i < count; ++i) scene().lights.push_back(parse_light(node.at(i)));
  }

  Light parse_light(const JsonNode& node) {
    node.expect_object();
    Light light;
    JsonNode type = node.required("type");
    std::string type_name = type.string();
    if (type_name == "quad") {
      node.collect_unknown_keys({"type", "origin", "edge1", "edge2", "radiance", "profile"},
                                scene().warnings);
      light.type = LightType::Quad;
      light.origin = coordinate(node.required("origin"));
      light.edge1 = coordinate(node.required("edge1"));
      light.edge2 = coordinate(node.required("edge2"));
    } else if (type_name == "polygon") {
      node.collect_unknown_keys({"type", "vertices", "radiance", "profile"}, scene().warnings);
      light.type = LightType::Polygon;
      JsonNode vertices = node.required("vertices");
      size_t count = vertices.size();
      if (count < 3)
        vertices.fail("a polygon needs at least 3 vertices, got " + std::to_string(count));
      if (count > limits_.max_polygon_vertices)
        vertices.fail("polygon has " + std::to_string(count) +
                      " vertices, more than the limit max_polygon_vertices = " +
                      std::to_string(limits_.max_polygon_vertices));
      for (size_t v = 0; v < count; ++v) light.vertices.push_back(coordinate(vertices.at(v)));
    } else if (type_name == "disk") {
      node.collect_unknown_keys({"type", "center", "normal", "radius", "radiance", "profile"},
                                scene().warnings);
      light.type = LightType::Disk;
      light.center = coordinate(node.required("center"));
      light.normal = node.required("normal").vec3();
      JsonNode radius = node.required("radius");
      light.radius = positive(radius, "radius");
      if (light.radius > limits_.max_coordinate)
        radius.fail("radius exceeds the limit max_coordinate = " +
                    number_text(limits_.max_coordinate));
      if (!(length(light.normal) > 0)) node.required("normal").fail("disk normal is zero");
    } else {
      type.fail("unknown light type '" + type_name + "' (expected quad, polygon or disk)");
    }
    light.radiance = radiance(node.required("radiance"));
    if (auto profile = node.optional("profile")) parse_profile(*profile, light);
    try {
      derive_light_geometry(light);
    } catch (const std::invalid_argument& error) {
      node.fail(std::string("degenerate ") + type_name + " light: " + error.what());
    }
    return light;
  }

  void parse_profile(const JsonNode& node, Light& light) {
    node.expect_object();
    node.collect_unknown_keys({"type", "sigma"}, scene().warnings);
    JsonNode type = node.required("type");
    std::string type_name = type.string();
    if (type_name == "constant") {
      light.profile = ProfileType::Constant;
    } else if (type_name == "gaussian") {
      if (light.type == LightType::Polygon)
        type.fail("a gaussian profile is defined for quad and disk lights only");
      light.profile = ProfileType::Gaussian;
      light.sigma = positive(node.required("sigma"), "sigma");
    } else {
      type.fail("unknown profile type '" + type_name + "' (expected constant or gaussian)");
    }
  }

  void parse_regions(const JsonNode& node) {
    node.expect_object();
    const Camera& camera = scene().camera;
    for (const std::string& name : node.keys()) {
      JsonNode entry = node.member(name);
      if (!entry.value().is_array() || entry.value().size() != 4)
        entry.fail("a region is [x0, y0, x1, y1], got " + entry.quoted_value());
      int64_t c[4];
      for (size_t k = 0; k < 4; ++k) c[k] = entry.at(k).integer();
      if (c[0] >= c[2] || c[1] >= c[3])
        entry.fail("empty region " + entry.quoted_value() + " (needs x0 < x1 and y0 < y1)");
      if (c[0] < 0 || c[1] < 0 || c[2] > camera.width || c[3] > camera.height)
        entry.fail("region " + entry.quoted_value() + " lies outside the image (" +
                   std::to_string(camera.width) + "x" + std::to_string(camera.height) + ")");
      scene().regions[name] = Region{static_cast<int>(c[0]), static_cast<int>(c[1]),
                                     static_cast<int>(c[2]), static_cast<int>(c[3])};
    }
  }

  const ObjFileReader& read_obj_;
  const std::string& source_;
  const SceneLimits& limits_;
  ParsedScene result_;
  std::map<std::string, uint32_t> material_index_;
};

}  // namespace

ParsedScene parse_scene_with_reader(const std::string& json_text, const ObjFileReader& read_obj,
                                    const std::string& source, const SceneLimits& limits) {
  // A pbrt-v3 file by its extension, or by its content when the name says neither.
  std::string extension = std::filesystem::path(source).extension().string();
  if (extension == ".pbrt" || (extension != ".json" && looks_like_pbrt(json_text)))
    return parse_pbrt_scene(json_text, read_obj, source, limits);
  return SceneParser(read_obj, source, limits).parse(json_text);
}

}  // namespace penumbra
