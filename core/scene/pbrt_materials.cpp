#include "core/scene/pbrt_materials.h"

#include <algorithm>
#include <filesystem>

namespace penumbra {

namespace {

// A spectrum parameter: an RGB constant or a spectrum texture; `fallback` when absent.
SpectrumParam spectrum_param(PbrtParams& params, const PbrtTextureScope& scope,
                             const std::string& name, const SpectrumParam& fallback) {
  const PbrtParameter* parameter = params.find(name);
  if (!parameter) return fallback;
  if (parameter->type == "texture") {
    if (parameter->strings.size() != 1) params.fail(*parameter, "names one texture");
    int index = scope.spectrum_texture(parameter->strings[0]);
    if (index < 0)
      params.fail(*parameter, "spectrum texture \"" + parameter->strings[0] + "\" is not defined");
    return {{0, 0, 0}, index};
  }
  if (parameter->type == "float" && parameter->numbers.size() == 1) {
    double v = parameter->numbers[0];
    return {{v, v, v}, kNoTexture};
  }
  return {*params.color(name), kNoTexture};
}

// A float parameter: a number or a float texture; `fallback` when absent.
FloatParam float_param(PbrtParams& params, const PbrtTextureScope& scope, const std::string& name,
                       const FloatParam& fallback) {
  const PbrtParameter* parameter = params.find(name);
  if (!parameter) return fallback;
  if (parameter->type == "texture") {
    if (parameter->strings.size() != 1) params.fail(*parameter, "names one texture");
    int index = scope.float_texture(parameter->strings[0]);
    if (index < 0)
      params.fail(*parameter, "float texture \"" + parameter->strings[0] + "\" is not defined");
    return {0, index};
  }
  return {params.number(name, fallback.value), kNoTexture};
}

bool is_constant_grey_or_rgb(const SpectrumParam& p) {
  return p.texture == kNoTexture;
}

}  // namespace

Material pbrt_default_material() {
  Material material;
  material.name = "pbrt-default";
  material.type = MaterialType::Lambert;
  material.albedo = Rgb(0.5, 0.5, 0.5);
  material.params = pbrt_material_defaults(MaterialType::Matte).params;
  return material;
}

Material material_from_pbrt(const std::string& name, const std::string& type, PbrtParams& params,
                            const PbrtTextureScope& scope, std::vector<std::string>& warnings) {
  static const std::pair<const char*, MaterialType> kTypes[] = {
      {"matte", MaterialType::Matte},
      {"plastic", MaterialType::Plastic},
      {"substrate", MaterialType::Substrate},
      {"metal", MaterialType::Metal},
      {"mirror", MaterialType::Mirror},
      {"glass", MaterialType::Glass},
      {"uber", MaterialType::Uber}};
  MaterialType material_type = MaterialType::Matte;
  bool known = false;
  for (const auto& [type_name, t] : kTypes)
    if (type == type_name) material_type = t, known = true;
  if (!known)
    params.fail("material type \"" + type +
                "\" is not modelled (matte, plastic, substrate, "
                "metal, mirror, glass and uber are)");
  Material material = pbrt_material_defaults(material_type);
  material.name = name;
  MaterialParams& p = material.params;
  p.kd = spectrum_param(params, scope, "Kd", p.kd);
  p.ks = spectrum_param(params, scope, "Ks", p.ks);
  p.kr = spectrum_param(params, scope, "Kr", p.kr);
  p.kt = spectrum_param(params, scope, "Kt", p.kt);
  p.opacity = spectrum_param(params, scope, "opacity", p.opacity);
  p.sigma = float_param(params, scope, "sigma", p.sigma);
  p.remap_roughness = params.boolean("remaproughness", true);
  // Roughness as each of pbrt-v3's materials reads it: plastic has one "roughness"; metal's and
  // uber's "roughness" is the default of "uroughness", and of "vroughness" for metal, while
  // uber's "vroughness" falls back to its u roughness; substrate and glass read u and v only.
  if (material_type == MaterialType::Plastic || material_type == MaterialType::Metal ||
      material_type == MaterialType::Uber) {
    FloatParam roughness = float_param(params, scope, "roughness", p.uroughness);
    p.uroughness = float_param(params, scope, "uroughness", roughness);
    p.vroughness = float_param(params, scope, "vroughness",
                               material_type == MaterialType::Uber ? p.uroughness : roughness);
  } else {
    p.uroughness = float_param(params, scope, "uroughness", p.uroughness);
    p.vroughness = float_param(params, scope, "vroughness", p.vroughness);
  }
  if (material_type == MaterialType::Metal) {
    // pbrt-v3's default metal is copper (measured spectra); its RGB equivalent.
    const SpectrumParam copper_eta{{0.200438, 0.924033, 1.10221}, kNoTexture};
    const SpectrumParam copper_k{{3.91295, 2.45285, 2.14219}, kNoTexture};
    if (!params.has("eta") || !params.has("k"))
      warnings.push_back(params.statement().location.str() + ": metal '" + name +
                         "': pbrt-v3's default copper spectra taken as their RGB values");
    p.eta_rgb = spectrum_param(params, scope, "eta", copper_eta);
    p.k = spectrum_param(params, scope, "k", copper_k);
  } else {
    // glass and uber: "eta", else "index".
    p.eta = float_param(params, scope, "eta", float_param(params, scope, "index", p.eta));
  }
  if (const PbrtParameter* bump = params.find("bumpmap")) {
    if (bump->type != "texture" || bump->strings.size() != 1)
      params.fail(*bump, "a bump map is a float texture (\"texture bumpmap\")");
    p.bump = scope.float_texture(bump->strings[0]);
    if (p.bump < 0) params.fail(*bump, "float texture \"" + bump->strings[0] + "\" is not defined");
  }
  // The exact Lambert case every renderer path has: matte, constant Kd, no roughness, no bump.
  if (material_type == MaterialType::Matte && is_constant_grey_or_rgb(p.kd) &&
      p.sigma.texture == kNoTexture && p.sigma.value == 0 && p.bump == kNoTexture) {
    Rgb kd = p.kd.value;
    bool clamped = false;
    for (int c = 0; c < 3; ++c) {
      double v = std::clamp(kd[c], 0.0, 1.0);
      clamped = clamped || v != kd[c];
      kd[c] = v;
    }
    if (clamped)
      warnings.push_back(params.statement().location.str() + ": matte '" + name +
                         "': Kd clamped to [0, 1]");
    material.type = MaterialType::Lambert;
    material.albedo = kd;
  }
  params.report_unused(warnings);
  return material;
}

Texture texture_from_pbrt(PbrtParams& params, const PbrtTextureScope& scope,
                          const std::function<std::shared_ptr<const std::string>(
                              const PbrtParameter& where, const std::string& name)>& read_image) {
  const PbrtStatement& statement = params.statement();
  Texture texture;
  texture.name = statement.arguments[0].text;
  texture.is_float = statement.arguments[1].text == "float";
  const std::string& class_name = statement.arguments[2].text;
  std::string mapping = params.string("mapping", "uv");
  if (mapping != "uv")
    params.fail(*params.find("mapping"),
                "texture mapping \"" + mapping + "\" is not modelled (\"uv\" is)");
  texture.su = params.number("uscale", 1);
  texture.sv = params.number("vscale", 1);
  texture.du = params.number("udelta", 0);
  texture.dv = params.number("vdelta", 0);
  // An operand: a constant or a texture of the same kind as this one.
  auto operand = [&](const std::string& name, double fallback) {
    if (texture.is_float) {
      FloatParam f = float_param(params, scope, name, {fallback, kNoTexture});
      return SpectrumParam{{f.value, f.value, f.value}, f.texture};
    }
    return spectrum_param(params, scope, name, {{fallback, fallback, fallback}, kNoTexture});
  };
  if (class_name == "constant") {
    texture.type = TextureType::Constant;
    texture.value = operand("value", 1).value;
  } else if (class_name == "scale") {
    texture.type = TextureType::Scale;
    texture.tex1 = operand("tex1", 1);
    texture.tex2 = operand("tex2", 1);
  } else if (class_name == "mix") {
    texture.type = TextureType::Mix;
    texture.tex1 = operand("tex1", 0);
    texture.tex2 = operand("tex2", 1);
    texture.amount = float_param(params, scope, "amount", {0.5, kNoTexture});
  } else if (class_name == "checkerboard") {
    texture.type = TextureType::Checkerboard;
    if (params.integer("dimension", 2) != 2)
      params.fail(*params.find("dimension"), "3D checkerboards are not modelled");
    texture.tex1 = operand("tex1", 1);
    texture.tex2 = operand("tex2", 0);
    std::string mode = params.string("aamode", "closedform");
    if (mode != "closedform" && mode != "none")
      params.fail(*params.find("aamode"), "aamode must be \"closedform\" or \"none\"");
    texture.checker_filtered = mode == "closedform";
  } else if (class_name == "imagemap") {
    texture.type = TextureType::ImageMap;
    const PbrtParameter* file = params.find("filename");
    if (!file) params.fail("imagemap needs \"string filename\"");
    texture.filename = params.string("filename", "");
    texture.image = read_image(*file, texture.filename);
    std::string extension = std::filesystem::path(texture.filename).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    texture.gamma = params.boolean("gamma", extension == ".tga" || extension == ".png");
    texture.scale = params.number("scale", 1);
    std::string wrap = params.string("wrap", "repeat");
    if (wrap == "repeat")
      texture.wrap = TextureWrap::Repeat;
    else if (wrap == "black")
      texture.wrap = TextureWrap::Black;
    else if (wrap == "clamp")
      texture.wrap = TextureWrap::Clamp;
    else
      params.fail(*params.find("wrap"), "wrap must be \"repeat\", \"black\" or \"clamp\"");
    texture.trilinear = params.boolean("trilinear", false);
    texture.max_anisotropy = params.number("maxanisotropy", 8);
  } else {
    params.fail("texture class \"" + class_name +
                "\" is not modelled (constant, scale, mix, "
                "checkerboard and imagemap are)");
  }
  return texture;
}

}  // namespace penumbra
