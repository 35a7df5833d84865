#include "core/scene/pbrt_scene_builder.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/math/transform.h"
#include "core/scene/light_setup.h"
#include "core/scene/pbrt_integrator.h"
#include "core/scene/pbrt_materials.h"
#include "core/scene/pbrt_params.h"
#include "core/scene/pbrt_parser.h"
#include "core/scene/ply_mesh.h"
#include "core/scene/scene_package.h"
#include "core/scene/scene_path.h"
#include "core/scene/shape_mesh.h"

namespace penumbra {

bool looks_like_pbrt(const std::string& text) {
  size_t i = 0;
  while (i < text.size()) {
    char c = text[i];
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') {
      ++i;
    } else {
      return c != '{';
    }
  }
  return false;
}

namespace {

constexpr double kMaxRadiance = 1e15;  // as the JSON reader (scene_parser.cpp)

std::string number_text(double x) {
  std::ostringstream out;
  out.precision(9);
  out << x;
  return out.str();
}

// An area light as AreaLightSource states it, waiting for the shapes that carry it.
struct AreaLightState {
  Rgb radiance{1, 1, 1};
  bool two_sided = false;
  int samples = 1;
  std::string location;
};

struct GraphicsState {
  Mat4 transform = Mat4::identity();
  bool reverse_orientation = false;
  int material = -1;  // index into Scene::materials; -1: pbrt's default matte
  std::optional<AreaLightState> area_light;
  std::map<std::string, int> named_materials;
  std::map<std::string, int> float_textures, spectrum_textures;  // -> Scene::textures
};

// A shape recorded inside ObjectBegin/ObjectEnd, in the object's space (its definition's
// transform applied), flattened into the scene at each ObjectInstance.
struct InstancedMesh {
  TriangleMesh mesh;
  uint32_t material = 0;
};

class PbrtSceneBuilder {
 public:
  PbrtSceneBuilder(const ObjFileReader& read_file, const std::string& source,
                   const SceneLimits& limits)
      : read_file_(read_file), source_(source), limits_(limits) {}

  ParsedScene build(const std::string& text) {
    if (text.size() > limits_.max_json_bytes)
      throw FormatError(source_ + ":1:1", "the scene file has " + std::to_string(text.size()) +
                                              " bytes, more than the limit max_json_bytes = " +
                                              std::to_string(limits_.max_json_bytes));
    PbrtParseLimits parse_limits;
    parse_limits.max_file_bytes = limits_.max_file_bytes;
    parse_pbrt(
        text, source_, [this](const std::string& relative) { return read_file_(relative); },
        [this](const PbrtStatement& statement) { handle(statement); },
        [this](const std::string& relative, const std::string& bytes) {
          result_.obj_files.emplace_back(relative, bytes);
        },
        parse_limits);
    if (!world_ended_)
      throw FormatError(source_,
                        "the file ends before WorldEnd (a pbrt-v3 scene is rendered at "
                        "its WorldEnd)");
    std::filesystem::path path(source_);
    scene().name = path.stem().string();
    scene().content_hash = scene_content_hash(text, result_.obj_files);
    return std::move(result_);
  }

 private:
  Scene& scene() { return result_.scene; }

  void warn(const PbrtLocation& where, const std::string& note) {
    scene().warnings.push_back(where.str() + ": " + note);
  }

  void handle(const PbrtStatement& statement) {
    const std::string& name = statement.name;
    if (world_ended_)
      pbrt_fail(statement.location, name + " after WorldEnd (Penumbra reads one scene per file)");
    // Statements of the options block (before WorldBegin) and of the world block.
    static const char* const kOptions[] = {
        "Camera", "Film", "Sampler", "PixelFilter", "Integrator", "Accelerator", "TransformTimes"};
    static const char* const kWorld[] = {
        "AttributeBegin",     "AttributeEnd",    "Shape",          "Material",
        "MakeNamedMaterial",  "NamedMaterial",   "Texture",        "AreaLightSource",
        "LightSource",        "ObjectBegin",     "ObjectEnd",      "ObjectInstance",
        "ReverseOrientation", "MakeNamedMedium", "MediumInterface"};
    for (const char* option : kOptions)
      if (name == option && in_world_)
        pbrt_fail(statement.location, name +
                                          " inside the world block (it belongs before "
                                          "WorldBegin)");
    for (const char* world : kWorld)
      if (name == world && !in_world_ && name != "MakeNamedMedium" && name != "MediumInterface")
        pbrt_fail(statement.location, name + " before WorldBegin (it belongs in the world block)");

    if (handle_transform(statement)) return;
    if (name == "WorldBegin") return world_begin(statement);
    if (name == "WorldEnd") return world_end(statement);
    if (name == "AttributeBegin") {
      attribute_stack_.push_back({state_, statement.location.str(), true});
      return;
    }
    if (name == "TransformBegin") {
      GraphicsState saved = state_;
      attribute_stack_.push_back({saved, statement.location.str(), false});
      return;
    }
    if (name == "AttributeEnd" || name == "TransformEnd") return pop_state(statement);
    if (name == "ReverseOrientation") {
      state_.reverse_orientation = !state_.reverse_orientation;
      return;
    }
    if (name == "Camera") return camera_statement(statement);
    if (name == "Film" || name == "Sampler" || name == "PixelFilter" || name == "Integrator") {
      options_[name] = statement;
      return;
    }
    if (name == "Accelerator") {
      warn(statement.location,
           "Accelerator ignored (Penumbra traces with Embree's BVH; the "
           "image does not depend on it)");
      return;
    }
    if (name == "TransformTimes") {
      warn(statement.location, "TransformTimes ignored (no motion: every transform is static)");
      return;
    }
    if (name == "MakeNamedMedium")
      pbrt_fail(statement.location,
                "participating media are not modelled (Penumbra renders "
                "direct illumination between surfaces in vacuum)");
    if (name == "MediumInterface") {
      for (const PbrtToken& argument : statement.arguments)
        if (!argument.text.empty())
          pbrt_fail(argument.location,
                    "participating media are not modelled (medium '" + argument.text + "')");
      return;
    }
    if (name == "Material") return material_statement(statement);
    if (name == "MakeNamedMaterial") return named_material_statement(statement);
    if (name == "NamedMaterial") {
      const PbrtToken& material = statement.arguments[0];
      auto found = state_.named_materials.find(material.text);
      if (found == state_.named_materials.end())
        pbrt_fail(material.location, "NamedMaterial \"" + material.text +
                                         "\" is not defined (no MakeNamedMaterial of that name "
                                         "in scope)");
      state_.material = found->second;
      return;
    }
    if (name == "Texture") return texture_statement(statement);
    if (name == "AreaLightSource") return area_light_statement(statement);
    if (name == "LightSource") {
      pbrt_fail(statement.location, "LightSource \"" + statement.arguments[0].text +
                                        "\" is not modelled: Penumbra renders area lights "
                                        "(AreaLightSource \"diffuse\") only");
    }
    if (name == "Shape") return shape_statement(statement);
    if (name == "ObjectBegin") {
      if (current_object_)
        pbrt_fail(statement.location, "ObjectBegin inside the definition of object '" +
                                          *current_object_ + "' (objects do not nest)");
      const std::string& object = statement.arguments[0].text;
      if (objects_.count(object))
        warn(statement.location, "object '" + object + "' redefined (the new definition wins)");
      objects_[object].clear();
      current_object_ = object;
      attribute_stack_.push_back({state_, statement.location.str(), true});
      return;
    }
    if (name == "ObjectEnd") {
      if (!current_object_) pbrt_fail(statement.location, "ObjectEnd without ObjectBegin");
      current_object_.reset();
      pop_state(statement);
      return;
    }
    if (name == "ObjectInstance") return object_instance(statement);
    pbrt_fail(statement.location, "statement " + name + " is not handled");
  }

