#include "core/method/method_check.h"

#include <string>
#include <string_view>

#include "core/strategies/light_checks.h"
#include "core/strategies/registered_strategies.h"

namespace penumbra {

namespace {

[[noreturn]] void refuse(const MethodSpec& method, const std::string& why) {
  throw FormatError("method", "\"" + to_string(method) + "\": " + why);
}

}  // namespace

void check_method_runs_on(const Scene& scene, const MethodSpec& method) {
  // Every term: what its family allows in a combination, then the registry row's own check.
  for (const MethodTerm& term : method.terms) {
    const StrategyInfo& info = strategy_info(term.strategy);
    // An analytic line strategy gives an estimate per line and no density at a point: no MIS.
    if (info.family == StrategyFamily::AnalyticLine && method.terms.size() > 1 &&
        method.combine != Combine::Avg)
      refuse(method, "strategy \"" + std::string(info.name) +
                         "\" integrates each line analytically and has no pdf at a point, so it "
                         "cannot be combined by \"" +
                         std::string(combine_name(method.combine)) +
                         "\": use it alone or with /avg");
    if (auto why = strategy_refusal(term.strategy, scene, term.direction)) refuse(method, *why);
  }
  switch (method.combine) {
    case Combine::Balance:
    case Combine::Power:
    case Combine::Avg:
      break;
    case Combine::Smooth:
    case Combine::SmoothFixed:
      if (auto why = first_light_not_quad(
              scene, "combination \"" + std::string(combine_name(method.combine)) +
                         "\" smooths the BSDF pdf over a quad's (u, v) (Salesin & Jarosz Eq. 23)"))
        refuse(method, *why);
      break;
    case Combine::Weighted:
    case Combine::ClampedOptimal: {
      // Peters' heuristics weight a diffuse (psa) and a specular (ltc) technique by their
      // unshadowed integrals: exactly one term of each.
      std::string name(combine_name(method.combine));
      bool one_psa_one_ltc =
          method.terms.size() == 2 && method.terms[0].strategy != method.terms[1].strategy;
      for (const MethodTerm& term : method.terms)
        if (term.strategy != strategy_id<ProjectedSolidAngleStrategy> &&
            term.strategy != strategy_id<LtcStrategy>)
          one_psa_one_ltc = false;
      if (!one_psa_one_ltc)
        refuse(method, "combination \"" + name +
                           "\" (Peters 2021 Sec. 4.2-4.3) combines one psa term and one ltc term, "
                           "e.g. \"psa+ltc/" +
                           name + "\" or \"2*psa+ltc/" + name + "\"");
      for (size_t l = 0; l < scene.lights.size(); ++l)
        if (scene.lights[l].type == LightType::Disk)
          refuse(method, "combination \"" + name +
                             "\" needs polygon or quad lights (psa and ltc sample polygons); "
                             "light " +
                             std::to_string(l) + " is a disk");
      break;
    }
  }
}

}  // namespace penumbra
