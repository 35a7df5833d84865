#include "core/lines/bd16_estimator.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

struct ChordExtent {
  double low = 0, high = 0;  // coordinates along the direction
  bool found = false;
};

// Where the line at offset w crosses the polygon's boundary (convex: one interval).
ChordExtent chord_extent(const std::vector<double>& along, const std::vector<double>& offsets,
                         double w) {
  ChordExtent extent;
  size_t size = along.size();
  auto include = [&extent](double z) {
    if (!extent.found) {
      extent.low = extent.high = z;
      extent.found = true;
    } else {
      extent.low = std::min(extent.low, z);
      extent.high = std::max(extent.high, z);
    }
  };
  for (size_t i = 0; i < size; ++i) {
    size_t j = (i + 1) % size;
    double wi = offsets[i], wj = offsets[j];
    if (wi == wj) {
      if (w == wi) {
        include(along[i]);
        include(along[j]);
      }
    } else if ((w - wi) * (w - wj) <= 0) {
      double fraction = std::clamp((w - wi) / (wj - wi), 0.0, 1.0);
      include(along[i] + fraction * (along[j] - along[i]));
    }
  }
  return extent;
}

}  // namespace

LineOffsetDistribution::LineOffsetDistribution(const Light& light, const Vec3& direction) {
  const std::vector<Vec3>& vertices = light.vertices;
  if (vertices.size() < 3) return;
  Vec3 in_plane = direction - dot(direction, light.normal) * light.normal;
  double in_plane_length = length(in_plane);
  if (!(in_plane_length > 0) || !std::isfinite(in_plane_length)) return;
  direction_ = in_plane / in_plane_length;
  across_ = normalize(cross_accurate(light.normal, direction_));
  origin_ = vertices[0];
  along_.resize(vertices.size());
  offsets_.resize(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    Vec3 relative = vertices[i] - origin_;
    along_[i] = dot(relative, direction_);
    offsets_[i] = dot(relative, across_);
  }
  breakpoints_ = offsets_;
  std::sort(breakpoints_.begin(), breakpoints_.end());
  breakpoints_.erase(std::unique(breakpoints_.begin(), breakpoints_.end()), breakpoints_.end());
  chords_.resize(breakpoints_.size());
  for (size_t k = 0; k < breakpoints_.size(); ++k) {
    ChordExtent extent = chord_extent(along_, offsets_, breakpoints_[k]);
    chords_[k] = extent.found ? extent.high - extent.low : 0.0;
  }
  cumulative_.assign(breakpoints_.size(), 0.0);
  for (size_t k = 1; k < breakpoints_.size(); ++k) {
    double width = breakpoints_[k] - breakpoints_[k - 1];
    cumulative_[k] = cumulative_[k - 1] + 0.5 * (chords_[k - 1] + chords_[k]) * width;
  }
  total_ = cumulative_.empty() ? 0.0 : cumulative_.back();
  if (!(total_ > 0) || !std::isfinite(total_)) {
    breakpoints_.clear();
    total_ = 0;
  }
}

std::optional<LineOffsetDistribution::Line> LineOffsetDistribution::chord(double offset) const {
  if (breakpoints_.size() < 2 || !(offset >= breakpoints_.front()) ||
      !(offset <= breakpoints_.back())) {
    return std::nullopt;
  }
  ChordExtent extent = chord_extent(along_, offsets_, offset);
  if (!extent.found) return std::nullopt;
  Line line;
  line.offset = offset;
  line.pdf = (extent.high - extent.low) / total_;
  Vec3 base = origin_ + offset * across_;
  line.a = base + extent.low * direction_;
  line.b = base + extent.high * direction_;
  return line;
}

std::optional<LineOffsetDistribution::Line> LineOffsetDistribution::sample(double u) const {
  if (breakpoints_.size() < 2) return std::nullopt;
  double target = std::clamp(u, 0.0, 1.0) * total_;
  // The piece [k, k+1] with cumulative_[k] <= target < cumulative_[k+1]; zero-area pieces are
  // never chosen (upper_bound skips equal cumulative values).
  size_t pieces = breakpoints_.size() - 1;
  size_t k = static_cast<size_t>(std::upper_bound(cumulative_.begin(), cumulative_.end(), target) -
                                 cumulative_.begin());
  k = (k == 0) ? 0 : k - 1;
  if (k >= pieces) {
    // target == total: the last piece with area.
    k = pieces - 1;
    while (k > 0 && !(cumulative_[k + 1] > cumulative_[k])) --k;
  }
  double piece_area = cumulative_[k + 1] - cumulative_[k];
  if (!(piece_area > 0)) return std::nullopt;
  double xi = std::clamp((target - cumulative_[k]) / piece_area, 0.0, 1.0);
  double l0 = chords_[k], l1 = chords_[k + 1];
  // Fraction s of the piece's width: l0 s + (l1 - l0) s^2 / 2 = xi (l0 + l1) / 2.
  double denominator = l0 + std::sqrt(std::max(0.0, l0 * l0 + xi * (l1 * l1 - l0 * l0)));
  double s = denominator > 0 ? std::clamp(xi * (l0 + l1) / denominator, 0.0, 1.0) : xi;
  double offset = breakpoints_[k] + s * (breakpoints_[k + 1] - breakpoints_[k]);
  offset = std::clamp(offset, breakpoints_[k], breakpoints_[k + 1]);
  return chord(offset);
}