  // ---- Transforms ---------------------------------------------------------------------

  static Vec3 vec_of(const std::vector<PbrtToken>& arguments, size_t first) {
    return {arguments[first].number, arguments[first + 1].number, arguments[first + 2].number};
  }

  void apply(const PbrtStatement& statement, const Mat4& t) {
    Mat4 product = state_.transform * t;
    if (!product.is_finite())
      pbrt_fail(statement.location, statement.name + " makes the transform non-finite");
    state_.transform = product;
  }

  static Mat4 matrix_of(const std::vector<PbrtToken>& arguments) {
    // pbrt-v3 reads the 16 numbers column by column.
    Mat4 t;
    for (int column = 0; column < 4; ++column)
      for (int row = 0; row < 4; ++row) t.m[row][column] = arguments[column * 4 + row].number;
    return t;
  }

  bool handle_transform(const PbrtStatement& statement) {
    const std::string& name = statement.name;
    const auto& a = statement.arguments;
    if (name == "Identity") {
      state_.transform = Mat4::identity();
    } else if (name == "Translate") {
      apply(statement, Mat4::translate(vec_of(a, 0)));
    } else if (name == "Scale") {
      apply(statement, Mat4::scale(vec_of(a, 0)));
    } else if (name == "Rotate") {
      Vec3 axis = vec_of(a, 1);
      if (!(length(axis) > 0)) pbrt_fail(a[1].location, "Rotate about a zero axis");
      apply(statement, Mat4::rotate(a[0].number, axis));
    } else if (name == "LookAt") {
      apply(statement, look_at(statement));
    } else if (name == "Transform") {
      state_.transform = matrix_of(a);
    } else if (name == "ConcatTransform") {
      apply(statement, matrix_of(a));
    } else if (name == "CoordinateSystem") {
      named_systems_[a[0].text] = state_.transform;
    } else if (name == "CoordSysTransform") {
      auto found = named_systems_.find(a[0].text);
      if (found == named_systems_.end())
        pbrt_fail(a[0].location, "coordinate system \"" + a[0].text +
                                     "\" is not defined (CoordinateSystem, or \"camera\" after "
                                     "Camera, \"world\" after WorldBegin)");
      state_.transform = found->second;
    } else if (name == "ActiveTransform") {
      if (a[0].text != "All")
        pbrt_fail(a[0].location, "ActiveTransform " + a[0].text +
                                     " is not modelled (animated transforms: Penumbra renders "
                                     "a static scene)");
    } else {
      return false;
    }
    return true;
  }

  // pbrt-v3's LookAt: the world-to-camera transform of a camera at `eye` looking at `look`.
  static Mat4 look_at(const PbrtStatement& statement) {
    const auto& a = statement.arguments;
    Vec3 eye = vec_of(a, 0), look = vec_of(a, 3), up = vec_of(a, 6);
    Vec3 dir = look - eye;
    if (!(length(dir) > 0)) pbrt_fail(statement.location, "LookAt: eye and look-at point coincide");
    dir = normalize(dir);
    if (!(length(up) > 0) || !(length(cross(normalize(up), dir)) > 1e-9))
      pbrt_fail(a[6].location, "LookAt: the up vector is zero or parallel to the view direction");
    Vec3 right = normalize(cross(normalize(up), dir));
    Vec3 new_up = cross(dir, right);
    Mat4 camera_to_world = Mat4::identity();
    for (int row = 0; row < 3; ++row) {
      camera_to_world.m[row][0] = right[row];
      camera_to_world.m[row][1] = new_up[row];
      camera_to_world.m[row][2] = dir[row];
      camera_to_world.m[row][3] = eye[row];
    }
    std::optional<Mat4> world_to_camera = camera_to_world.inverse();
    if (!world_to_camera) pbrt_fail(statement.location, "LookAt gives a singular transform");
    return *world_to_camera;
  }

  struct SavedState {
    GraphicsState state;
    std::string location;
    bool attributes = true;  // AttributeBegin (all state) or TransformBegin (transform only)
  };

  void pop_state(const PbrtStatement& statement) {
    bool attributes = statement.name != "TransformEnd";
    if (attribute_stack_.empty())
      pbrt_fail(statement.location, statement.name + " without a matching " +
                                        (attributes ? "AttributeBegin" : "TransformBegin"));
    SavedState saved = std::move(attribute_stack_.back());
    attribute_stack_.pop_back();
    if (saved.attributes != attributes && statement.name != "ObjectEnd")
      pbrt_fail(statement.location, statement.name + " closes the " +
                                        (saved.attributes ? "AttributeBegin" : "TransformBegin") +
                                        " at " + saved.location);
    if (attributes)
      state_ = std::move(saved.state);
    else
      state_.transform = saved.state.transform;
  }

  // ---- Options block ------------------------------------------------------------------

