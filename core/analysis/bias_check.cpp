// The block z-test of a method's runs against a reference (see the header).

#include "core/analysis/bias_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace penumbra {

namespace {

void check_size(const Image& image, int width, int height, const std::string& what) {
  if (image.width != width || image.height != height)
    throw std::invalid_argument(what + " is " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + ", the reference " +
                                std::to_string(width) + "x" + std::to_string(height));
}

const char* channel_name(int c) {
  static const char* names[3] = {"red", "green", "blue"};
  return names[c];
}

}  // namespace

double normal_two_sided_tail(double sigma) {
  return std::erfc(sigma / std::sqrt(2.0));
}

BiasCheckResult check_bias(const Film& reference, const Image* exact_fraction,
                           std::span<const Film> runs, const BiasCheckOptions& options) {
  const int width = reference.color.width, height = reference.color.height;
  if (width <= 0 || height <= 0) throw std::invalid_argument("the reference image is empty");
  check_size(reference.variance, width, height, "the reference's variance layer");
  if (runs.size() < 2)
    throw std::invalid_argument("a bias check needs at least 2 runs, got " +
                                std::to_string(runs.size()));
  if (options.block_size < 1) throw std::invalid_argument("the block size must be at least 1");
  if (!(options.sigma > 0)) throw std::invalid_argument("the threshold must be positive");
  for (size_t j = 0; j < runs.size(); ++j) {
    check_size(runs[j].color, width, height, "run " + std::to_string(j));
    check_size(runs[j].variance, width, height, "run " + std::to_string(j) + "'s variance layer");
  }
  const bool with_fraction = exact_fraction && exact_fraction->width > 0;
  if (with_fraction) check_size(*exact_fraction, width, height, "the exact-fraction layer");

  BiasCheckResult result;
  result.runs = int(runs.size());
  result.width = width;
  result.height = height;
  result.block_size = options.block_size;
  result.sigma = options.sigma;
  result.per_test_false_alarm = normal_two_sided_tail(options.sigma);
  std::vector<double> relative_errors;
  const double k = double(runs.size());
  const int b = options.block_size;
  std::vector<double> run_means(runs.size());
  for (int y0 = 0; y0 < height; y0 += b)
    for (int x0 = 0; x0 < width; x0 += b) {
      const int x1 = std::min(x0 + b, width), y1 = std::min(y0 + b, height);
      const double n = double(x1 - x0) * (y1 - y0);
      ++result.blocks;
      double fraction = -1;
      if (with_fraction) {
        double sum = 0;
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) sum += exact_fraction->at(x, y).x;
        fraction = sum / n;
      }
      for (int c = 0; c < 3; ++c) {
        auto value = [c](const Image& image, int x, int y) {
          return double(image.rgb[(size_t(y) * image.width + x) * 3 + c]);
        };
        double ref_sum = 0, ref_var = 0;
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) {
            ref_sum += value(reference.color, x, y);
            ref_var += value(reference.variance, x, y);
          }
        double within = 0, mean = 0;
        bool any_signal = ref_sum != 0;
        for (size_t j = 0; j < runs.size(); ++j) {
          double sum = 0, var = 0;
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
              sum += value(runs[j].color, x, y);
              var += value(runs[j].variance, x, y);
            }
          run_means[j] = sum / n;
          within += var / (n * n);
          mean += run_means[j];
          any_signal = any_signal || sum != 0;
        }
        if (!any_signal) continue;
        mean /= k;
        double spread = 0;
        for (double m : run_means) spread += (m - mean) * (m - mean);
        const double between = spread / (k - 1) / k;  // variance of the mean over runs
        within /= k * k;
        const double r = ref_sum / n;
        const double floor = 1e-6 * std::abs(r) + 1e-9;
        const double se = std::sqrt(std::max(within, between) + ref_var / (n * n) + floor * floor);
        BlockTest test;
        test.x0 = x0;
        test.y0 = y0;
        test.x1 = x1;
        test.y1 = y1;
        test.channel = c;
        test.estimate = mean;
        test.reference = r;
        test.standard_error = se;
        test.z = (mean - r) / se;
        test.exact_share = fraction;
        if (within == 0 && between == 0 && std::abs(mean - r) > floor) {
          // No noise in the runs: their spread says nothing about their error.
          test.z = 0;
          result.inconclusive.push_back(test);
          continue;
        }
        ++result.tests;
        if (r != 0) relative_errors.push_back(se / std::abs(r));
        if (result.tests == 1 || std::abs(test.z) > std::abs(result.worst.z)) result.worst = test;
        if (std::abs(test.z) > options.sigma) result.flagged.push_back(test);
      }
    }
  std::sort(result.flagged.begin(), result.flagged.end(),
            [](const BlockTest& a, const BlockTest& b) { return std::abs(a.z) > std::abs(b.z); });
  result.family_false_alarm_bound = std::min(1.0, result.tests * result.per_test_false_alarm);
  if (!relative_errors.empty()) {
    auto middle = relative_errors.begin() + relative_errors.size() / 2;
    std::nth_element(relative_errors.begin(), middle, relative_errors.end());
    result.median_relative_error = *middle;
  }
  return result;
}