double LineOffsetDistribution::pdf(double offset) const {
  std::optional<Line> line = chord(offset);
  return line ? line->pdf : 0.0;
}

double pdf_of_offset(const Light& light, const Vec3& direction, double offset) {
  return LineOffsetDistribution(light, direction).pdf(offset);
}

Vec3 bd16_line_direction(const Light& light, Bd16Direction mode, const Vec2& direction_u) {
  const std::vector<Vec3>& vertices = light.vertices;
  bool quad = light.type == LightType::Quad;
  Vec3 first = quad ? light.edge1 : vertices[1] - vertices[0];
  if (mode == Bd16Direction::U) return normalize(first);
  if (mode == Bd16Direction::V) {
    return normalize(quad ? light.edge2 : vertices.back() - vertices[0]);
  }
  Vec3 e1 = normalize(first - dot(first, light.normal) * light.normal);
  Vec3 e2 = cross(light.normal, e1);
  double angle = kPi * direction_u.x;
  return std::cos(angle) * e1 + std::sin(angle) * e2;
}

std::optional<std::string> Bd16LineSampler::unsupported(const Light& light,
                                                        const Material& material) {
  if (light.type == LightType::Disk) {
    return std::string(
        "line-bd16: disk lights are not supported (line offsets are sampled for polygonal "
        "lights only: quads, triangles and convex polygons)");
  }
  if (light.vertices.size() < 3) {
    return std::string("line-bd16: the light has fewer than 3 vertices");
  }
  if (light.profile != ProfileType::Constant) {
    return std::string(
        "line-bd16: gaussian light profiles are not supported (the closed-form line integrals "
        "assume constant radiance)");
  }
  if (material.type != MaterialType::Lambert && material.type != MaterialType::Phong) {
    const char* kind = material.type == MaterialType::Ggx ? "ggx" : "a pbrt-v3 material";
    return "line-bd16: material '" + material.name + "' is " + kind +
           "; line-bd16 integrates lines in closed form for lambert and phong only (a pbrt-v3 "
           "matte is lambert when its Kd is constant, without sigma or bump)";
  }
  return std::nullopt;
}

Bd16LineSampler::Bd16LineSampler(const Light& light, const Material& material, const Vec3& x,
                                 const Vec3& n, const Vec3& wo, Bd16Direction mode)
    : light_(&light), receiver_(make_line_receiver(material, x, n, wo)), mode_(mode) {
  facing_ = light.vertices.size() >= 3 && dot(light.normal, x - light.vertices[0]) > 0 &&
            dot(n, wo) > 0 && is_finite(x) && is_finite(n) && is_finite(wo);
  if (facing_ && mode != Bd16Direction::Random) {
    fixed_ = LineOffsetDistribution(light, bd16_line_direction(light, mode, Vec2{0, 0}));
  }
}

const LineOffsetDistribution& Bd16LineSampler::distribution_for(const Vec2& direction_u) const {
  if (mode_ != Bd16Direction::Random) return fixed_;
  if (direction_u.x != random_key_) {
    random_ = LineOffsetDistribution(*light_, bd16_line_direction(*light_, mode_, direction_u));
    random_key_ = direction_u.x;
  }
  return random_;
}

Rgb Bd16LineSampler::estimate_with(double offset_u, const Vec2& direction_u,
                                   const LineQuery* query) const {
  if (!facing_) return {0, 0, 0};
  std::optional<LineOffsetDistribution::Line> line = distribution_for(direction_u).sample(offset_u);
  if (!line || !(line->pdf > 0)) return {0, 0, 0};
  LineIntegrator integrator(receiver_, line->a, line->b, light_->normal);
  if (integrator.zero()) return {0, 0, 0};
  Rgb sum{0, 0, 0};
  if (query) {
    IntervalList visible;
    query->visible_intervals(receiver_.x, line->a, line->b, visible);
    for (const Interval& piece : visible) {
      sum += integrator.radiance(light_->radiance, piece.lo, piece.hi);
    }
  } else {
    sum = integrator.radiance(light_->radiance, 0.0, 1.0);
  }
  Rgb estimate = sum / line->pdf;
  if (!is_finite(estimate)) return {0, 0, 0};
  return estimate;
}

Rgb Bd16LineSampler::estimate(double offset_u, const Vec2& direction_u,
                              const LineQuery& query) const {
  return estimate_with(offset_u, direction_u, &query);
}

Rgb Bd16LineSampler::estimate_unoccluded(double offset_u, const Vec2& direction_u) const {
  return estimate_with(offset_u, direction_u, nullptr);
}

}  // namespace penumbra