  void camera_statement(const PbrtStatement& statement) {
    if (camera_statement_) warn(statement.location, "a second Camera replaces the one before");
    camera_statement_ = statement;
    camera_world_to_camera_ = state_.transform;
    std::optional<Mat4> camera_to_world = state_.transform.inverse();
    if (!camera_to_world)
      pbrt_fail(statement.location, "the camera transform is singular (not invertible)");
    named_systems_["camera"] = *camera_to_world;
  }

  void world_begin(const PbrtStatement& statement) {
    if (in_world_) pbrt_fail(statement.location, "WorldBegin inside the world block");
    resolve_camera(statement);
    in_world_ = true;
    state_.transform = Mat4::identity();
    named_systems_["world"] = Mat4::identity();
  }

  void resolve_camera(const PbrtStatement& world_begin) {
    Camera& camera = scene().camera;
    // Film.
    int full_width = 640, full_height = 480;
    double crop[4] = {0, 1, 0, 1};
    if (auto film = options_.find("Film"); film != options_.end()) {
      PbrtParams params(film->second);
      const std::string& type = film->second.arguments[0].text;
      if (type != "image" && type != "rgb")
        params.fail("film type \"" + type + "\" is not modelled (expected \"image\")");
      full_width = resolution(params, "xresolution", 640);
      full_height = resolution(params, "yresolution", 480);
      if (const std::vector<double>* window = params.numbers("cropwindow", {"float"}, 4)) {
        if (window->size() != 4) params.fail(*params.find("cropwindow"), "expected 4 numbers");
        for (int i = 0; i < 4; ++i) crop[i] = std::clamp((*window)[i], 0.0, 1.0);
        if (!(crop[0] < crop[1] && crop[2] < crop[3]))
          params.fail(*params.find("cropwindow"), "empty crop window");
      }
      if (params.has("filename")) {
        params.ignore("filename");
        scene().warnings.push_back(params.find("filename")->location.str() +
                                   ": Film filename ignored (the output is named by -o)");
      }
      double scale = params.number("scale", 1);
      if (scale != 1)
        params.fail(*params.find("scale"), "a film scale other than 1 is not modelled");
      if (params.has("maxsampleluminance"))
        params.fail(*params.find("maxsampleluminance"),
                    "sample clamping is not modelled (it biases the image)");
      params.ignore("diagonal");
      params.report_unused(scene().warnings);
    }
    // pbrt-v3's cropped pixel bounds.
    int x0 = static_cast<int>(std::ceil(full_width * crop[0]));
    int x1 = static_cast<int>(std::ceil(full_width * crop[1]));
    int y0 = static_cast<int>(std::ceil(full_height * crop[2]));
    int y1 = static_cast<int>(std::ceil(full_height * crop[3]));
    if (x1 <= x0 || y1 <= y0)
      pbrt_fail(world_begin.location, "the film's crop window holds no pixel");
    camera.width = x1 - x0;
    camera.height = y1 - y0;
    if (x0 != 0 || y0 != 0 || x1 != full_width || y1 != full_height) {
      camera.crop_x = x0;
      camera.crop_y = y0;
      camera.full_width = full_width;
      camera.full_height = full_height;
    }

    // Camera.
    double fov = 90;
    double frame = double(full_width) / full_height;
    camera.screen_x0 = frame > 1 ? -frame : -1;
    camera.screen_x1 = frame > 1 ? frame : 1;
    camera.screen_y0 = frame > 1 ? -1 : -1 / frame;
    camera.screen_y1 = frame > 1 ? 1 : 1 / frame;
    bool explicit_window = false;
    Mat4 world_to_camera = Mat4::identity();
    if (camera_statement_) {
      PbrtParams params(*camera_statement_);
      const std::string& type = camera_statement_->arguments[0].text;
      if (type != "perspective")
        params.fail("camera \"" + type +
                    "\" is not modelled (Penumbra has the perspective "
                    "camera)");
      world_to_camera = camera_world_to_camera_;
      fov = params.number("fov", 90);
      if (params.has("halffov")) fov = 2 * params.number("halffov", 45);
      if (!(fov > 0 && fov < 180)) params.fail(*params.find("fov"), "fov must lie in (0, 180)");
      if (params.has("frameaspectratio")) {
        frame = params.number("frameaspectratio", frame);
        if (!(frame > 0))
          params.fail(*params.find("frameaspectratio"), "frameaspectratio must be positive");
        camera.screen_x0 = frame > 1 ? -frame : -1;
        camera.screen_x1 = frame > 1 ? frame : 1;
        camera.screen_y0 = frame > 1 ? -1 : -1 / frame;
        camera.screen_y1 = frame > 1 ? 1 : 1 / frame;
        explicit_window = true;
      }
      if (const std::vector<double>* window = params.numbers("screenwindow", {"float"}, 4)) {
        if (window->size() != 4) params.fail(*params.find("screenwindow"), "expected 4 numbers");
        camera.screen_x0 = (*window)[0];
        camera.screen_x1 = (*window)[1];
        camera.screen_y0 = (*window)[2];
        camera.screen_y1 = (*window)[3];
        if (!(camera.screen_x0 < camera.screen_x1 && camera.screen_y0 < camera.screen_y1))
          params.fail(*params.find("screenwindow"), "empty screen window");
        explicit_window = true;
      }
      double lens_radius = params.number("lensradius", 0);
      if (lens_radius != 0)
        params.fail(*params.find("lensradius"), "depth of field (a lens radius) is not modelled");
      params.ignore("focaldistance");
      params.ignore("shutteropen");
      params.ignore("shutterclose");
      params.report_unused(scene().warnings);
    }
    camera.fov_y_deg = fov;
    // The default window of a landscape frame is the JSON camera's own; anything else is given
    // explicitly.
    camera.has_screen_window = explicit_window || frame < 1;

    std::optional<Mat4> camera_to_world = world_to_camera.inverse();
    PbrtLocation where = camera_statement_ ? camera_statement_->location : world_begin.location;
    if (!camera_to_world || !camera_to_world->is_affine())
      pbrt_fail(where, "the camera transform is not an invertible affine transform");
    Vec3 right = camera_to_world->vector({1, 0, 0});
    Vec3 up = camera_to_world->vector({0, 1, 0});
    Vec3 forward = camera_to_world->vector({0, 0, 1});
    double scale = length(forward);
    auto close = [scale](double a, double b) { return std::abs(a - b) <= 1e-6 * scale; };
    if (!close(length(right), scale) || !close(length(up), scale) ||
        std::abs(dot(right, up)) > 1e-6 * scale * scale ||
        std::abs(dot(right, forward)) > 1e-6 * scale * scale ||
        std::abs(dot(up, forward)) > 1e-6 * scale * scale)
      pbrt_fail(where, "the camera transform shears or scales unevenly (not modelled)");
    camera.position = camera_to_world->point({0, 0, 0});
    Vec3 view = normalize(forward);
    camera.look_at = camera.position + view;
    camera.up = normalize(up);
    camera.mirror_x = dot(right, cross(view, camera.up)) < 0;

    // Pixel filter.
    if (auto filter = options_.find("PixelFilter"); filter != options_.end()) {
      PbrtParams params(filter->second);
      const std::string& type = filter->second.arguments[0].text;
      PixelFilter& f = camera.filter;
      if (type == "box") {
        f.type = PixelFilterType::Box;
        f.radius_x = params.number("xwidth", 0.5);
        f.radius_y = params.number("ywidth", 0.5);
      } else if (type == "triangle") {
        f.type = PixelFilterType::Triangle;
        f.radius_x = params.number("xwidth", 2);
        f.radius_y = params.number("ywidth", 2);
      } else if (type == "gaussian") {
        f.type = PixelFilterType::Gaussian;
        f.radius_x = params.number("xwidth", 2);
        f.radius_y = params.number("ywidth", 2);
        f.alpha = params.number("alpha", 2);
        if (!(f.alpha > 0 && f.alpha < 1e6))
          params.fail(*params.find("alpha"), "alpha must lie in (0, 1e6)");
      } else {
        params.fail("pixel filter \"" + type +
                    "\" is not modelled (box, triangle and gaussian "
                    "are; mitchell and sinc have negative lobes)");
      }
      for (double radius : {f.radius_x, f.radius_y})
        if (!(radius > 0 && radius <= 16))
          params.fail("filter widths (radii) must lie in (0, 16] pixels");
      params.report_unused(scene().warnings);
    }

    // Sampler.
    if (auto sampler = options_.find("Sampler"); sampler != options_.end()) {
      PbrtParams params(sampler->second);
      const std::string& type = sampler->second.arguments[0].text;
      SceneRenderDefaults& defaults = scene().render_defaults;
      int64_t spp = 0;
      std::string approximated;
      if (type == "stratified") {
        int64_t xs = params.integer("xsamples", 4), ys = params.integer("ysamples", 4);
        if (xs < 1 || ys < 1) params.fail("xsamples and ysamples must be at least 1");
        spp = xs * ys;
        defaults.sampler = params.boolean("jitter", true) ? "stratified" : "uniform";
      } else {
        int64_t fallback = type == "random" ? 4 : 16;
        spp = params.integer("pixelsamples", fallback);
        if (type == "random") {
          defaults.sampler = "random";
        } else if (type == "halton") {
          defaults.sampler = "halton";
        } else if (type == "sobol") {
          defaults.sampler = "sobol";
        } else if (type == "02sequence" || type == "lowdiscrepancy") {
          defaults.sampler = "sobol";
          approximated = "sobol";
        } else if (type == "maxmindist") {
          defaults.sampler = "stratified";
          approximated = "stratified";
        } else {
          params.fail("sampler \"" + type + "\" is not modelled");
        }
      }
      if (spp < 1 || spp > (int64_t(1) << 20))
        params.fail("the sample count per pixel must lie in [1, 2^20]");
      defaults.spp = static_cast<uint32_t>(spp);
      if (!approximated.empty())
        warn(sampler->second.location, "sampler \"" + type + "\" approximated by Penumbra's \"" +
                                           approximated + "\" pattern");
      params.report_unused(scene().warnings);
    }
    if (!options_.count("Sampler")) {  // pbrt-v3's default sampler
      scene().render_defaults.sampler = "halton";
      scene().render_defaults.spp = 16;
    }
    // pbrt-v3 scales the camera ray differentials by 1 / sqrt(samples per pixel).
    scene().texture_footprint_scale =
        1 / std::sqrt(std::max(1.0, double(scene().render_defaults.spp)));
  }

