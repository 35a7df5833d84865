#include "core/method/direct_lighting.h"

#include <algorithm>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"
#include "core/method/combination.h"
#include "core/method/method_check.h"
#include "core/method/smoothing.h"
#include "core/method/unshadowed_integrals.h"
#include "core/strategies/registered_strategies.h"

namespace penumbra {

namespace {

// ---- Strategies: the prepared strategy of a term, its samples and densities ---------------------

// Every term's prepared strategy is a PreparedStrategy (the registry's variant,
// core/strategies/registered_strategies.h); its family says which entry points it has.

std::optional<LightPoint> sample_strategy(const PreparedStrategy& strategy, const Vec2& u) {
  return std::visit(
      [&](const auto& s) -> std::optional<LightPoint> {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, std::monostate>)
          return std::nullopt;
        else if constexpr (T::kFamily == StrategyFamily::Point)
          return s.sample(u);
        else
          return std::nullopt;
      },
      strategy);
}

double pdf_strategy(const PreparedStrategy& strategy, const Vec3& point) {
  return std::visit(
      [&](const auto& s) -> double {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, std::monostate>)
          return 0.0;
        else if constexpr (T::kFamily == StrategyFamily::Point)
          return s.pdf(point);
        else
          return 0.0;
      },
      strategy);
}

// The line of a line term's sample, or the pdf of a line term given the traced line through a
// point (its own direction's line) and the point's t on it.
std::optional<LightPoint> sample_line(const PreparedStrategy& strategy, const Vec2& u,
                                      TracedLine& line, double& t) {
  return std::visit(
      [&](const auto& s) -> std::optional<LightPoint> {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, std::monostate>)
          return std::nullopt;
        else if constexpr (T::kFamily == StrategyFamily::Line)
          return s.sample(u, line, t);
        else
          return std::nullopt;
      },
      strategy);
}
double pdf_line(const PreparedStrategy& strategy, const TracedLine& line, double t,
                const Vec3& point) {
  return std::visit(
      [&](const auto& s) -> double {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, std::monostate>)
          return 0.0;
        else if constexpr (T::kFamily == StrategyFamily::Line)
          return s.pdf(line, t, point);
        else
          return 0.0;
      },
      strategy);
}

// Aspect of the 2D strata: strategies that map u.x along edge1 and u.y along edge2 of a quad.
// Line terms (u.x the line's offset, u.y the point along it) and the BSDF use square strata:
// their sample space is not the light's rectangle, and a square grid has no leftover samples
// at N = 4^k (cmj still stratifies every 1D projection, the line offsets included, in N strata).
double strata_aspect(const MethodTerm& term, const Light& light) {
  if (light.type != LightType::Quad) return 1.0;
  if (!strategy_info(term.strategy).rectangle_strata) return 1.0;
  double e1 = length(light.edge1), e2 = length(light.edge2);
  return (e1 > 0 && e2 > 0) ? e1 / e2 : 1.0;
}

// ---- The integrand ------------------------------------------------------------------------------

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
  Rgb f = shading_bsdf(sp, wi);
  return f * le * (cos_x * cos_l / r2);
}

