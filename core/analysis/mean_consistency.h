#pragma once
// Whether an estimator's mean agrees with a reference value when both are known only from a
// finite number of independent estimates (the stability table's `!`, core/analysis/stability.h).
//
// The statistic is Welch's t: t = (mean - reference) / sqrt(se^2 + se_ref^2), with the
// Welch-Satterthwaite degrees of freedom
//   nu = (se^2 + se_ref^2)^2 / (se^4 / (n - 1) + se_ref^4 / (m - 1))
// (an exact reference, m = 0 or se_ref = 0: nu = n - 1, Student's one-sample t). Under the null
// hypothesis of an unbiased estimator (normal estimates) t follows Student's t with nu degrees of
// freedom, so the two-sided p-value 2 (1 - F_nu(|t|)) has the same false-alarm rate at every trial
// count. A fixed threshold on |t| (say 5 standard errors) does not: with 16 trials the standard
// error is itself estimated from 16 values and |t_15| > 5 is 276 times likelier than |z| > 5.
//
// kFiveSigma is the false-alarm rate of a 5-standard-error normal test: thresholds at that rate
// are 5 standard errors for many trials and grow as the trials get fewer (8.27 at 16 trials).

namespace penumbra {

// Two-sided normal tail beyond 5 standard deviations: 2 (1 - Phi(5)).
inline constexpr double kFiveSigmaFalseAlarmRate = 5.733031437583878e-7;

struct MeanConsistency {
  double t = 0;          // Welch's t (signed); +-infinity for a difference with zero errors
  double dof = 0;        // Welch-Satterthwaite degrees of freedom
  double p_value = 1;    // two-sided
  double threshold = 0;  // |t| beyond which the test fails at the rate asked for
  bool consistent = true;
};

// `trials` >= 2 estimates gave `mean` with standard error `standard_error`; the reference is
// `reference` +- `reference_error` from `reference_trials` estimates (0 or an error of 0: exact).
// Inconsistent when the p-value is below `false_alarm_rate` (in (0, 1)). Throws
// std::invalid_argument for fewer than two trials or a rate outside (0, 1).
MeanConsistency mean_consistency(double mean, double standard_error, int trials, double reference,
                                 double reference_error, int reference_trials,
                                 double false_alarm_rate = kFiveSigmaFalseAlarmRate);

}  // namespace penumbra