  int resolution(PbrtParams& params, const std::string& name, int fallback) {
    int64_t value = params.integer(name, fallback);
    if (value < 1 || value > limits_.max_resolution)
      params.fail(*params.find(name), "resolution must lie in [1, " +
                                          std::to_string(limits_.max_resolution) +
                                          "] (max_resolution)");
    return static_cast<int>(value);
  }

  void world_end(const PbrtStatement& statement) {
    if (!in_world_) pbrt_fail(statement.location, "WorldEnd without WorldBegin");
    if (current_object_)
      pbrt_fail(statement.location, "WorldEnd inside the definition of object '" +
                                        *current_object_ + "' (missing ObjectEnd)");
    if (!attribute_stack_.empty())
      warn(statement.location, std::to_string(attribute_stack_.size()) +
                                   " AttributeBegin/TransformBegin left open at WorldEnd (closed "
                                   "here)");
    if (scene().lights.empty())
      pbrt_fail(statement.location,
                "the scene has no area light (Penumbra renders direct light "
                "from AreaLightSource \"diffuse\" shapes)");
    if (scene().lights.size() > limits_.max_lights)
      pbrt_fail(statement.location,
                "too many lights: " + std::to_string(scene().lights.size()) +
                    " exceeds the limit max_lights = " + std::to_string(limits_.max_lights));
    // The integrator's settings need the lights' sample counts.
    int light_samples = light_samples_.empty() ? 1 : light_samples_.front();
    for (size_t i = 1; i < light_samples_.size(); ++i)
      if (light_samples_[i] != light_samples) {
        warn(statement.location,
             "area lights ask for different sample counts; Penumbra's method takes one count "
             "for every light: the first light's (" +
                 std::to_string(light_samples) + ")");
        break;
      }
    if (auto integrator = options_.find("Integrator"); integrator != options_.end()) {
      PbrtParams params(integrator->second);
      map_pbrt_integrator(params, light_samples, scene().render_defaults, scene().max_depth,
                          scene().warnings);
      params.report_unused(scene().warnings);
    } else {
      // pbrt-v3's default integrator is the path tracer.
      scene().render_defaults.method =
          (light_samples == 1 ? std::string() : std::to_string(light_samples) + "*") + "area+" +
          (light_samples == 1 ? std::string() : std::to_string(light_samples) + "*") + "bsdf/power";
      scene().max_depth = 5;
      warn(statement.location,
           "no Integrator: pbrt-v3's default path tracer is rendered as "
           "direct illumination (indirect light omitted) with " +
               scene().render_defaults.method);
    }
    if (scene().lights.size() > 1)
      warn(statement.location,
           "area-light shapes do not occlude in Penumbra (pbrt-v3's do): one "
           "light's shape never shadows another's light");
    world_ended_ = true;
  }