namespace {

std::string describe(const BlockTest& t) {
  char text[320];
  const double relative = t.reference != 0 ? (t.estimate - t.reference) / t.reference : 0;
  std::snprintf(text, sizeof text,
                "block [%d,%d)x[%d,%d) %s: %.6g against %.6g (%+.2f%%), z = %+.2f", t.x0, t.x1,
                t.y0, t.y1, channel_name(t.channel), t.estimate, t.reference, 100 * relative, t.z);
  std::string out = text;
  if (t.exact_share >= 0) {
    std::snprintf(text, sizeof text, ", reference %.0f%% exact", 100 * t.exact_share);
    out += text;
  }
  return out;
}

}  // namespace

std::string bias_check_text(const BiasCheckResult& r, const std::string& what, int max_listed) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line,
                "%s: %d runs, %dx%d pixels in %d blocks of %dx%d, %d block-channel tests\n",
                what.c_str(), r.runs, r.width, r.height, r.blocks, r.block_size, r.block_size,
                r.tests);
  out += line;
  std::snprintf(line, sizeof line,
                "resolution: median standard error %.3g%% of the block's value: a bias of about "
                "%.2g%% in a typical block would be flagged\n",
                100 * r.median_relative_error, 100 * r.sigma * r.median_relative_error);
  out += line;
  if (r.tests > 0) out += "largest |z|: " + describe(r.worst) + "\n";
  std::snprintf(line, sizeof line,
                "an unbiased method shows a block beyond %.3g sigma with probability at most "
                "%d x %.2g = %.2g (Bonferroni over the tests; block means close to normal)\n",
                r.sigma, r.tests, r.per_test_false_alarm, r.family_false_alarm_bound);
  out += line;
  if (!r.inconclusive.empty()) {
    std::snprintf(
        line, sizeof line,
        "inconclusive: %zu block-channel tests whose runs have no noise at all but differ "
        "from the reference (e.g. no sample found the light): raise the budget; first: ",
        r.inconclusive.size());
    out += line + describe(r.inconclusive[0]) + "\n";
  }
  if (r.passed()) {
    std::snprintf(line, sizeof line, "PASS: no block beyond %.3g sigma\n", r.sigma);
    out += line;
    return out;
  }
  std::snprintf(line, sizeof line,
                "FAIL: %zu block-channel tests beyond %.3g sigma: the method is biased here (or "
                "the reference is)\n",
                r.flagged.size(), r.sigma);
  out += line;
  for (size_t i = 0; i < r.flagged.size() && int(i) < max_listed; ++i)
    out += "  " + describe(r.flagged[i]) + "\n";
  if (int(r.flagged.size()) > max_listed)
    out += "  ... and " + std::to_string(r.flagged.size() - size_t(max_listed)) + " more\n";
  return out;
}

std::string bias_check_json(const BiasCheckResult& r, const std::string& scene,
                            const std::string& method) {
  auto block = [](const BlockTest& t) {
    nlohmann::json j = {{"rect", {t.x0, t.y0, t.x1, t.y1}},
                        {"channel", channel_name(t.channel)},
                        {"estimate", t.estimate},
                        {"reference", t.reference},
                        {"standard_error", t.standard_error},
                        {"z", t.z}};
    if (t.exact_share >= 0) j["exact_share"] = t.exact_share;
    return j;
  };
  nlohmann::json out = {{"format", "penumbra/verify-result@1"},
                        {"scene", scene},
                        {"method", method},
                        {"passed", r.passed()},
                        {"runs", r.runs},
                        {"resolution", {r.width, r.height}},
                        {"block_size", r.block_size},
                        {"sigma", r.sigma},
                        {"blocks", r.blocks},
                        {"tests", r.tests},
                        {"per_test_false_alarm", r.per_test_false_alarm},
                        {"family_false_alarm_bound", r.family_false_alarm_bound},
                        {"median_relative_error", r.median_relative_error},
                        {"flagged", nlohmann::json::array()}};
  if (r.tests > 0) out["worst"] = block(r.worst);
  for (const BlockTest& t : r.flagged) out["flagged"].push_back(block(t));
  out["inconclusive"] = nlohmann::json::array();
  for (const BlockTest& t : r.inconclusive) out["inconclusive"].push_back(block(t));
  return out.dump(2);
}

}  // namespace penumbra