// Can this light reach the shading point at all? (A planar emitter seen from behind or edge-on
// contributes nothing; neither does a light entirely below the shading point's horizon.)
bool light_reaches_point(const ShadingPoint& sp, const Light& light) {
  // The emitting side, with the same tolerance the strategies use (core/lights).
  if (!light_faces_point(light, sp.position)) return false;
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

// ---- Prepared terms of one (shading point, light) -----------------------------------------------

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
  // Prepares the term's strategy in place, with its family's constructor. A line term without a
  // line query (weights() for tests) stays unprepared: no samples, density 0.
  void prepare(const MethodTerm& term, const ShadingPoint& sp, const Light& light,
               const LineQuery* lines) {
    void* slot = storage_[count_++];
    RegisteredStrategies::visit_row(term.strategy, [&]<typename T>() {
      constexpr size_t index = RegisteredStrategies::id_of<T>() + 1;
      if constexpr (T::kFamily == StrategyFamily::Point) {
        new (slot) PreparedStrategy(std::in_place_index<index>, sp, light);
      } else if constexpr (T::kFamily == StrategyFamily::Line) {
        if (lines)
          new (slot) PreparedStrategy(std::in_place_index<index>, sp, light,
                                      line_axis(term.direction), *lines);
        else
          new (slot) PreparedStrategy();
      } else {
        new (slot) PreparedStrategy(std::in_place_index<index>, sp, light, term.direction);
      }
    });
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

// ---- Lines through a point of the light (line densities, the smoothing factor) ------------------

bool smoothing(Combine combine) {
  return combine == Combine::Smooth || combine == Combine::SmoothFixed;
}

// What the combination needs of one (shading point, light) beyond the prepared terms: the line
// families along both edges (to find the line through a point, and its coordinates for the
// smoothing heuristic) and the smoothing width d_m.
struct LightLines {
  std::optional<QuadLineFamily> family[2];  // by LineAxis
  bool needed[2] = {false, false};          // some line term runs along this axis
  double smoothing_width = 0;               // d_m: half the light's smallest side
};

// The lines through one point of the light, traced on demand and shared by the terms along the
// same axis (a line-area and a line-sa term along edge1 see the same segment).
class PointLines {
 public:
  void reset() { traced_[0] = traced_[1] = false; }
  // Slot for a line term's own sample: it fills the line and t, then marks it.
  TracedLine& slot(LineAxis axis) { return line_[int(axis)]; }
  double& slot_t(LineAxis axis) { return t_[int(axis)]; }
  void mark(LineAxis axis) { traced_[int(axis)] = true; }

  // The traced line along `axis` through `point` (one line query the first time).
  const TracedLine& get(LineAxis axis, const Vec3& point, const QuadLineFamily& family,
                        const LineQuery& query, double& t) {
    int a = int(axis);
    if (!traced_[a]) {
      Vec2 st = family.coordinates(point);
      t_[a] = std::clamp(st.y, 0.0, 1.0);
      if (st.x >= -1e-9 && st.x <= 1 + 1e-9 && st.y >= -1e-9 && st.y <= 1 + 1e-9) {
        family.trace(std::clamp(st.x, 0.0, 1.0), query, line_[a]);
      } else {
        line_[a].offset = st.x;
        line_[a].visible.clear();
      }
      traced_[a] = true;
    }
    t = t_[a];
    return line_[a];
  }

 private:
  TracedLine line_[2];
  double t_[2] = {0, 0};
  bool traced_[2] = {false, false};
};

// ---- Combination: the terms' densities at a sample and its weight -------------------------------

// Salesin & Jarosz Eq. 23-24 at a point of the light: the light-edge factor along both edges
// times, for `smooth`, the occluder-edge factor of every line direction the method traces.
// 1 where the light has no line family (not a quad).
double smoothing_factor(const MethodSpec& method, const LightLines& lines, PointLines& point_lines,
                        const LineQuery* query, const Vec3& point) {
  const auto& along_edge1 = lines.family[int(LineAxis::Edge1)];
  if (!along_edge1) return 1.0;
  Vec2 st = along_edge1->coordinates(point);  // (fraction along edge2, fraction along edge1)
  double side1 = along_edge1->along_length(), side2 = along_edge1->across_length();
  double factor = light_edge_smoothing(st.y * side1, side1, lines.smoothing_width) *
                  light_edge_smoothing(st.x * side2, side2, lines.smoothing_width);
  if (method.combine == Combine::Smooth && query) {
    for (int a = 0; a < 2 && factor > 0; ++a) {
      if (!lines.needed[a] || !lines.family[a]) continue;
      double t;
      const TracedLine& line = point_lines.get(LineAxis(a), point, *lines.family[a], *query, t);
      factor *=
          occluder_edge_smoothing(line, t, lines.family[a]->along_length(), lines.smoothing_width);
    }
  }
  return factor;
}

// The combination weight of a sample of term `term` at `point` (its own pdf `own_pdf`): every
// other term's density at the point (a line query for line terms), then the heuristic
// (core/method/combination.h). Peters' per-channel heuristics are apart (below).
double combination_weight(const MethodSpec& method, const PreparedTerms& prepared,
                          const LightLines& lines, PointLines& point_lines, const LineQuery* query,
                          size_t term, double own_pdf, const Vec3& point, int multiplier) {
  const size_t term_count = method.terms.size();
  if (term_count == 1) return 1.0;
  if (method.combine == Combine::Avg) return average_weight(term_count);
  double scaled[kMaxMethodTerms];
  for (size_t k = 0; k < term_count; ++k) {
    const MethodTerm& other = method.terms[k];
    double pdf;
    if (k == term) {
      pdf = own_pdf;
    } else if (is_line_strategy(other.strategy)) {
      LineAxis axis = line_axis(other.direction);
      const auto& family = lines.family[int(axis)];
      pdf = 0;
      if (family && query) {
        double t;
        const TracedLine& line = point_lines.get(axis, point, *family, *query, t);
        pdf = pdf_line(prepared[k], line, t, point);
      }
    } else {
      pdf = pdf_strategy(prepared[k], point);
    }
    scaled[k] = double(other.count) * multiplier * pdf;
  }
  std::span<const double> scaled_pdfs(scaled, term_count);
  switch (method.combine) {
    case Combine::Power:
      return power_weight(scaled_pdfs, term);
    case Combine::Smooth:
    case Combine::SmoothFixed: {
      // Salesin & Jarosz Eq. 22: the BSDF terms' densities eased at discontinuities.
      bool eased[kMaxMethodTerms];
      for (size_t k = 0; k < term_count; ++k)
        eased[k] = method.terms[k].strategy == strategy_id<BsdfStrategy>;
      double factor = smoothing_factor(method, lines, point_lines, query, point);
      return smoothed_balance_weight(scaled_pdfs, {eased, term_count}, factor, term);
    }
    default:
      return balance_weight(scaled_pdfs, term);
  }
}

LightLines prepare_light_lines(const MethodSpec& method, const ShadingPoint& sp,
                               const Light& light) {
  LightLines lines;
  bool any = smoothing(method.combine);
  for (const MethodTerm& term : method.terms) {
    if (!is_line_strategy(term.strategy)) continue;
    lines.needed[int(line_axis(term.direction))] = true;
    any = true;
  }
  if (!any || light.type != LightType::Quad) return lines;
  for (int a = 0; a < 2; ++a)
    if (lines.needed[a] || (a == 0 && smoothing(method.combine)))
      lines.family[a] = QuadLineFamily::prepare(sp.position, sp.normal, light, LineAxis(a));
  lines.smoothing_width = 0.5 * std::min(length(light.edge1), length(light.edge2));
  return lines;
}

// ---- Peters' per-channel combination (one psa and one ltc term) ---------------------------------

// Peters 2021 Sec. 4.2-4.3: `psa+ltc/weighted` and `psa+ltc/clamped-optimal`. The weights are per
// colour channel and need the unshadowed integrals c_j of the shading point and light
// (core/method/combination.h, unshadowed_integrals.h); technique 0 is psa, 1 is ltc.
bool peters_combination(Combine combine) {
  return combine == Combine::Weighted || combine == Combine::ClampedOptimal;
}
PetersHeuristic peters_heuristic(Combine combine) {
  return combine == Combine::Weighted ? PetersHeuristic::Weighted : PetersHeuristic::ClampedOptimal;
}
int peters_technique(const MethodTerm& term) {
  return term.strategy == strategy_id<LtcStrategy> ? 1 : 0;
}

// What Peters' combination needs of one (shading point, light): c_j, the counts n_j (times the
// multiplier) and which term is which technique.
struct PetersTerms {
  UnshadowedIntegrals unshadowed{};
  TechniqueCounts counts{0, 0};
  size_t term_of[kPetersTechniques] = {0, 1};
};

PetersTerms prepare_peters(const MethodSpec& method, const PreparedTerms& prepared,
                           const ShadingPoint& sp, const Light& light, int multiplier) {
  PetersTerms peters;
  const ProjectedSolidAngleStrategy* psa = nullptr;
  const LtcStrategy* ltc = nullptr;
  for (size_t k = 0; k < method.terms.size(); ++k) {
    int j = peters_technique(method.terms[k]);
    peters.term_of[j] = k;
    peters.counts[j] = method.terms[k].count * multiplier;
    if (j == 0) psa = std::get_if<ProjectedSolidAngleStrategy>(&prepared[k]);
    if (j == 1) ltc = std::get_if<LtcStrategy>(&prepared[k]);
  }
  if (psa && ltc) peters.unshadowed = unshadowed_polygon_shading(sp, light, *psa, *ltc);
  return peters;
}

// The densities of both techniques at a sample of technique j (its own pdf given).
TechniqueDensities peters_densities(const PetersTerms& peters, const PreparedTerms& prepared, int j,
                                    double own_pdf, const Vec3& point) {
  TechniqueDensities pdfs;
  for (int k = 0; k < kPetersTechniques; ++k)
    pdfs[k] = k == j ? own_pdf : pdf_strategy(prepared[peters.term_of[k]], point);
  return pdfs;
}

// ---- Billen & Dutré's analytic lines ------------------------------------------------------------

// Billen & Dutré's line-bd16 term: n analytic line estimates with 1D-stratified offsets and
// one direction per shading point (used by :rand), times the combination weight (1 or 1/T).
Rgb analytic_line_estimate(const PreparedStrategy& prepared, const LineQuery& query,
                           Pattern pattern, const StreamKey& stream, int n, double weight) {
  const auto* strategy = std::get_if<LineBd16Strategy>(&prepared);
  if (!strategy) return {};
  Rgb contribution = strategy->estimate_sum(pattern, stream, n, query) * (weight / double(n));
  return is_finite(contribution) ? contribution : Rgb{};
}

}  // namespace

// ---- The estimator ------------------------------------------------------------------------------

DirectLighting::DirectLighting(const Scene& scene, const MethodSpec& method)
    : scene_(&scene), method_(method) {
  check_method_runs_on(scene, method);
}

bool DirectLighting::needs_line_query() const {
  for (const MethodTerm& term : method_.terms)
    if (is_line_strategy(term.strategy)) return true;
  return false;
}

std::vector<double> DirectLighting::weights(const ShadingPoint& sp, int light_index,
                                            const Vec3& light_point, int multiplier,
                                            const LineQuery* query) const {
  const Light& light = scene_->lights[light_index];
  size_t terms = method_.terms.size();
  PreparedTerms prepared;
  for (size_t k = 0; k < terms; ++k) prepared.prepare(method_.terms[k], sp, light, query);
  LightLines lines = prepare_light_lines(method_, sp, light);
  std::vector<double> out(terms);
  if (peters_combination(method_.combine)) {
    // Per-channel weights; reported as their mean over the channels (still summing to one).
    PetersTerms peters = prepare_peters(method_, prepared, sp, light, multiplier);
    for (size_t i = 0; i < terms; ++i) {
      int j = peters_technique(method_.terms[i]);
      TechniqueDensities pdfs = peters_densities(
          peters, prepared, j, pdf_strategy(prepared[i], light_point), light_point);
      Rgb w = peters_mis_weight(peters_heuristic(method_.combine), j, pdfs, peters.unshadowed,
                                kClampedOptimalBlend, peters.counts);
      out[i] = (w.x + w.y + w.z) / 3.0;
    }
    return out;
  }
  for (size_t i = 0; i < terms; ++i) {
    // Term i's own pdf at the point, as another term would evaluate it.
    PointLines point_lines;
    double own;
    if (is_line_strategy(method_.terms[i].strategy)) {
      own = 0;
      LineAxis axis = line_axis(method_.terms[i].direction);
      if (lines.family[int(axis)] && query) {
        double t;
        const TracedLine& line =
            point_lines.get(axis, light_point, *lines.family[int(axis)], *query, t);
        own = pdf_line(prepared[i], line, t, light_point);
      }
    } else {
      own = pdf_strategy(prepared[i], light_point);
    }
    out[i] = combination_weight(method_, prepared, lines, point_lines, query, i, own, light_point,
                                multiplier);
  }
  return out;
}

Rgb DirectLighting::estimate(const ShadingPoint& sp, const Visibility& visibility, Pattern pattern,
                             const StreamKey& key, int multiplier) const {
  thread_local std::vector<Vec2> samples;
  thread_local PointLines point_lines;
  const LineQuery* query = visibility.line_query();
  if (!query && needs_line_query())
    throw std::invalid_argument("DirectLighting: method \"" + to_string(method_) +
                                "\" has line terms but the Visibility has no line query");
  Rgb total;
  const size_t term_count = method_.terms.size();
  for (size_t l = 0; l < scene_->lights.size(); ++l) {
    const Light& light = scene_->lights[l];
    if (!light_reaches_point(sp, light)) continue;

    // Prepare every term's strategy once for this shading point and light.
    PreparedTerms prepared;
    for (size_t k = 0; k < term_count; ++k) prepared.prepare(method_.terms[k], sp, light, query);
    LightLines lines = prepare_light_lines(method_, sp, light);
    const bool peters = peters_combination(method_.combine);
    PetersTerms peters_terms;
    if (peters) peters_terms = prepare_peters(method_, prepared, sp, light, multiplier);

    Rgb light_sum;
    for (size_t i = 0; i < term_count; ++i) {
      const MethodTerm& term = method_.terms[i];
      const bool line_term = is_line_strategy(term.strategy);
      const LineAxis axis = line_axis(term.direction);
      const int n = term.count * multiplier;
      StreamKey stream = key;
      stream.stream = light_term_stream(int(l), int(i));
      if (strategy_info(term.strategy).family == StrategyFamily::AnalyticLine) {
        light_sum += analytic_line_estimate(prepared[i], *query, pattern, stream, n,
                                            average_weight(term_count));
        continue;
      }
      samples.resize(n);
      generate_2d(pattern, stream, strata_aspect(term, light), samples);

      for (int j = 0; j < n; ++j) {
        point_lines.reset();
        std::optional<LightPoint> x;
        if (line_term) {
          x = sample_line(prepared[i], samples[j], point_lines.slot(axis),
                          point_lines.slot_t(axis));
          point_lines.mark(axis);
        } else {
          x = sample_strategy(prepared[i], samples[j]);
        }
        if (!x || !(x->pdf_area > 0)) continue;
        Rgb f = unshadowed_integrand(sp, light, x->position);
        if (is_black(f)) continue;
        // A line sample's point is visible by construction; other samples take a shadow ray
        // before any line pdf is evaluated (only visible points need one).
        if (!line_term && visibility.occluded(sp.position, sp.normal, x->position)) continue;

        if (peters) {
          int technique = peters_technique(term);
          TechniqueSample s{
              f, peters_densities(peters_terms, prepared, technique, x->pdf_area, x->position)};
          light_sum += peters_sample_contribution(technique, s, peters_terms.unshadowed,
                                                  peters_heuristic(method_.combine),
                                                  kClampedOptimalBlend, peters_terms.counts) /
                       double(n);
          continue;
        }
        double weight = combination_weight(method_, prepared, lines, point_lines, query, i,
                                           x->pdf_area, x->position, multiplier);
        if (weight == 0) continue;
        Rgb contribution = f * (weight / (double(n) * x->pdf_area));
        if (is_finite(contribution)) light_sum += contribution;
      }
    }
    total += light_sum;
  }
  return total;
}

}  // namespace penumbra
