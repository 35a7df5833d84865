#include "core/materials/pbrt_shading.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <vector>

#include "core/image/oiio_services.h"

namespace penumbra {
namespace {

// Two unit vectors perpendicular to n and to each other (pbrt-v3's CoordinateSystem role).
void coordinate_system(const Vec3& n, Vec3& s, Vec3& t) {
  Frame f = Frame::from_normal(n);
  s = f.s;
  t = f.t;
}

// pbrt-v3's InverseGammaCorrect (the sRGB curve).
double inverse_gamma(double v) {
  if (v <= 0.04045) return v * (1.0 / 12.92);
  return std::pow((v + 0.055) * (1.0 / 1.055), 2.4);
}

// pbrt-v3's RGBSpectrum::y().
double pbrt_luminance(double r, double g, double b) {
  return 0.212671 * r + 0.715160 * g + 0.072169 * b;
}

Vec3 face_forward(const Vec3& v, const Vec3& reference) {
  return dot(v, reference) < 0 ? -v : v;
}

}  // namespace

SurfaceGeometry triangle_geometry(const Scene& scene, uint32_t triangle, const Vec2& b) {
  SurfaceGeometry g;
  const uint32_t* tri = &scene.indices[size_t(triangle) * 3];
  const Vec3& p0 = scene.positions[tri[0]];
  const Vec3& p1 = scene.positions[tri[1]];
  const Vec3& p2 = scene.positions[tri[2]];
  double b0 = 1 - b.x - b.y;
  g.p = p0 * b0 + p1 * b.x + p2 * b.y;
  uint8_t flags = scene.triangle_shading.empty() ? 0 : scene.triangle_shading[triangle];
  Vec2 uv[3] = {{0, 0}, {1, 0}, {1, 1}};
  if ((flags & kTriangleHasUvs) && !scene.uvs.empty())
    for (int i = 0; i < 3; ++i) uv[i] = scene.uvs[tri[i]];
  g.uv = {uv[0].x * b0 + uv[1].x * b.x + uv[2].x * b.y,
          uv[0].y * b0 + uv[1].y * b.x + uv[2].y * b.y};

  Vec3 n = cross(p1 - p0, p2 - p0);
  double n_length = length(n);
  g.n = n_length > 0 ? n / n_length : Vec3{0, 0, 1};

  // dp/du, dp/dv from the uv differences (pbrt-v3's Triangle::Intersect).
  double du02 = uv[0].x - uv[2].x, dv02 = uv[0].y - uv[2].y;
  double du12 = uv[1].x - uv[2].x, dv12 = uv[1].y - uv[2].y;
  Vec3 dp02 = p0 - p2, dp12 = p1 - p2;
  double determinant = du02 * dv12 - dv02 * du12;
  bool degenerate = std::abs(determinant) < 1e-8;
  if (!degenerate) {
    double inv = 1.0 / determinant;
    g.dpdu = (dv12 * dp02 - dv02 * dp12) * inv;
    g.dpdv = (du02 * dp12 - du12 * dp02) * inv;
  }
  if (degenerate || !(length_squared(cross(g.dpdu, g.dpdv)) > 0))
    coordinate_system(g.n, g.dpdu, g.dpdv);

  g.ns = g.n;
  g.shading_dpdu = g.dpdu;
  g.shading_dpdv = g.dpdv;
  if ((flags & kTriangleHasNormals) && !scene.normals.empty()) {
    const Vec3& n0 = scene.normals[tri[0]];
    const Vec3& n1 = scene.normals[tri[1]];
    const Vec3& n2 = scene.normals[tri[2]];
    Vec3 ns = n0 * b0 + n1 * b.x + n2 * b.y;
    double ns_length = length(ns);
    if (ns_length > 0) {
      g.ns = ns / ns_length;
      Vec3 ss = normalize(g.dpdu);
      Vec3 ts = cross(g.ns, ss);
      if (length_squared(ts) > 0) {
        ts = normalize(ts);
        ss = cross(ts, g.ns);
      } else {
        coordinate_system(g.ns, ss, ts);
      }
      g.shading_dpdu = ss;
      g.shading_dpdv = ts;
      // dn/du, dn/dv from the vertex normals.
      if (!degenerate) {
        double inv = 1.0 / determinant;
        Vec3 dn02 = n0 - n2, dn12 = n1 - n2;
        g.dndu = (dv12 * dn02 - dv02 * dn12) * inv;
        g.dndv = (du02 * dn12 - du12 * dn02) * inv;
      }
      // The shading normal is authoritative for orientation.
      g.n = face_forward(g.n, g.ns);
    }
  }
  return g;
}

void set_footprint(SurfaceGeometry& g, const RayDifferential& ray) {
  double d = dot(g.n, g.p);
  double denom_x = dot(g.n, ray.dx_direction), denom_y = dot(g.n, ray.dy_direction);
  if (!(std::abs(denom_x) > 0) || !(std::abs(denom_y) > 0)) return;
  double tx = -(dot(g.n, ray.dx_origin) - d) / denom_x;
  double ty = -(dot(g.n, ray.dy_origin) - d) / denom_y;
  if (!std::isfinite(tx) || !std::isfinite(ty)) return;
  Vec3 dpdx = ray.dx_origin + tx * ray.dx_direction - g.p;
  Vec3 dpdy = ray.dy_origin + ty * ray.dy_direction - g.p;
  int dim0, dim1;
  if (std::abs(g.n.x) > std::abs(g.n.y) && std::abs(g.n.x) > std::abs(g.n.z)) {
    dim0 = 1;
    dim1 = 2;
  } else if (std::abs(g.n.y) > std::abs(g.n.z)) {
    dim0 = 0;
    dim1 = 2;
  } else {
    dim0 = 0;
    dim1 = 1;
  }
  double a00 = g.dpdu[dim0], a01 = g.dpdv[dim0], a10 = g.dpdu[dim1], a11 = g.dpdv[dim1];
  double det = a00 * a11 - a01 * a10;
  if (!(std::abs(det) >= 1e-10)) return;
  auto solve = [&](const Vec3& rhs, double& x0, double& x1) {
    double b0 = rhs[dim0], b1 = rhs[dim1];
    x0 = (a11 * b0 - a01 * b1) / det;
    x1 = (a00 * b1 - a10 * b0) / det;
    if (!std::isfinite(x0)) x0 = 0;
    if (!std::isfinite(x1)) x1 = 0;
  };
  solve(dpdx, g.dudx, g.dvdx);
  solve(dpdy, g.dudy, g.dvdy);
}

struct SceneTextures::Impl {
  // OpenImageIO's texture system over the scene's MIP-mapped image maps (none without any).
  std::unique_ptr<oiio::TextureSystem> system;
  std::filesystem::path directory;
  // Per texture of the scene: its handle in the system (image maps only).
  std::vector<const void*> handles;