  // ---- Materials and textures -------------------------------------------------------------

  PbrtTextureScope texture_scope() const {
    auto lookup = [](const std::map<std::string, int>& names) {
      return [&names](const std::string& name) {
        auto found = names.find(name);
        return found == names.end() ? -1 : found->second;
      };
    };
    return {lookup(state_.float_textures), lookup(state_.spectrum_textures)};
  }

  int add_material(const std::string& name, const std::string& type, PbrtParams& params) {
    scene().materials.push_back(
        material_from_pbrt(name, type, params, texture_scope(), scene().warnings));
    return static_cast<int>(scene().materials.size() - 1);
  }

  void material_statement(const PbrtStatement& statement) {
    PbrtParams params(statement);
    const std::string& type = statement.arguments[0].text;
    // Anonymous materials are named for their type and place: "plastic@scene.pbrt:20".
    std::string file =
        std::filesystem::path(statement.location.file ? *statement.location.file : source_)
            .filename()
            .string();
    state_.material = add_material(
        type + "@" + file + ":" + std::to_string(statement.location.line), type, params);
  }

  void named_material_statement(const PbrtStatement& statement) {
    PbrtParams params(statement);
    const std::string& name = statement.arguments[0].text;
    if (!params.has("type")) params.fail("MakeNamedMaterial needs \"string type\"");
    std::string type = params.string("type", "");
    if (state_.named_materials.count(name))
      warn(statement.location, "named material '" + name + "' redefined (the new one wins)");
    state_.named_materials[name] = add_material(name, type, params);
  }

  void texture_statement(const PbrtStatement& statement) {
    PbrtParams params(statement);
    std::string value_type = statement.arguments[1].text;
    if (value_type == "color") value_type = "spectrum";
    if (value_type != "float" && value_type != "spectrum")
      pbrt_fail(statement.arguments[1].location,
                "texture type \"" + value_type + "\" (expected \"float\" or \"spectrum\")");
    // Image files travel with the scene (package and content hash); each is read once.
    auto read_image = [this](const PbrtParameter& where, const std::string& name) {
      std::string relative = scene_file(where, name, "texture");
      auto found = images_.find(relative);
      if (found != images_.end()) return found->second;
      auto bytes = std::make_shared<const std::string>(read_scene_file(where, relative, "texture"));
      images_[relative] = bytes;
      return std::shared_ptr<const std::string>(bytes);
    };
    Texture texture = texture_from_pbrt(params, texture_scope(), read_image);
    params.report_unused(scene().warnings);
    auto& names = texture.is_float ? state_.float_textures : state_.spectrum_textures;
    if (names.count(texture.name))
      warn(statement.location, "texture '" + texture.name + "' redefined (the new one wins)");
    names[texture.name] = static_cast<int>(scene().textures.size());
    scene().textures.push_back(std::move(texture));
  }

  // ---- Files ---------------------------------------------------------------------------

  std::string scene_file(const PbrtParameter& where, const std::string& name, const char* what) {
    try {
      return normalize_scene_relative_path(name);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(where.location, std::string("refused ") + what + " path: " + error.what());
    }
  }

  // The bytes of a file the scene names, read once and recorded for the content hash. The
  // reference is valid until the next file is read.
  const std::string& read_scene_file(const PbrtParameter& where, const std::string& relative,
                                     const char* what) {
    for (const auto& [path, bytes] : result_.obj_files)
      if (path == relative) return bytes;
    std::string bytes;
    try {
      bytes = read_file_(relative);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(where.location, std::string(what) + " file cannot be read: " + error.what());
    }
    if (bytes.size() > limits_.max_file_bytes)
      pbrt_fail(where.location, std::string(what) + " file '" + relative +
                                    "' exceeds the limit max_file_bytes = " +
                                    std::to_string(limits_.max_file_bytes));
    result_.obj_files.emplace_back(relative, std::move(bytes));
    return result_.obj_files.back().second;
  }

  // ---- Area lights -----------------------------------------------------------------------

  void area_light_statement(const PbrtStatement& statement) {
    PbrtParams params(statement);
    const std::string& type = statement.arguments[0].text;
    if (type != "diffuse")
      params.fail("area light \"" + type + "\" is not modelled (expected \"diffuse\")");
    AreaLightState light;
    light.location = statement.location.str();
    light.radiance = params.color("L").value_or(Rgb(1, 1, 1));
    if (std::optional<Rgb> scale = params.color("scale")) light.radiance = light.radiance * *scale;
    for (int c = 0; c < 3; ++c) {
      if (!(light.radiance[c] >= 0)) params.fail("radiance L must be finite and not negative");
      if (light.radiance[c] > kMaxRadiance)
        params.fail("radiance " + number_text(light.radiance[c]) +
                    " exceeds the limit max_radiance = " + number_text(kMaxRadiance));
    }
    light.two_sided = params.boolean("twosided", false);
    int64_t samples = params.integer("samples", params.integer("nsamples", 1));
    if (params.has("xsamples") || params.has("ysamples")) {
      int64_t xs = params.integer("xsamples", 1), ys = params.integer("ysamples", 1);
      if (xs < 1 || ys < 1) params.fail("xsamples and ysamples must be at least 1");
      samples = xs * ys;
    }
    if (samples < 1 || samples > 4096) params.fail("light samples must lie in [1, 4096]");
    light.samples = static_cast<int>(samples);
    params.report_unused(scene().warnings);
    state_.area_light = light;
  }

  // Adds a light built by light_setup.h after checking it against the scene's limits (light
  // count, coordinates), so that no light can overflow the estimators' arithmetic.
  void push_light(const Light& light, int samples, const PbrtLocation& where) {
    if (scene().lights.size() >= limits_.max_lights)
      pbrt_fail(where, "too many lights: more than the limit max_lights = " +
                           std::to_string(limits_.max_lights));
    auto check = [&](const Vec3& p) {
      for (int axis = 0; axis < 3; ++axis)
        if (!(std::abs(p[axis]) <= limits_.max_coordinate))
          pbrt_fail(where, "a light coordinate " + number_text(p[axis]) +
                               " exceeds the limit max_coordinate = " +
                               number_text(limits_.max_coordinate));
    };
    for (const Vec3& v : light.vertices) check(v);
    check(light.center);
    if (!(light.radius <= limits_.max_coordinate))
      pbrt_fail(where, "the light's radius exceeds the limit max_coordinate");
    scene().lights.push_back(light);
    light_samples_.push_back(samples);
  }

