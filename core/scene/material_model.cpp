// pbrt-v3's default material parameters (its Create*Material functions, PBR 3rd ed. ch. 9).

#include "core/scene/scene.h"

namespace penumbra {
namespace {

SpectrumParam grey(double v) {
  return {{v, v, v}, kNoTexture};
}
FloatParam number(double v) {
  return {v, kNoTexture};
}

}  // namespace

Material pbrt_material_defaults(MaterialType type) {
  Material m;
  m.type = type;
  MaterialParams& p = m.params;
  p.opacity = grey(1);
  p.eta = number(1.5);
  switch (type) {
    case MaterialType::Matte:
      p.kd = grey(0.5);
      p.sigma = number(0);
      break;
    case MaterialType::Plastic:
      p.kd = grey(0.25);
      p.ks = grey(0.25);
      p.uroughness = p.vroughness = number(0.1);
      break;
    case MaterialType::Substrate:
      p.kd = grey(0.5);
      p.ks = grey(0.5);
      p.uroughness = p.vroughness = number(0.1);
      break;
    case MaterialType::Metal:
      p.uroughness = p.vroughness = number(0.01);
      break;
    case MaterialType::Mirror:
      p.kr = grey(0.9);
      break;
    case MaterialType::Glass:
      p.kr = grey(1);
      p.kt = grey(1);
      p.uroughness = p.vroughness = number(0);
      break;
    case MaterialType::Uber:
      p.kd = grey(0.25);
      p.ks = grey(0.25);
      p.kr = grey(0);
      p.kt = grey(0);
      p.uroughness = p.vroughness = number(0.1);
      break;
    case MaterialType::Lambert:
    case MaterialType::Phong:
    case MaterialType::Ggx:
      break;
  }
  return m;
}

}  // namespace penumbra