  ~Impl() {
    system.reset();
    std::error_code ignored;
    if (!directory.empty()) std::filesystem::remove_all(directory, ignored);
  }
};

SceneTextures::SceneTextures(const Scene& scene) : scene_(&scene), impl_(std::make_unique<Impl>()) {
  impl_->handles.resize(scene.textures.size(), nullptr);
  bool any_image = false;
  for (const Texture& t : scene.textures) any_image = any_image || t.type == TextureType::ImageMap;
  if (!any_image) return;
  static std::atomic<uint64_t> counter{0};
  impl_->directory =
      std::filesystem::temp_directory_path() /
      ("penumbra-textures-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::create_directories(impl_->directory);
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const Texture& t = scene.textures[i];
    if (t.type != TextureType::ImageMap) continue;
    auto fail = [&](const std::string& why) {
      throw FormatError("", "texture \"" + t.name + "\" (" + t.filename + "): " + why);
    };
    if (!t.image) fail("no image data");
    try {
      const oiio::Services& services = oiio::services();
      if (!impl_->system) impl_->system = services.texture_system(512.0f);
      oiio::Pixels source =
          services.decode_image(*t.image, std::filesystem::path(t.filename).extension().string());
      // Decode as pbrt-v3 does before it builds the MIP map.
      oiio::Pixels decoded;
      decoded.width = source.width;
      decoded.height = source.height;
      decoded.channels = t.is_float ? 1 : 3;
      decoded.data.resize(size_t(source.width) * size_t(source.height) * size_t(decoded.channels));
      size_t pixel_count = size_t(source.width) * size_t(source.height);
      for (size_t p = 0; p < pixel_count; ++p) {
        const float* in = &source.data[p * size_t(source.channels)];
        double rgb[3];
        for (int c = 0; c < 3; ++c) rgb[c] = in[std::min(c, source.channels - 1)];
        float* out = &decoded.data[p * size_t(decoded.channels)];
        if (t.is_float) {
          double y = pbrt_luminance(rgb[0], rgb[1], rgb[2]);
          out[0] = float(t.scale * (t.gamma ? inverse_gamma(y) : y));
        } else {
          for (int c = 0; c < 3; ++c)
            out[c] = float(t.scale * (t.gamma ? inverse_gamma(rgb[c]) : rgb[c]));
        }
      }
      std::filesystem::path file = impl_->directory / ("texture-" + std::to_string(i) + ".exr");
      services.write_mip_map(decoded, file.string());
      impl_->handles[i] = impl_->system->handle(file.string());
    } catch (const FormatError&) {
      throw;
    } catch (const std::runtime_error& error) {
      fail(error.what());
    }
  }
}

SceneTextures::~SceneTextures() = default;

Rgb SceneTextures::spectrum(const SpectrumParam& p, const SurfaceGeometry& g) const {
  return p.texture == kNoTexture ? p.value : evaluate(p.texture, g);
}

double SceneTextures::number(const FloatParam& p, const SurfaceGeometry& g) const {
  return p.texture == kNoTexture ? p.value : evaluate(p.texture, g).x;
}

Rgb SceneTextures::evaluate(int32_t index, const SurfaceGeometry& g) const {
  if (index < 0 || size_t(index) >= scene_->textures.size()) return {0, 0, 0};
  const Texture& t = scene_->textures[index];
  // pbrt-v3's UVMapping2D.
  double s = t.su * g.uv.x + t.du, tt = t.sv * g.uv.y + t.dv;
  double dsdx = t.su * g.dudx, dsdy = t.su * g.dudy;
  double dtdx = t.sv * g.dvdx, dtdy = t.sv * g.dvdy;
  switch (t.type) {
    case TextureType::Constant:
      return t.value;
    case TextureType::Scale:
      return spectrum(t.tex1, g) * spectrum(t.tex2, g);
    case TextureType::Mix: {
      double amount = number(t.amount, g);
      return (1 - amount) * spectrum(t.tex1, g) + amount * spectrum(t.tex2, g);
    }
    case TextureType::Checkerboard: {
      auto point = [&]() {
        return (int(std::floor(s)) + int(std::floor(tt))) % 2 == 0 ? spectrum(t.tex1, g)
                                                                   : spectrum(t.tex2, g);
      };
      if (!t.checker_filtered) return point();
      double ds = std::max(std::abs(dsdx), std::abs(dsdy));
      double dt = std::max(std::abs(dtdx), std::abs(dtdy));
      double s0 = s - ds, s1 = s + ds, t0 = tt - dt, t1 = tt + dt;
      if (std::floor(s0) == std::floor(s1) && std::floor(t0) == std::floor(t1)) return point();
      auto bump_int = [](double x) {
        return double(int(std::floor(x / 2))) +
               2 * std::max(x / 2 - int(std::floor(x / 2)) - 0.5, 0.0);
      };
      double s_int = (bump_int(s1) - bump_int(s0)) / (2 * ds);
      double t_int = (bump_int(t1) - bump_int(t0)) / (2 * dt);
      double area2 = s_int + t_int - 2 * s_int * t_int;
      if (ds == 1 || dt == 1) area2 = 0.5;
      if (!std::isfinite(area2)) return point();
      return (1 - area2) * spectrum(t.tex1, g) + area2 * spectrum(t.tex2, g);
    }
    case TextureType::ImageMap: {
      const void* handle = impl_->handles[index];
      if (!handle) return {0, 0, 0};
      oiio::TextureLookup lookup;
      lookup.wrap = t.wrap == TextureWrap::Repeat  ? oiio::Wrap::Periodic
                    : t.wrap == TextureWrap::Black ? oiio::Wrap::Black
                                                   : oiio::Wrap::Clamp;
      lookup.trilinear = t.trilinear;
      lookup.max_anisotropy = std::max(1, int(t.max_anisotropy));
      lookup.channels = t.is_float ? 1 : 3;
      // pbrt-v3 flips the image: its t = 0 is the bottom row, OpenImageIO's the top.
      lookup.s = float(s);
      lookup.t = float(1 - tt);
      lookup.dsdx = float(dsdx);
      lookup.dtdx = float(-dtdx);
      lookup.dsdy = float(dsdy);
      lookup.dtdy = float(-dtdy);
      float result[3] = {0, 0, 0};
      if (!impl_->system->texture(handle, lookup, result)) return {0, 0, 0};
      if (t.is_float) return {result[0], result[0], result[0]};
      return {result[0], result[1], result[2]};
    }
  }
  return {0, 0, 0};
}

PbrtMaterialValues material_values(const Material& m, const SurfaceGeometry& g,
                                   const SceneTextures& tx) {
  const MaterialParams& p = m.params;
  PbrtMaterialValues v;
  v.kd = tx.spectrum(p.kd, g);
  v.ks = tx.spectrum(p.ks, g);
  v.kr = tx.spectrum(p.kr, g);
  v.kt = tx.spectrum(p.kt, g);
  v.opacity = tx.spectrum(p.opacity, g);
  v.eta_rgb = tx.spectrum(p.eta_rgb, g);
  v.k = tx.spectrum(p.k, g);
  v.eta = tx.number(p.eta, g);
  v.sigma = tx.number(p.sigma, g);
  v.uroughness = tx.number(p.uroughness, g);
  v.vroughness = tx.number(p.vroughness, g);
  return v;
}

void apply_bump(const Material& m, SurfaceGeometry& g, const SceneTextures& tx) {
  if (m.params.bump == kNoTexture) return;
  FloatParam bump{0, m.params.bump};
  double du = 0.5 * (std::abs(g.dudx) + std::abs(g.dudy));
  if (du == 0) du = 0.0005;
  double dv = 0.5 * (std::abs(g.dvdx) + std::abs(g.dvdy));
  if (dv == 0) dv = 0.0005;
  SurfaceGeometry shifted = g;
  shifted.uv = {g.uv.x + du, g.uv.y};
  double u_displace = tx.number(bump, shifted);
  shifted.uv = {g.uv.x, g.uv.y + dv};
  double v_displace = tx.number(bump, shifted);
  double displace = tx.number(bump, g);
  Vec3 dpdu = g.shading_dpdu + (u_displace - displace) / du * g.ns + displace * g.dndu;
  Vec3 dpdv = g.shading_dpdv + (v_displace - displace) / dv * g.ns + displace * g.dndv;
  Vec3 ns = cross(dpdu, dpdv);
  double ns_length = length(ns);
  if (!(ns_length > 0) || !std::isfinite(ns_length)) return;
  // pbrt-v3's SetShadingGeometry(..., false): the shading normal is faced to the geometric one.
  g.ns = face_forward(ns / ns_length, g.n);
  g.shading_dpdu = dpdu;
  g.shading_dpdv = dpdv;
}

SurfaceBsdf pbrt_surface_bsdf(const Material& m, SurfaceGeometry g, const SceneTextures& tx) {
  apply_bump(m, g, tx);
  // pbrt-v3's BSDF frame: ss = normalize(shading dp/du), ts = cross(ns, ss).
  Frame frame;
  frame.n = g.ns;
  Vec3 ss = g.shading_dpdu - dot(g.shading_dpdu, g.ns) * g.ns;
  double ss_length = length(ss);
  if (ss_length > 0 && std::isfinite(ss_length)) {
    frame.s = ss / ss_length;
    frame.t = cross(frame.n, frame.s);
  } else {
    frame = Frame::from_normal(g.ns);
  }
  return make_pbrt_bsdf(m, material_values(m, g, tx), frame, g.n);
}

}  // namespace penumbra