  // Adds a quad light origin + s e1 + t e2 emitting towards `normal`'s side, keeping e1 as the
  // file's first edge (Penumbra's u lines run along it).
  void add_quad_light(const Vec3& origin, const Vec3& e1, const Vec3& e2, const Vec3& normal,
                      const AreaLightState& area, const PbrtLocation& where) {
    bool along = dot(cross(e1, e2), normal) > 0;
    Vec3 o = along ? origin : origin + e2, edge2 = along ? e2 : -e2;
    for (int side = 0; side < (area.two_sided ? 2 : 1); ++side) {
      Light light;
      try {
        light = side == 0 ? make_quad_light(o, e1, edge2, area.radiance)
                          : make_quad_light(o + edge2, e1, -edge2, area.radiance);
      } catch (const std::invalid_argument& error) {
        pbrt_fail(where, std::string("degenerate quad light: ") + error.what());
      }
      push_light(light, area.samples, where);
    }
  }

  void add_polygon_light(std::vector<Vec3> vertices, const Vec3& normal, const AreaLightState& area,
                         const PbrtLocation& where) {
    if (dot(cross(vertices[1] - vertices[0], vertices[2] - vertices[0]), normal) < 0)
      std::reverse(vertices.begin(), vertices.end());
    for (int side = 0; side < (area.two_sided ? 2 : 1); ++side) {
      Light light;
      try {
        light = make_polygon_light(vertices, area.radiance);
      } catch (const std::invalid_argument& error) {
        pbrt_fail(where, std::string("degenerate polygon light: ") + error.what());
      }
      push_light(light, area.samples, where);
      std::reverse(vertices.begin(), vertices.end());
    }
  }

  bool flips_orientation() const {
    return state_.reverse_orientation != (state_.transform.determinant3() < 0);
  }

  // A world-space triangle mesh carrying the current area light: a parallelogram of two
  // triangles becomes a quad light, any other mesh one polygon light per triangle, each facing
  // pbrt-v3's emitting side (the triangle's normal, turned to the shading normals when the mesh
  // has them, else flipped by ReverseOrientation and handedness-swapping transforms).
  void mesh_lights(const TriangleMesh& mesh, const AreaLightState& area,
                   const PbrtLocation& where) {
    auto emitting_normal = [&](size_t t) {
      const Vec3& a = mesh.positions[mesh.indices[t]];
      const Vec3& b = mesh.positions[mesh.indices[t + 1]];
      const Vec3& c = mesh.positions[mesh.indices[t + 2]];
      Vec3 n = cross(b - a, c - a);
      if (!mesh.normals.empty()) {
        Vec3 shading = mesh.normals[mesh.indices[t]] + mesh.normals[mesh.indices[t + 1]] +
                       mesh.normals[mesh.indices[t + 2]];
        if (dot(n, shading) < 0) n = -n;
      } else if (flips_orientation()) {
        n = -n;
      }
      return n;
    };
    if (mesh.positions.size() == 4 && mesh.indices.size() == 6) {
      // Find the shared diagonal: the two corners in both triangles.
      const uint32_t* i = mesh.indices.data();
      std::vector<uint32_t> shared, alone;
      for (int k = 0; k < 3; ++k) {
        bool in_second = i[3] == i[k] || i[4] == i[k] || i[5] == i[k];
        (in_second ? shared : alone).push_back(i[k]);
      }
      if (shared.size() == 2 && alone.size() == 1) {
        uint32_t other = 0;
        for (int k = 3; k < 6; ++k)
          if (i[k] != shared[0] && i[k] != shared[1]) other = i[k];
        const Vec3& o = mesh.positions[alone[0]];
        Vec3 e1 = mesh.positions[shared[0]] - o, e2 = mesh.positions[shared[1]] - o;
        Vec3 far = mesh.positions[other];
        double size = std::max(length(e1), length(e2));
        if (length(o + e1 + e2 - far) <= 1e-6 * size) {
          Vec3 n0 = emitting_normal(0), n1 = emitting_normal(3);
          if (dot(n0, n1) > 0) {
            add_quad_light(o, e1, e2, n0, area, where);
            return;
          }
        }
      }
    }
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
      add_polygon_light({mesh.positions[mesh.indices[t]], mesh.positions[mesh.indices[t + 1]],
                         mesh.positions[mesh.indices[t + 2]]},
                        emitting_normal(t), area, where);
  }

  // ---- Shapes --------------------------------------------------------------------------

  uint32_t current_material() {
    if (state_.material >= 0) return static_cast<uint32_t>(state_.material);
    if (default_material_ < 0) {
      scene().materials.push_back(pbrt_default_material());
      default_material_ = static_cast<int>(scene().materials.size() - 1);
    }
    return static_cast<uint32_t>(default_material_);
  }

  TriangleMesh transformed(TriangleMesh world, const Mat4& transform, const PbrtLocation& where) {
    for (Vec3& p : world.positions) p = transform.point(p);
    if (!world.normals.empty()) {
      std::optional<Mat4> inverse = transform.inverse();
      if (!inverse) pbrt_fail(where, "the shape's transform is singular");
      for (Vec3& n : world.normals) {
        Vec3 t = Mat4::normal(*inverse, n);
        double l = length(t);
        n = l > 0 && std::isfinite(l) ? t / l : Vec3(0, 0, 0);
      }
    }
    for (const Vec3& p : world.positions)
      if (!is_finite(p)) pbrt_fail(where, "a transformed vertex is not finite");
    return world;
  }

  // Bakes pbrt-v3's orientation into the winding of a mesh without shading normals (whose
  // outside is then cross(p1 - p0, p2 - p0)): ReverseOrientation and handedness-swapping
  // transforms flip it.
  TriangleMesh oriented(TriangleMesh mesh) const {
    if (mesh.normals.empty() && flips_orientation())
      for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    return mesh;
  }

