#include "core/method/direct_lighting.h"

#include <new>
#include <type_traits>
#include <variant>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"
#include "core/polygon/psa_strategy.h"
#include "core/strategies/area_strategy.h"
#include "core/strategies/bsdf_strategy.h"
#include "core/strategies/solid_angle_strategy.h"

namespace penumbra {

namespace {

// monostate: not prepared (never sampled or evaluated).
using PreparedStrategy = std::variant<std::monostate, AreaStrategy, SolidAngleStrategy, BsdfStrategy,
                                      ProjectedSolidAngleStrategy>;

std::optional<LightPoint> sample_strategy(const PreparedStrategy& strategy, const Vec2& u) {
  return std::visit(
      [&](const auto& s) -> std::optional<LightPoint> {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, std::monostate>) return std::nullopt;
        else return s.sample(u);
      },
      strategy);
}

double pdf_strategy(const PreparedStrategy& strategy, const Vec3& point) {
  return std::visit(
      [&](const auto& s) -> double {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, std::monostate>) return 0.0;
        else return s.pdf(point);
      },
      strategy);
}

PreparedStrategy prepare(StrategyKind kind, const ShadingPoint& sp, const Light& light) {
  switch (kind) {
    case StrategyKind::Area: return AreaStrategy(sp, light);
    case StrategyKind::SolidAngle: return SolidAngleStrategy(sp, light);
    case StrategyKind::Bsdf: return BsdfStrategy(sp, light);
    case StrategyKind::ProjectedSolidAngle: return ProjectedSolidAngleStrategy(sp, light);
    default: break;
  }
  // The constructor of DirectLighting refuses every other kind before we get here.
  return std::monostate{};
}

// Aspect of the 2D strata: strategies that map u.x along edge1 and u.y along edge2 of a quad.
double strata_aspect(StrategyKind kind, const Light& light) {
  if (light.type != LightType::Quad) return 1.0;
  if (kind != StrategyKind::Area && kind != StrategyKind::SolidAngle) return 1.0;
  double e1 = length(light.edge1), e2 = length(light.edge2);
  return (e1 > 0 && e2 > 0) ? e1 / e2 : 1.0;
}

// The unoccluded integrand in area measure: f(wo, wi) cos_x Le cos_l / r^2.
Rgb unshadowed_integrand(const ShadingPoint& sp, const Light& light, const Vec3& point) {
  Vec3 d = point - sp.position;
  double r2 = length_squared(d);
  if (!(r2 > 0)) return {};
  double r = std::sqrt(r2);
  Vec3 wi = d / r;
  double cos_x = dot(sp.normal, wi);
  double cos_l = -dot(light.normal, wi);
  if (cos_x <= 0 || cos_l <= 0) return {};
  Rgb le = emitted_radiance(light, point, -wi);
  if (is_black(le)) return {};
  Rgb f = eval_bsdf(*sp.material, sp.normal, sp.wo, wi);
  return f * le * (cos_x * cos_l / r2);
}

// Can this light reach the shading point at all? (A planar emitter seen from behind or edge-on
// contributes nothing; neither does a light entirely below the shading point's horizon.)
bool light_faces_point(const ShadingPoint& sp, const Light& light) {
  if (dot(light.normal, sp.position - light.centroid) <= 0) return false;
  if (light.type == LightType::Disk) {
    // The disk's lowest point relative to the tangent plane.
    double height = dot(sp.normal, light.center - sp.position);
    Vec3 in_plane = sp.normal - light.normal * dot(sp.normal, light.normal);
    return height + light.radius * length(in_plane) > 0;
  }
  for (const Vec3& v : light.vertices)
    if (dot(sp.normal, v - sp.position) > 0) return true;
  return false;
}

double weight_of(Combine combine, int term, std::span<const double> scaled_pdfs) {
  // scaled_pdfs[k] = n_k p_k
  int terms = int(scaled_pdfs.size());
  if (terms == 1) return 1.0;
  switch (combine) {
    case Combine::Avg: return 1.0 / terms;
    case Combine::Power: {
      double sum = 0;
      for (double p : scaled_pdfs) sum += p * p;
      return sum > 0 ? scaled_pdfs[term] * scaled_pdfs[term] / sum : 0.0;
    }
    case Combine::Balance:
    default: {
      double sum = 0;
      for (double p : scaled_pdfs) sum += p;
      return sum > 0 ? scaled_pdfs[term] / sum : 0.0;
    }
  }
}

// The prepared strategies of one (shading point, light), constructed in place. Not an array of
// variants or optionals: those value-initialize (zero) their whole storage, and a psa strategy
// is kilobytes: zeroing 16 of them cost more than the rest of a sample.
class PreparedTerms {
 public:
  PreparedTerms() = default;
  PreparedTerms(const PreparedTerms&) = delete;
  PreparedTerms& operator=(const PreparedTerms&) = delete;
  ~PreparedTerms() {
    for (size_t i = 0; i < count_; ++i) at(i).~PreparedStrategy();
  }
  void emplace_back(PreparedStrategy&& strategy) {
    new (storage_[count_++]) PreparedStrategy(std::move(strategy));
  }
  const PreparedStrategy& operator[](size_t i) const {
    return *std::launder(reinterpret_cast<const PreparedStrategy*>(storage_[i]));
  }

