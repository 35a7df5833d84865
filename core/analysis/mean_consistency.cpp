#include "core/analysis/mean_consistency.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/report/significance.h"

namespace penumbra {

MeanConsistency mean_consistency(double mean, double standard_error, int trials, double reference,
                                 double reference_error, int reference_trials,
                                 double false_alarm_rate) {
  if (trials < 2) throw std::invalid_argument("mean_consistency: needs at least two trials");
  if (!(false_alarm_rate > 0 && false_alarm_rate < 1))
    throw std::invalid_argument("mean_consistency: the false-alarm rate must lie in (0, 1)");
  const bool exact = reference_trials < 2 || !(reference_error > 0);
  const double a = standard_error * standard_error;
  const double b = exact ? 0.0 : reference_error * reference_error;
  MeanConsistency result;
  result.dof = double(trials - 1);
  if (!exact && a + b > 0) {
    const double denominator = a * a / double(trials - 1) + b * b / double(reference_trials - 1);
    if (denominator > 0) result.dof = (a + b) * (a + b) / denominator;
  }
  result.threshold = student_t_quantile(1 - false_alarm_rate / 2, result.dof);
  const double difference = mean - reference;
  const double scale = std::sqrt(a + b);
  if (scale > 0) {
    result.t = difference / scale;
  } else {
    result.t =
        difference == 0 ? 0.0 : std::copysign(std::numeric_limits<double>::infinity(), difference);
  }
  if (std::isinf(result.t))
    result.p_value = 0;
  else
    result.p_value = 2 * (1 - student_t_cdf(std::abs(result.t), result.dof));
  result.consistent = !(std::isnan(difference)) && result.p_value >= false_alarm_rate;
  return result;
}

}  // namespace penumbra