  void add_occluder(const TriangleMesh& world, uint32_t material, const PbrtLocation& where) {
    if (current_object_) {
      objects_[*current_object_].push_back({world, material});
      return;
    }
    size_t dropped = 0;
    try {
      dropped = append_mesh_to_scene(scene(), world, material, limits_);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(where, error.what());
    }
    if (dropped > 0) warn(where, "dropped " + std::to_string(dropped) + " zero-area triangle(s)");
  }

  void shape_statement(const PbrtStatement& statement) {
    PbrtParams params(statement);
    const std::string& type = statement.arguments[0].text;
    const PbrtLocation& where = statement.location;
    if (params.has("alpha") || params.has("shadowalpha")) {
      // A constant alpha of 1 is the default; anything else cuts holes.
      for (const char* name : {"alpha", "shadowalpha"}) {
        const PbrtParameter* alpha = params.find(name);
        if (alpha &&
            !(alpha->type == "float" && alpha->numbers.size() == 1 && alpha->numbers[0] == 1))
          params.fail(*alpha, "alpha masks (cut-outs) are not modelled: shapes are opaque");
      }
    }
    if (state_.area_light && current_object_)
      params.fail(
          "area lights inside an object definition are not modelled (pbrt-v3 refuses "
          "them too)");

    if (type == "quad") {
      Vec3 o = params.point3("o").value_or(Vec3(0, 0, 0));
      Vec3 u = params.vector3("u").value_or(Vec3(1, 0, 0));
      Vec3 v = params.vector3("v").value_or(Vec3(0, 0, 1));
      params.report_unused(scene().warnings);
      if (state_.area_light) {
        Vec3 ow = state_.transform.point(o), uw = state_.transform.vector(u),
             vw = state_.transform.vector(v);
        // The seed's quad emits along cross(u, v) in world space, flipped by ReverseOrientation
        // and by transforms that swap handedness.
        Vec3 normal = cross(uw, vw) * (flips_orientation() ? -1.0 : 1.0);
        add_quad_light(ow, uw, vw, normal, *state_.area_light, where);
        return;
      }
      if (!(length(cross(u, v)) > kDegenerateSine * length(u) * length(v)))
        params.fail("degenerate quad: u and v are zero or parallel");
      TriangleMesh mesh;
      mesh.positions = {o, o + u, o + u + v, o + v};
      mesh.indices = {0, 1, 2, 0, 2, 3};
      mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      add_occluder(oriented(transformed(mesh, state_.transform, where)), current_material(), where);
      return;
    }

    TriangleMesh mesh;
    if (type == "trianglemesh") {
      mesh = triangle_mesh(params);
    } else if (type == "plymesh") {
      mesh = ply_mesh(params);
    } else if (type == "sphere") {
      if (state_.area_light)
        params.fail(
            "sphere lights are not modelled (quad, triangle-mesh and "
            "disk lights are)");
      mesh = sphere(params);
    } else if (type == "disk") {
      if (state_.area_light) return disk_light(params);
      mesh = disk(params);
    } else {
      params.fail("shape \"" + type +
                  "\" is not modelled (trianglemesh, plymesh, quad, sphere "
                  "and disk are)");
    }
    params.report_unused(scene().warnings);
    TriangleMesh world = transformed(std::move(mesh), state_.transform, where);
    if (state_.area_light) {
      mesh_lights(world, *state_.area_light, where);
      return;
    }
    add_occluder(oriented(std::move(world)), current_material(), where);
  }

  void check_indices(PbrtParams& params, const PbrtParameter& parameter, const TriangleMesh& mesh) {
    for (uint32_t index : mesh.indices)
      if (index >= mesh.positions.size())
        params.fail(parameter, "index " + std::to_string(index) + " out of range [0, " +
                                   std::to_string(mesh.positions.size()) + ")");
  }

  TriangleMesh triangle_mesh(PbrtParams& params) {
    TriangleMesh mesh;
    const std::vector<double>* p = params.numbers("P", {"point3", "point"}, 3);
    if (!p) params.fail("trianglemesh needs \"point P\"");
    const PbrtParameter& p_parameter = *params.find("P");
    size_t vertices = p->size() / 3;
    if (vertices > std::numeric_limits<uint32_t>::max())
      params.fail(p_parameter, "too many vertices for 32-bit indices");
    for (size_t v = 0; v < vertices; ++v)
      mesh.positions.push_back({(*p)[3 * v], (*p)[3 * v + 1], (*p)[3 * v + 2]});
    const std::vector<double>* indices = params.numbers("indices", {"integer"}, 3);
    if (indices) {
      for (double index : *indices) {
        if (!(index >= 0 && index < double(vertices)))
          params.fail(*params.find("indices"), "index " + number_text(index) +
                                                   " out of range [0, " + std::to_string(vertices) +
                                                   ")");
        mesh.indices.push_back(static_cast<uint32_t>(index));
      }
    } else if (vertices == 3) {
      mesh.indices = {0, 1, 2};  // pbrt-v3 allows one triangle without indices
    } else {
      params.fail("trianglemesh needs \"integer indices\" (only a single triangle may omit them)");
    }
    if (mesh.indices.empty()) params.fail("trianglemesh has no triangles");
    if (const std::vector<double>* n = params.numbers("N", {"normal", "normal3"}, 3)) {
      if (n->size() != p->size())
        params.fail(*params.find("N"),
                    "needs one normal per vertex (" + std::to_string(vertices) + ")");
      for (size_t v = 0; v < vertices; ++v)
        mesh.normals.push_back({(*n)[3 * v], (*n)[3 * v + 1], (*n)[3 * v + 2]});
    }
    for (const char* name : {"uv", "st"}) {
      if (!params.has(name)) continue;
      if (!mesh.uvs.empty()) params.fail(*params.find(name), "both uv and st are given");
      const std::vector<double>* uv = params.numbers(name, {"float", "point2"}, 2);
      if (uv->size() != 2 * vertices)
        params.fail(*params.find(name),
                    "needs one (u, v) per vertex (" + std::to_string(vertices) + ")");
      for (size_t v = 0; v < vertices; ++v) mesh.uvs.push_back({(*uv)[2 * v], (*uv)[2 * v + 1]});
    }
    if (params.has("S")) {
      params.ignore("S");
      warn(params.find("S")->location,
           "per-vertex tangents S ignored (the shading frame is "
           "built from the normal)");
    }
    params.ignore("faceIndices");
    return mesh;
  }