 private:
  PreparedStrategy& at(size_t i) {
    return *std::launder(reinterpret_cast<PreparedStrategy*>(storage_[i]));
  }
  alignas(PreparedStrategy) unsigned char storage_[kMaxMethodTerms][sizeof(PreparedStrategy)];
  size_t count_ = 0;
};

[[noreturn]] void refuse(const MethodSpec& method, const std::string& why) {
  throw FormatError("method", "\"" + to_string(method) + "\": " + why);
}

}  // namespace

DirectLighting::DirectLighting(const Scene& scene, const MethodSpec& method)
    : scene_(&scene), method_(method) {
  for (const MethodTerm& term : method.terms) {
    switch (term.strategy) {
      case StrategyKind::Area:
      case StrategyKind::SolidAngle:
      case StrategyKind::Bsdf: break;
      case StrategyKind::ProjectedSolidAngle:
        for (size_t l = 0; l < scene.lights.size(); ++l)
          if (scene.lights[l].type == LightType::Disk)
            refuse(method, "strategy \"psa\" samples polygons and quads; light " +
                               std::to_string(l) + " is a disk (use sa or area)");
        break;
      case StrategyKind::Ltc:
        refuse(method, "strategy \"" + std::string(strategy_name(term.strategy)) +
                           "\" is not available yet (Peters 2021 LTC sampling, issue #4)");
      case StrategyKind::LineArea:
      case StrategyKind::LineSolidAngle:
      case StrategyKind::LineBd16:
        refuse(method, "strategy \"" + std::string(strategy_name(term.strategy)) +
                           "\" is not available yet (line samples, issue #3)");
    }
  }
  switch (method.combine) {
    case Combine::Balance:
    case Combine::Power:
    case Combine::Avg: break;
    default:
      refuse(method, "combination \"" + std::string(combine_name(method.combine)) +
                         "\" is not available yet");
  }
}

std::vector<double> DirectLighting::weights(const ShadingPoint& sp, int light_index,
                                            const Vec3& light_point, int multiplier) const {
  const Light& light = scene_->lights[light_index];
  size_t terms = method_.terms.size();
  std::vector<double> scaled(terms);
  for (size_t k = 0; k < terms; ++k) {
    PreparedStrategy strategy = prepare(method_.terms[k].strategy, sp, light);
    double pdf = pdf_strategy(strategy, light_point);
    scaled[k] = double(method_.terms[k].count) * multiplier * pdf;
  }
  std::vector<double> out(terms);
  for (size_t k = 0; k < terms; ++k) out[k] = weight_of(method_.combine, int(k), scaled);
  return out;
}

Rgb DirectLighting::estimate(const ShadingPoint& sp, const Visibility& visibility,
                             Pattern pattern, const StreamKey& key, int multiplier) const {
  thread_local std::vector<Vec2> samples;
  constexpr int kMaxTerms = kMaxMethodTerms;
  Rgb total;
  const size_t term_count = method_.terms.size();
  for (size_t l = 0; l < scene_->lights.size(); ++l) {
    const Light& light = scene_->lights[l];
    if (!light_faces_point(sp, light)) continue;

    // Prepare every term's strategy once for this shading point and light.
    PreparedTerms prepared;
    for (size_t k = 0; k < term_count; ++k)
      prepared.emplace_back(prepare(method_.terms[k].strategy, sp, light));

    Rgb light_sum;
    for (size_t i = 0; i < term_count; ++i) {
      const MethodTerm& term = method_.terms[i];
      const int n = term.count * multiplier;
      samples.resize(n);
      StreamKey stream = key;
      stream.stream = light_term_stream(int(l), int(i));
      generate_2d(pattern, stream, strata_aspect(term.strategy, light), samples);

      for (int j = 0; j < n; ++j) {
        std::optional<LightPoint> x = sample_strategy(prepared[i], samples[j]);
        if (!x || !(x->pdf_area > 0)) continue;
        Rgb f = unshadowed_integrand(sp, light, x->position);
        if (is_black(f)) continue;

        double weight = 1.0;
        if (term_count > 1) {
          double scaled[kMaxTerms];
          for (size_t k = 0; k < term_count; ++k) {
            double pdf = k == i ? x->pdf_area : pdf_strategy(prepared[k], x->position);
            scaled[k] = double(method_.terms[k].count) * multiplier * pdf;
          }
          weight = weight_of(method_.combine, int(i), std::span<const double>(scaled, term_count));
          if (weight == 0) continue;
        }
        if (visibility.occluded(sp.position, sp.normal, x->position)) continue;
        Rgb contribution = f * (weight / (double(n) * x->pdf_area));
        if (is_finite(contribution)) light_sum += contribution;
      }
    }
    total += light_sum;
  }
  return total;
}

}  // namespace penumbra