  TriangleMesh ply_mesh(PbrtParams& params) {
    const PbrtParameter* file = params.find("filename");
    if (!file) params.fail("plymesh needs \"string filename\"");
    std::string name = params.string("filename", "");
    std::string relative = scene_file(*file, name, "PLY");
    const std::string& bytes = read_scene_file(*file, relative, "PLY");
    PlyReadResult read;
    try {
      read = read_ply_mesh(bytes, limits_.max_triangles, limits_.max_triangles);
    } catch (const std::invalid_argument& error) {
      pbrt_fail(file->location, "PLY file '" + relative + "' cannot be used: " + error.what());
    }
    if (read.skipped_faces > 0)
      warn(file->location, "PLY file '" + relative + "': " + std::to_string(read.skipped_faces) +
                               " face(s) with other than 3 or 4 vertices skipped (as pbrt-v3 "
                               "skips them)");
    if (params.has("displacement") || params.has("edgelength"))
      params.fail("displacement mapping is not modelled");
    return std::move(read.mesh);  // (bytes stay in the file list for the content hash)
  }

  TriangleMesh sphere(PbrtParams& params) {
    double radius = params.number("radius", 1);
    double zmin = params.number("zmin", -radius), zmax = params.number("zmax", radius);
    double phimax = params.number("phimax", 360);
    if (!(radius > 0 && radius <= limits_.max_coordinate))
      params.fail("sphere radius must be positive (and within max_coordinate)");
    if (zmin > -radius || zmax < radius || phimax < 360)
      params.fail("partial spheres (zmin, zmax, phimax) are not modelled");
    const int subdivisions = 5;
    warn(params.statement().location, "sphere approximated by an icosphere of " +
                                          std::to_string(icosphere_triangle_count(subdivisions)) +
                                          " triangles (its flat facets shade and occlude)");
    return icosphere_mesh({0, 0, 0}, radius, subdivisions);
  }

  TriangleMesh disk(PbrtParams& params) {
    double height = params.number("height", 0), radius = params.number("radius", 1);
    double inner = params.number("innerradius", 0), phimax = params.number("phimax", 360);
    if (!(radius > 0 && radius <= limits_.max_coordinate))
      params.fail("disk radius must be positive (and within max_coordinate)");
    if (inner != 0 || phimax < 360) params.fail("annuli and partial disks are not modelled");
    const int segments = 128;
    warn(params.statement().location, "disk approximated by a " + std::to_string(segments) +
                                          "-gon (its occlusion differs by under 0.1% of its area)");
    TriangleMesh mesh;
    mesh.positions.push_back({0, 0, height});
    for (int k = 0; k < segments; ++k) {
      double phi = 2 * kPi * k / segments;
      mesh.positions.push_back({radius * std::cos(phi), radius * std::sin(phi), height});
    }
    for (int k = 0; k < segments; ++k)
      mesh.indices.insert(mesh.indices.end(),
                          {0, uint32_t(1 + k), uint32_t(1 + (k + 1) % segments)});
    return mesh;
  }

  void disk_light(PbrtParams& params) {
    double height = params.number("height", 0), radius = params.number("radius", 1);
    double inner = params.number("innerradius", 0), phimax = params.number("phimax", 360);
    params.report_unused(scene().warnings);
    if (inner != 0 || phimax < 360) params.fail("annulus and partial-disk lights are not modelled");
    const Mat4& t = state_.transform;
    Vec3 center = t.point({0, 0, height});
    Vec3 a = t.vector({radius, 0, 0}), b = t.vector({0, radius, 0});
    if (std::abs(length(a) - length(b)) > 1e-6 * length(a) ||
        std::abs(dot(a, b)) > 1e-6 * dot(a, a))
      params.fail("a disk light under a non-uniform scale (an ellipse) is not modelled");
    std::optional<Mat4> inverse = t.inverse();
    if (!inverse) params.fail("the disk's transform is singular");
    // pbrt-v3's disk emits along its transformed +z normal, flipped by ReverseOrientation.
    Vec3 normal = Mat4::normal(*inverse, {0, 0, 1});
    if (state_.reverse_orientation) normal = -normal;
    const AreaLightState& area = *state_.area_light;
    for (int side = 0; side < (area.two_sided ? 2 : 1); ++side) {
      Light light;
      try {
        light = make_disk_light(center, side == 0 ? normal : -normal, length(a), area.radiance);
      } catch (const std::invalid_argument& error) {
        params.fail(std::string("degenerate disk light: ") + error.what());
      }
      push_light(light, area.samples, params.statement().location);
    }
  }

  void object_instance(const PbrtStatement& statement) {
    const PbrtToken& name = statement.arguments[0];
    if (current_object_)
      pbrt_fail(name.location,
                "ObjectInstance inside the definition of object '" + *current_object_ + "'");
    auto found = objects_.find(name.text);
    if (found == objects_.end())
      pbrt_fail(name.location, "object \"" + name.text + "\" is not defined (no ObjectBegin)");
    for (const InstancedMesh& shape : found->second) {
      TriangleMesh world = transformed(shape.mesh, state_.transform, statement.location);
      size_t dropped = 0;
      try {
        dropped = append_mesh_to_scene(scene(), world, shape.material, limits_);
      } catch (const std::invalid_argument& error) {
        pbrt_fail(statement.location, error.what());
      }
      if (dropped > 0)
        warn(statement.location, "dropped " + std::to_string(dropped) + " zero-area triangle(s)");
    }
  }

  const ObjFileReader& read_file_;
  const std::string& source_;
  const SceneLimits& limits_;
  ParsedScene result_;

  GraphicsState state_;
  std::vector<SavedState> attribute_stack_;
  std::map<std::string, Mat4> named_systems_;
  std::map<std::string, PbrtStatement> options_;
  std::optional<PbrtStatement> camera_statement_;
  Mat4 camera_world_to_camera_ = Mat4::identity();
  std::map<std::string, std::vector<InstancedMesh>> objects_;
  std::optional<std::string> current_object_;
  std::vector<int> light_samples_;
  std::map<std::string, std::shared_ptr<const std::string>> images_;
  int default_material_ = -1;
  bool in_world_ = false;
  bool world_ended_ = false;
};

}  // namespace

ParsedScene parse_pbrt_scene(const std::string& text, const ObjFileReader& read_file,
                             const std::string& source, const SceneLimits& limits) {
  return PbrtSceneBuilder(read_file, source, limits).build(text);
}

}  // namespace penumbra
