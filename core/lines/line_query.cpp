#include "core/lines/line_query.h"

#include <embree3/rtcore.h>
#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

#include "core/scene/scene.h"

namespace penumbra {

namespace {

// ---------------------------------------------------------------------------------------------
// Build: Embree's rtcBuildBVH calls these to make a tree of our temporary nodes (allocated from
// Embree's thread-local allocator, freed with the RTCBVH), which we then flatten.

struct BuildNode {
  bool is_leaf;
};

struct BuildInner {
  BuildNode base{false};
  unsigned child_count = 0;
  BuildNode* children[LineQuery::kWidth] = {};
  RTCBounds bounds[LineQuery::kWidth] = {};
};

struct BuildLeaf {
  BuildNode base{true};
  unsigned triangle_count = 0;
  uint32_t triangles[RTC_BUILD_MAX_PRIMITIVES_PER_LEAF] = {};
};

void* create_inner(RTCThreadLocalAllocator allocator, unsigned int, void*) {
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(BuildInner), 16);
  return new (memory) BuildInner();
}

void set_children(void* node, void** children, unsigned int child_count, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  inner->child_count = child_count;
  for (unsigned i = 0; i < child_count; ++i)
    inner->children[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned int child_count, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned i = 0; i < child_count; ++i) inner->bounds[i] = *bounds[i];
}

// What the callbacks share: the triangles (for spatial splits) and a flag set from Embree's
// build threads when a leaf is larger than asked (Embree promises not to).
struct BuildStatus {
  std::atomic<bool> oversized_leaf{false};
  const std::vector<OccluderTriangle>* occluders = nullptr;
  const std::vector<uint32_t>* reference_triangle = nullptr;  // primID -> index in occluders
  double build_scale = 1;  // primitive boxes are the triangles' boxes times this power of two
};

void* create_leaf(RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* primitives,
                  size_t primitive_count, void* user) {
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(BuildLeaf), 16);
  auto* leaf = new (memory) BuildLeaf();
  if (primitive_count > RTC_BUILD_MAX_PRIMITIVES_PER_LEAF) {
    static_cast<BuildStatus*>(user)->oversized_leaf = true;
    primitive_count = RTC_BUILD_MAX_PRIMITIVES_PER_LEAF;
  }
  leaf->triangle_count = static_cast<unsigned>(primitive_count);
  for (size_t i = 0; i < primitive_count; ++i) leaf->triangles[i] = primitives[i].primID;
  return leaf;
}

// Float bounds that contain the double value.
float round_down(double value) {
  float f = static_cast<float>(value);
  return static_cast<double>(f) > value ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                                        : f;
}
float round_up(double value) {
  float f = static_cast<float>(value);
  return static_cast<double>(f) < value ? std::nextafter(f, std::numeric_limits<float>::infinity())
                                        : f;
}

// Spatial splits (SBVH, HIGH quality): the boxes of the parts of a triangle on either side of
// the plane coordinate[dimension] = position, within the box of the primitive (itself perhaps a
// part of the triangle already). The parts' corners are the triangle's vertices on that side
// and its edges' crossings with the plane, computed in double and rounded outwards, so each
// box holds its part of the triangle: the node tests stay conservative.
void split_primitive(const RTCBuildPrimitive* primitive, unsigned int dimension, float position,
                     RTCBounds* left_bounds, RTCBounds* right_bounds, void* user) {
  const auto* status = static_cast<const BuildStatus*>(user);
  const OccluderTriangle& triangle =
      (*status->occluders)[(*status->reference_triangle)[primitive->primID]];
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  double v[3][3];
  for (int k = 0; k < 3; ++k)
    for (int axis = 0; axis < 3; ++axis)
      v[k][axis] = static_cast<double>(triangle.coordinate[axis][k]) * status->build_scale;
  double lower[2][3], upper[2][3];  // [side][axis]: side 0 below the plane, 1 above
  for (int side = 0; side < 2; ++side)
    for (int axis = 0; axis < 3; ++axis) {
      lower[side][axis] = kInfinity;
      upper[side][axis] = -kInfinity;
    }
  auto add = [&](int side, const double point[3]) {
    for (int axis = 0; axis < 3; ++axis) {
      lower[side][axis] = std::min(lower[side][axis], point[axis]);
      upper[side][axis] = std::max(upper[side][axis], point[axis]);
    }
  };
  const double plane = position;
  for (int k = 0; k < 3; ++k) {
    if (v[k][dimension] <= plane) add(0, v[k]);
    if (v[k][dimension] >= plane) add(1, v[k]);
  }
  static constexpr int kEdges[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (const auto& edge : kEdges) {
    const double* p = v[edge[0]];
    const double* q = v[edge[1]];
    if (!((p[dimension] < plane && q[dimension] > plane) ||
          (p[dimension] > plane && q[dimension] < plane)))
      continue;
    const double f = (plane - p[dimension]) / (q[dimension] - p[dimension]);
    double crossing[3];
    for (int axis = 0; axis < 3; ++axis) crossing[axis] = p[axis] + f * (q[axis] - p[axis]);
    crossing[dimension] = plane;
    add(0, crossing);
    add(1, crossing);
  }
  // Float boxes rounded outwards, within the primitive's box and on their side of the plane.
  // A side the triangle does not reach inside the primitive's box collapses to a point there.
  const float box_lower[3] = {primitive->lower_x, primitive->lower_y, primitive->lower_z};
  const float box_upper[3] = {primitive->upper_x, primitive->upper_y, primitive->upper_z};
  RTCBounds* out[2] = {left_bounds, right_bounds};
  for (int side = 0; side < 2; ++side) {
    float lo[3], hi[3];
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::max(round_down(lower[side][axis]), box_lower[axis]);
      hi[axis] = std::min(round_up(upper[side][axis]), box_upper[axis]);
    }
    if (side == 0) hi[dimension] = std::min(hi[dimension], position);
    if (side == 1) lo[dimension] = std::max(lo[dimension], position);
    for (int axis = 0; axis < 3; ++axis) {
      if (lo[axis] <= hi[axis]) continue;
      lo[axis] = hi[axis] = axis == static_cast<int>(dimension)
                                ? std::clamp(position, box_lower[axis], box_upper[axis])
                                : box_lower[axis];
    }
    *out[side] = RTCBounds{lo[0], lo[1], lo[2], 0, hi[0], hi[1], hi[2], 0};
  }
}

// Pre-splitting (before the build, at every quality): a long slanted triangle's box is mostly
// empty, so every shadow triangle that passes anywhere near it reaches its leaf. Such triangles
// enter the build as several references, each with the box of one piece of the triangle (the
// triangle clipped to a half-space, recursively at the middle of the piece's longest axis); the
// leaves still hold the whole triangle, so the exact test and its watertightness are untouched
// and a triangle reached through two pieces cuts the same interval twice (subtracting is
// idempotent). Each piece's box contains that piece: the clipped corners are computed in double
// (relative error ~1e-16) and the float box is rounded outwards and then widened by one float
// ulp, far more than that error.
struct SplitPolygon {
  static constexpr int kCapacity = 3 + 16;  // a triangle clipped by at most 16 planes
  int count = 0;
  double v[kCapacity][3];
};

struct PreSplitLimits {
  int max_depth = 10;            // at most 2^max_depth pieces per triangle
  double min_extent = 0;         // pieces no longer than this along any axis are kept
  double max_box_to_area = 4.0;  // kept when the box's half surface area <= this x area
};

void polygon_bounds(const SplitPolygon& polygon, double lower[3], double upper[3]) {
  for (int axis = 0; axis < 3; ++axis) lower[axis] = upper[axis] = polygon.v[0][axis];
  for (int k = 1; k < polygon.count; ++k)
    for (int axis = 0; axis < 3; ++axis) {
      lower[axis] = std::min(lower[axis], polygon.v[k][axis]);
      upper[axis] = std::max(upper[axis], polygon.v[k][axis]);
    }
}

double polygon_area(const SplitPolygon& polygon) {
  Vec3 sum(0, 0, 0);
  const Vec3 origin(polygon.v[0][0], polygon.v[0][1], polygon.v[0][2]);
  for (int k = 1; k + 1 < polygon.count; ++k) {
    const Vec3 p(polygon.v[k][0], polygon.v[k][1], polygon.v[k][2]);
    const Vec3 q(polygon.v[k + 1][0], polygon.v[k + 1][1], polygon.v[k + 1][2]);
    sum += cross(p - origin, q - origin);
  }
  return 0.5 * length(sum);
}

// Sutherland-Hodgman against coordinate[axis] <= plane (below) and >= plane (above); corners on
// the plane go to both sides, crossings get the plane's coordinate exactly.
void clip_polygon(const SplitPolygon& in, int axis, double plane, SplitPolygon& below,
                  SplitPolygon& above) {
  below.count = above.count = 0;
  auto add = [](SplitPolygon& polygon, const double* point) {
    if (polygon.count == SplitPolygon::kCapacity) return;  // unreachable: depth is bounded
    for (int k = 0; k < 3; ++k) polygon.v[polygon.count][k] = point[k];
    ++polygon.count;
  };
  for (int k = 0; k < in.count; ++k) {
    const double* p = in.v[k];
    const double* q = in.v[(k + 1) % in.count];
    if (p[axis] <= plane) add(below, p);
    if (p[axis] >= plane) add(above, p);
    if ((p[axis] < plane && q[axis] > plane) || (p[axis] > plane && q[axis] < plane)) {
      const double f = (plane - p[axis]) / (q[axis] - p[axis]);
      double crossing[3];
      for (int c = 0; c < 3; ++c) crossing[c] = p[c] + f * (q[c] - p[c]);
      crossing[axis] = plane;
      add(below, crossing);
      add(above, crossing);
    }
  }
}

// The float box of a piece (see above), within `limit` (the whole triangle's float box).
RTCBounds piece_box(const double lower[3], const double upper[3], const RTCBuildPrimitive& limit) {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  float lo[3], hi[3];
  const float limit_lower[3] = {limit.lower_x, limit.lower_y, limit.lower_z};
  const float limit_upper[3] = {limit.upper_x, limit.upper_y, limit.upper_z};
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = std::max(std::nextafter(round_down(lower[axis]), -kInfinity), limit_lower[axis]);
    hi[axis] = std::min(std::nextafter(round_up(upper[axis]), kInfinity), limit_upper[axis]);
  }
  return RTCBounds{lo[0], lo[1], lo[2], 0, hi[0], hi[1], hi[2], 0};
}

// Appends the boxes of the pieces of `polygon` (a triangle or a part of one) to `boxes`.
void split_into_pieces(const SplitPolygon& polygon, int depth, const PreSplitLimits& limits,
                       const RTCBuildPrimitive& limit, std::vector<RTCBounds>& boxes) {
  double lower[3], upper[3];
  polygon_bounds(polygon, lower, upper);
  const double extent[3] = {upper[0] - lower[0], upper[1] - lower[1], upper[2] - lower[2]};
  const int axis =
      extent[0] >= extent[1] ? (extent[0] >= extent[2] ? 0 : 2) : (extent[1] >= extent[2] ? 1 : 2);
  const double half_area = extent[0] * extent[1] + extent[1] * extent[2] + extent[2] * extent[0];
  if (depth >= limits.max_depth || !(extent[axis] > limits.min_extent) ||
      half_area <= limits.max_box_to_area * polygon_area(polygon)) {
    boxes.push_back(piece_box(lower, upper, limit));
    return;
  }
  const double plane = 0.5 * (lower[axis] + upper[axis]);
  SplitPolygon below, above;
  clip_polygon(polygon, axis, plane, below, above);
  // A side holding fewer than three corners touches the plane only: the other side's box holds
  // those points.
  if (below.count >= 3) split_into_pieces(below, depth + 1, limits, limit, boxes);
  if (above.count >= 3) split_into_pieces(above, depth + 1, limits, limit, boxes);
}

// Replaces `primitives` (one box per occluder, primID its index) by the references of the
// pre-split (see split_into_pieces), with reference_triangle[primID] the occluder of each.
// Triangles are split while a piece is longer than 1/64 of the scene's extent and its box's half
// surface area is more than 4 times its area (a flat triangle in an axis plane has 2); at most
// max(n / 2, 65536) references are added to n triangles (the length threshold doubles until
// they fit).
void pre_split(const std::vector<OccluderTriangle>& occluders,
               std::vector<RTCBuildPrimitive>& primitives,
               std::vector<uint32_t>& reference_triangle) {
  double scene_lower[3], scene_upper[3];
  for (int axis = 0; axis < 3; ++axis) {
    scene_lower[axis] = std::numeric_limits<double>::infinity();
    scene_upper[axis] = -std::numeric_limits<double>::infinity();
  }
  for (const RTCBuildPrimitive& p : primitives) {
    const float lower[3] = {p.lower_x, p.lower_y, p.lower_z};
    const float upper[3] = {p.upper_x, p.upper_y, p.upper_z};
    for (int axis = 0; axis < 3; ++axis) {
      scene_lower[axis] = std::min<double>(scene_lower[axis], lower[axis]);
      scene_upper[axis] = std::max<double>(scene_upper[axis], upper[axis]);
    }
  }
  const double scene_extent =
      std::max({scene_upper[0] - scene_lower[0], scene_upper[1] - scene_lower[1],
                scene_upper[2] - scene_lower[2]});
  const size_t budget = occluders.size() + std::max<size_t>(occluders.size() / 2, 65536);
  PreSplitLimits limits;
  limits.min_extent = scene_extent / 64;
  std::vector<RTCBuildPrimitive> split;
  std::vector<RTCBounds> boxes;
  for (;;) {
    split.clear();
    reference_triangle.clear();
    for (const RTCBuildPrimitive& whole : primitives) {
      const OccluderTriangle& triangle = occluders[whole.primID];
      SplitPolygon polygon;
      polygon.count = 3;
      for (int k = 0; k < 3; ++k)
        for (int axis = 0; axis < 3; ++axis) polygon.v[k][axis] = triangle.coordinate[axis][k];
      boxes.clear();
      split_into_pieces(polygon, 0, limits, whole, boxes);
      for (const RTCBounds& box : boxes) {
        RTCBuildPrimitive piece = whole;
        piece.lower_x = box.lower_x;
        piece.lower_y = box.lower_y;
        piece.lower_z = box.lower_z;
        piece.upper_x = box.upper_x;
        piece.upper_y = box.upper_y;
        piece.upper_z = box.upper_z;
        piece.primID = static_cast<unsigned>(split.size());
        split.push_back(piece);
        reference_triangle.push_back(whole.primID);
      }
      if (split.size() > budget) break;
    }
    if (split.size() <= budget) break;
    limits.min_extent *= 2;
  }
  primitives = std::move(split);
}

RTCBuildQuality embree_quality(LineQueryBuildQuality quality) {
  switch (quality) {
    case LineQueryBuildQuality::Low:
      return RTC_BUILD_QUALITY_LOW;
    case LineQueryBuildQuality::High:
      return RTC_BUILD_QUALITY_HIGH;
    default:
      return RTC_BUILD_QUALITY_MEDIUM;
  }
}

Vec3 absolute(const Vec3& v) {
  return {std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)};
}

// ---------------------------------------------------------------------------------------------
// Traversal. The node test needs, per query, three linear functions f(p) = dot(gradient, p) +
// offset over boxes (the distance to the shadow plane, alpha and beta; see shadow_triangle.h):
// their value at a box's centre (`middle`) and a radius, so that [middle - radius, middle +
// radius] contains the exact range of f over the box. Their constants are floats, computed
// once per query.

// The three functions, in this order, index the set-up's arrays.
enum Function { kDistance = 0, kAlpha = 1, kBeta = 2 };

// Everything the node test needs from one query.
struct NodeTestSetup {
  float region_lower[3], region_upper[3];  // bounding box of the crossing region
  float gradient[3][3];                    // [axis][function]
  float magnitude[3][3];                   // |gradient|
  float offset[3], error[3];               // [function]
  // Depth s = alpha + beta: its range over a box lies within the sum of theirs, widened by
  // depth_error (the rounding of the two extra sums; see set_up_node_test).
  float depth_error;
  float s_min, s_max;

  // Over the eight boxes (centre c, half extent e): the value of function f at the centre, and
  // a radius such that [middle - radius, middle + radius] holds f over the box.
  lanes::F8 middle(Function f, const lanes::F8 center[3]) const {
    return (offset[f] + gradient[0][f] * center[0]) +
           (gradient[1][f] * center[1] + gradient[2][f] * center[2]);
  }
  lanes::F8 radius(Function f, const lanes::F8 extent[3]) const {
    return (error[f] + magnitude[0][f] * extent[0]) +
           (magnitude[1][f] * extent[1] + magnitude[2][f] * extent[2]);
  }
};

// What the node test returns for each surviving child: the t-range its box projects to on the
// segment and the lower bound of its depth s (the near-to-far order).
struct ChildRanges {
  float t_lower[LineQuery::kWidth];
  float t_upper[LineQuery::kWidth];
  float depth_lower[LineQuery::kWidth];
};

// The node test: the eight child boxes at once (lanes.h: SSE2 halves or AVX, the same float
// operations per lane either way). Ordered comparisons: NaN centres (empty slots) fail.
//
// Cheapest tests first: the child box against the crossing region's bounding box (the
// triangle-box test's box-axis half, Akenine-Möller 2001) and against the shadow plane
// (|distance| <= radius). Most rejected children fail one of these, and then alpha, beta and
// depth are never computed. Then the side planes through x (alpha >= 0, beta >= 0), the plane
// through the segment (s < s_max) and the self-occlusion plane (s > s_min). Finally the
// surviving boxes are projected from x onto the segment: within the wedge (alpha, beta >= 0),
// t = beta / (alpha + beta) grows with beta and falls with alpha, so over the box's [alpha] x
// [beta] rectangle its range is [beta_lo / (alpha_hi + beta_lo), beta_hi / (alpha_lo + beta_hi)]
// with negative bounds clamped to 0. Returns the bit mask of the surviving children.
template <class Mask>
inline unsigned test_children(const LineQuery::Node& node, const NodeTestSetup& setup,
                              ChildRanges& out) {
  using lanes::F8;
  using lanes::I8;
  const F8 center[3] = {lanes::load(node.center[0]), lanes::load(node.center[1]),
                        lanes::load(node.center[2])};
  const F8 extent[3] = {lanes::load(node.extent[0]), lanes::load(node.extent[1]),
                        lanes::load(node.extent[2])};
  I8 keep = (center[0] - extent[0] <= setup.region_upper[0]) &
            (center[0] + extent[0] >= setup.region_lower[0]);
  for (int k = 1; k < 3; ++k) {
    keep &= center[k] - extent[k] <= setup.region_upper[k];
    keep &= center[k] + extent[k] >= setup.region_lower[k];
  }
  if (Mask::of(keep) == 0) return 0;
  keep &= lanes::absolute(setup.middle(kDistance, center)) <= setup.radius(kDistance, extent);
  if (Mask::of(keep) == 0) return 0;

  const F8 alpha_middle = setup.middle(kAlpha, center);
  const F8 alpha_radius = setup.radius(kAlpha, extent);
  const F8 beta_middle = setup.middle(kBeta, center);
  const F8 beta_radius = setup.radius(kBeta, extent);
  const F8 depth_middle = alpha_middle + beta_middle;
  const F8 depth_radius = (alpha_radius + beta_radius) + setup.depth_error;
  const F8 alpha_lower = alpha_middle - alpha_radius;
  const F8 alpha_upper = alpha_middle + alpha_radius;
  const F8 beta_lower = beta_middle - beta_radius;
  const F8 beta_upper = beta_middle + beta_radius;
  const F8 depth_lower = depth_middle - depth_radius;
  const F8 depth_upper = depth_middle + depth_radius;
  keep &= alpha_upper >= 0.0f;
  keep &= beta_upper >= 0.0f;
  keep &= depth_upper > setup.s_min;
  keep &= depth_lower < setup.s_max;
  const unsigned mask = Mask::of(keep);
  if (mask == 0) return 0;

  const F8 zero = {};
  const F8 tiny = zero + FLT_MIN;
  const F8 beta_lower_clamped = lanes::maximum(beta_lower, zero);
  const F8 alpha_lower_clamped = lanes::maximum(alpha_lower, zero);
  lanes::store(out.t_lower,
               beta_lower_clamped / lanes::maximum(alpha_upper + beta_lower_clamped, tiny));
  lanes::store(out.t_upper, beta_upper / lanes::maximum(alpha_lower_clamped + beta_upper, tiny));
  lanes::store(out.depth_lower, depth_lower);
  return mask;
}

// The AVX build also counts bits with POPCNT (every AVX CPU has it).
bool cpu_has_avx() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx") && __builtin_cpu_supports("popcnt");
#else
  return false;
#endif
}

// The traversal stack: node or leaf codes with the t-range each one's box projects to
// (re-checked when popped, since cuts found in the meantime may have covered it). One array per
// field, so that every pop reads exactly what one push wrote (a load spanning two stores would
// wait for them to reach the cache, on every node).
constexpr int kStackCapacity = 256;  // kWidth - 1 entries per level: depth checked at build
struct TraversalStack {
  uint32_t code[kStackCapacity];
  float t_lower[kStackCapacity], t_upper[kStackCapacity];
  int top = 0;

  void push(uint32_t node, float lower, float upper) {
    code[top] = node;
    t_lower[top] = lower;
    t_upper[top] = upper;
    ++top;
  }
  bool empty() const { return top == 0; }
};

// Slack on projected t-ranges (t is in [0,1]): float rounding of one add and one divide.
constexpr float kProjectionSlack = 1e-6f;

// What a query reads of the built structure.
struct Traversal {
  const LineQuery::Node* nodes;
  const OccluderTriangle* triangles;  // in leaf order
  bool empty;                         // no occluders
  bool prefetch;       // nodes and triangles exceed a typical L2 cache: prefetch children
  Vec3 scene_max_abs;  // per axis, the largest |coordinate| (float error bounds)
  ShadowTriangleTolerances tolerances;
};

// 2^-e for the e with 2^e <= value < 2^(e + 1): a scale that brings `value` into [1, 2) exactly.
// For finite positive values whose scale is a normal double (every non-degenerate shadow
// triangle's normal); otherwise 1 / value, which rounds.
inline double unit_scale(double value) {
  uint64_t bits;
  __builtin_memcpy(&bits, &value, sizeof bits);
  const int64_t exponent = static_cast<int64_t>(bits >> 52);  // biased; sign bit clear
  if (exponent < 1 || exponent > 2045) return 1 / value;
  const uint64_t scale_bits = static_cast<uint64_t>(2046 - exponent) << 52;
  double scale;
  __builtin_memcpy(&scale, &scale_bits, sizeof scale);
  return scale;
}

// The node test's constants for one shadow triangle: double, rounded to float. (Scalar code:
// each value is written once and read back only as the float it was stored as.)
inline void set_up_node_test(const ShadowTriangle& shadow, const Vec3& scene_max_abs,
                             NodeTestSetup& setup) {
  const Vec3& x = shadow.x;
  // The plane test is homogeneous in the normal: scaled by a power of two to a largest
  // component in [1, 2) (exact, and far from float denormals, which flush to zero, at any
  // scene scale).
  const Vec3 n = shadow.plane_normal * unit_scale(max_component(absolute(shadow.plane_normal)));
  const Vec3* const gradients[3] = {&n, &shadow.alpha_gradient, &shadow.beta_gradient};
  // Float error of evaluating dot(g, c) + offset and dot(|g|, e) with g, offset, c, e rounded to
  // float: a few ulps of the largest partial sum, bounded by |g|.(max |p| + |x|) since centres
  // and extents are bounded by the scene's extent; 32 ulps to be safe. (Double rounding here is
  // far below that margin.)
  const Vec3 bound = scene_max_abs + absolute(x);
  for (int f = 0; f < 3; ++f) {
    const Vec3& g = *gradients[f];
    setup.offset[f] = static_cast<float>(-dot(g, x));  // f(p) = dot(g, p) - dot(g, x)
    setup.error[f] = static_cast<float>(32 * (FLT_EPSILON / 2) * dot(absolute(g), bound));
    for (int axis = 0; axis < 3; ++axis) {
      setup.gradient[axis][f] = static_cast<float>(g[axis]);
      // |float(g)| == float(|g|) (rounding is symmetric).
      setup.magnitude[axis][f] = std::fabs(setup.gradient[axis][f]);
    }
  }
  // Depth s = alpha + beta over a box: within [alpha] + [beta] (each radius already holds its
  // own error bound), i.e. middle alpha_m + beta_m, radius alpha_r + beta_r. The two extra float
  // sums round by at most an ulp of (|g_alpha| + |g_beta|).(max |p| + |x|), far below the sum of
  // the two 32-ulp error terms added here.
  setup.depth_error = setup.error[kAlpha] + setup.error[kBeta];
  setup.s_min = static_cast<float>(shadow.s_min);
  setup.s_max = static_cast<float>(shadow.s_max);
  // The bounding box of the part of the shadow triangle that can hold a crossing: depth s in
  // [s_min, s_max], the quadrilateral x + s (a - x), x + s (b - x). Box against box is the
  // triangle-box test's box-axis half (Akenine-Möller 2001); with the free zone near x left
  // out, it also drops the surface x lies on before its leaf is reached. Rounded outwards.
  for (int k = 0; k < 3; ++k) {
    // Per axis the corners are x + s v with s in {s_min, s_max} (both > 0) and v in
    // {to_a, to_b}: the extremes take s_max where v is on the far side of 0.
    const double v_lower = std::min(shadow.to_a[k], shadow.to_b[k]);
    const double v_upper = std::max(shadow.to_a[k], shadow.to_b[k]);
    const double lower = x[k] + (v_lower < 0 ? shadow.s_max : shadow.s_min) * v_lower;
    const double upper = x[k] + (v_upper > 0 ? shadow.s_max : shadow.s_min) * v_upper;
    // Rounding of the corners (double) and to float (half an ulp): 1e-6 of the coordinates
    // involved covers both.
    const double slack = 1e-6 * (std::fabs(x[k]) + std::fabs(lower) + std::fabs(upper));
    setup.region_lower[k] = static_cast<float>(lower - slack);
    setup.region_upper[k] = static_cast<float>(upper + slack);
  }
}

// One query: the shadow triangle and the node test's constants, then the walk (nodes tested
// eight children at a time, surviving children pushed so that the nearest is popped first,
// exact crossings at the leaves). Inlined whole into query_sse and query_avx (below), so that
// the node test and occluder_cut are compiled for each instruction set. Returns false, with
// `out` untouched, when the shadow triangle is degenerate (the caller answers those with a
// shadow ray).
template <class Mask>
inline bool query(const Traversal& traversal, const Vec3& x, const Vec3& a, const Vec3& b,
                  IntervalList& out, LineQueryStats* stats) {
  ShadowTriangle shadow;
  if (!shadow.set(x, a, b, traversal.tolerances)) return false;
  if (traversal.empty) return true;
  NodeTestSetup setup;
  set_up_node_test(shadow, traversal.scene_max_abs, setup);

  TraversalStack stack;
  stack.push(0, 0.0f, 1.0f);
  uint64_t nodes_visited = 0, triangles_tested = 0, cuts = 0;
  ChildRanges ranges;

  while (!stack.empty()) {
    const int top = --stack.top;
    const uint32_t code = stack.code[top];
    // Skip what cuts found since the push have covered. (Before the first cut the whole
    // segment is visible and every pushed range, within [0,1], overlaps it.)
    if (cuts != 0 &&
        !out.overlaps(stack.t_lower[top] - kProjectionSlack, stack.t_upper[top] + kProjectionSlack))
      continue;

    if (code & LineQuery::kLeafFlag) {
      // Leaf: exact crossings in double.
      const uint32_t first = (code & ~LineQuery::kLeafFlag) >> LineQuery::kCountBits;
      const uint32_t count = (code & ((1u << LineQuery::kCountBits) - 1)) + 1;
      for (uint32_t i = first; i < first + count; ++i) {
        ++triangles_tested;
        const std::optional<Interval> cut = occluder_cut(shadow, traversal.triangles[i]);
        if (!cut) continue;
        ++cuts;
        out.subtract(cut->lo, cut->hi);
        if (out.fully_occluded()) {
          stack.top = 0;  // nothing stays visible: done
          break;
        }
      }
      continue;
    }

    const LineQuery::Node& node = traversal.nodes[code];
    ++nodes_visited;
    unsigned mask = test_children<Mask>(node, setup, ranges);
    if (mask == 0) continue;
    // Push the surviving children far to near, so that the nearest is popped first (near
    // occluders cut the most; on a dense closed mesh the near side's cuts then cull the far
    // side's nodes). Each child's place is its rank by depth, counted with one vector compare
    // (ties by slot): no data-dependent branch per child. (Whether their projection is already
    // occluded is checked when they are popped.)
    int order[LineQuery::kWidth];
    const int kept = __builtin_popcount(mask);
    if (kept == 1) {
      order[0] = __builtin_ctz(mask);
    } else {
      const lanes::F8 depth = lanes::load(ranges.depth_lower);
      for (unsigned rest = mask; rest != 0; rest &= rest - 1) {
        const int slot = __builtin_ctz(rest);
        const unsigned nearer = Mask::of(depth < ranges.depth_lower[slot]) |
                                (Mask::of(depth == ranges.depth_lower[slot]) & ((1u << slot) - 1));
        order[__builtin_popcount(nearer & mask)] = slot;
      }
    }
    for (int i = kept - 1; i >= 0; --i) {
      const int slot = order[i];
      const uint32_t child = node.child[slot];
      stack.push(child, ranges.t_lower[slot], ranges.t_upper[slot]);
      // Start loading it now: the walk is bound by memory on large scenes (small ones stay in
      // cache, and the prefetches would only cost instructions).
      if (!traversal.prefetch) continue;
      if (child & LineQuery::kLeafFlag) {
        const char* leaf = reinterpret_cast<const char*>(
            &traversal.triangles[(child & ~LineQuery::kLeafFlag) >> LineQuery::kCountBits]);
        _mm_prefetch(leaf, _MM_HINT_T0);
        _mm_prefetch(leaf + 64, _MM_HINT_T0);
      } else {
        const char* next = reinterpret_cast<const char*>(&traversal.nodes[child]);
        for (size_t line = 0; line < sizeof(LineQuery::Node); line += 64)
          _mm_prefetch(next + line, _MM_HINT_T0);
      }
    }
  }
  if (stats) {
    stats->nodes_visited += nodes_visited;
    stats->triangles_tested += triangles_tested;
    stats->cuts += cuts;
  }
  return true;
}

// The two builds of the walk (flatten: everything it calls is inlined and compiled with its
// instruction set). Both do the same IEEE operations per lane: the same answers, bit for bit.
__attribute__((flatten)) bool query_sse(const Traversal& traversal, const Vec3& x, const Vec3& a,
                                        const Vec3& b, IntervalList& out, LineQueryStats* stats) {
  return query<lanes::SseMask>(traversal, x, a, b, out, stats);
}
#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx,popcnt"), flatten)) bool query_avx(const Traversal& traversal,
                                                              const Vec3& x, const Vec3& a,
                                                              const Vec3& b, IntervalList& out,
                                                              LineQueryStats* stats) {
  return query<lanes::AvxMask>(traversal, x, a, b, out, stats);
}
#else
bool query_avx(const Traversal& traversal, const Vec3& x, const Vec3& a, const Vec3& b,
               IntervalList& out, LineQueryStats* stats) {
  return query_sse(traversal, x, a, b, out, stats);
}
#endif

}  // namespace

LineQuery::LineQuery(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices,
                     const LineQueryOptions& options)
    : options_(options) {
  build(positions, indices);
}

LineQuery::LineQuery(const Scene& scene, const LineQueryOptions& options) : options_(options) {
  build(scene.positions, scene.indices);
}

void LineQuery::build(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices) {
  if (options_.max_leaf_size < 1 || options_.max_leaf_size > (1u << kCountBits))
    throw std::invalid_argument("LineQuery: max_leaf_size must be in [1, 32], got " +
                                std::to_string(options_.max_leaf_size));
  // Occluder triangles, canonical vertex order, and their float boxes.
  std::vector<OccluderTriangle> occluders;
  std::vector<RTCBuildPrimitive> primitives;
  size_t input_count = indices.size() / 3;
  occluders.reserve(input_count);
  primitives.reserve(input_count);
  scene_max_abs_ = {0, 0, 0};
  for (size_t i = 0; i < input_count; ++i) {
    std::optional<OccluderTriangle> triangle =
        OccluderTriangle::make(positions.at(indices[3 * i]), positions.at(indices[3 * i + 1]),
                               positions.at(indices[3 * i + 2]));
    if (!triangle) continue;
    RTCBuildPrimitive primitive;
    Vec3 lower = triangle->vertex(0), upper = lower;
    for (int vertex = 0; vertex < 3; ++vertex) {
      Vec3 v = triangle->vertex(vertex);
      for (int k = 0; k < 3; ++k) {
        lower[k] = std::min(lower[k], v[k]);
        upper[k] = std::max(upper[k], v[k]);
        scene_max_abs_[k] = std::max(scene_max_abs_[k], std::fabs(v[k]));
      }
    }
    primitive.lower_x = round_down(lower.x);
    primitive.lower_y = round_down(lower.y);
    primitive.lower_z = round_down(lower.z);
    primitive.upper_x = round_up(upper.x);
    primitive.upper_y = round_up(upper.y);
    primitive.upper_z = round_up(upper.z);
    primitive.geomID = 0;
    primitive.primID = static_cast<unsigned>(occluders.size());
    primitives.push_back(primitive);
    occluders.push_back(*triangle);
  }
  nodes_.clear();
  triangles_.clear();
  triangle_count_ = occluders.size();
  if (occluders.empty()) return;
  std::vector<uint32_t> reference_triangle;  // the triangle of each primitive (primID)
  if (options_.split_long_triangles) {
    pre_split(occluders, primitives, reference_triangle);
  } else {
    reference_triangle.resize(occluders.size());
    for (size_t i = 0; i < occluders.size(); ++i) reference_triangle[i] = static_cast<uint32_t>(i);
  }
  // Embree builds on boxes scaled by a power of two to a largest coordinate in [1, 2): its SAH
  // then sees the same numbers at every scene scale (box areas of tiny scenes would otherwise
  // be float denormals, flushed to zero on render threads). Exact both ways.
  const float build_scale =
      std::ldexp(1.0f, -std::ilogb(std::max(max_component(scene_max_abs_), 1e-30)));
  for (RTCBuildPrimitive& primitive : primitives) {
    primitive.lower_x *= build_scale;
    primitive.lower_y *= build_scale;
    primitive.lower_z *= build_scale;
    primitive.upper_x *= build_scale;
    primitive.upper_y *= build_scale;
    primitive.upper_z *= build_scale;
  }
  if (primitives.size() >= (size_t{1} << (31 - kCountBits)))
    throw std::invalid_argument("LineQuery: too many triangles (" +
                                std::to_string(occluders.size()) + " in " +
                                std::to_string(primitives.size()) + " pieces)");

  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw std::runtime_error("LineQuery: cannot create an Embree device");
  RTCBVH bvh = rtcNewBVH(device);
  RTCBuildArguments arguments = rtcDefaultBuildArguments();
  arguments.byteSize = sizeof(arguments);
  arguments.buildQuality = embree_quality(options_.build_quality);
  arguments.maxBranchingFactor = kWidth;
  arguments.maxDepth = 32;
  arguments.sahBlockSize = 1;
  arguments.minLeafSize = 1;
  arguments.maxLeafSize = options_.max_leaf_size;
  arguments.traversalCost = 1.0f;
  arguments.intersectionCost = 1.0f;
  arguments.bvh = bvh;
  // The union of the triangles' boxes (a root for a single leaf), before Embree reorders them.
  RTCBounds all_bounds{primitives[0].lower_x, primitives[0].lower_y, primitives[0].lower_z, 0,
                       primitives[0].upper_x, primitives[0].upper_y, primitives[0].upper_z, 0};
  for (const RTCBuildPrimitive& p : primitives) {
    all_bounds.lower_x = std::min(all_bounds.lower_x, p.lower_x);
    all_bounds.lower_y = std::min(all_bounds.lower_y, p.lower_y);
    all_bounds.lower_z = std::min(all_bounds.lower_z, p.lower_z);
    all_bounds.upper_x = std::max(all_bounds.upper_x, p.upper_x);
    all_bounds.upper_y = std::max(all_bounds.upper_y, p.upper_y);
    all_bounds.upper_z = std::max(all_bounds.upper_z, p.upper_z);
  }
  // Spatial splits (HIGH) add references to parts of triangles: room for twice as many.
  const bool spatial_splits = options_.build_quality == LineQueryBuildQuality::High;
  const size_t primitive_count = primitives.size();
  if (spatial_splits) primitives.resize(2 * primitive_count);
  arguments.primitives = primitives.data();
  arguments.primitiveCount = primitive_count;
  arguments.primitiveArrayCapacity = primitives.size();
  arguments.createNode = create_inner;
  arguments.setNodeChildren = set_children;
  arguments.setNodeBounds = set_bounds;
  arguments.createLeaf = create_leaf;
  arguments.splitPrimitive = spatial_splits ? split_primitive : nullptr;
  arguments.buildProgress = nullptr;
  BuildStatus status;
  status.occluders = &occluders;
  status.reference_triangle = &reference_triangle;
  status.build_scale = build_scale;
  arguments.userPtr = &status;
  auto* root = static_cast<BuildNode*>(rtcBuildBVH(&arguments));
  if (!root) {
    rtcReleaseBVH(bvh);
    rtcReleaseDevice(device);
    throw std::runtime_error("LineQuery: rtcBuildBVH failed (Embree error " +
                             std::to_string(static_cast<int>(rtcGetDeviceError(device))) + ")");
  }

  // Flatten depth first: a node's children get their codes after the node has its slot.
  triangles_.reserve(occluders.size());
  nodes_.reserve(occluders.size() / 2 + 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto new_node = [&]() {
    Node node;
    for (int k = 0; k < 3; ++k) {
      for (int slot = 0; slot < kWidth; ++slot) {
        node.center[k][slot] = nan;
        node.extent[k][slot] = 0;
      }
    }
    for (uint32_t& code : node.child) code = 0;
    nodes_.push_back(node);
    return static_cast<uint32_t>(nodes_.size() - 1);
  };
  auto flatten_leaf = [&](const BuildLeaf* leaf) {
    // Pieces of one triangle that share a leaf: the triangle once.
    uint32_t first = static_cast<uint32_t>(triangles_.size());
    uint32_t in_leaf[RTC_BUILD_MAX_PRIMITIVES_PER_LEAF];
    unsigned count = 0;
    for (unsigned i = 0; i < leaf->triangle_count; ++i) {
      const uint32_t triangle = reference_triangle[leaf->triangles[i]];
      if (std::find(in_leaf, in_leaf + count, triangle) != in_leaf + count) continue;
      in_leaf[count++] = triangle;
      triangles_.push_back(occluders[triangle]);
    }
    return kLeafFlag | (first << kCountBits) | (count - 1);
  };
  auto set_slot = [&](uint32_t index, int slot, const RTCBounds& bounds, uint32_t code) {
    Node& node = nodes_[index];
    const double lower[3] = {bounds.lower_x / build_scale, bounds.lower_y / build_scale,
                             bounds.lower_z / build_scale};
    const double upper[3] = {bounds.upper_x / build_scale, bounds.upper_y / build_scale,
                             bounds.upper_z / build_scale};
    for (int k = 0; k < 3; ++k) {
      // Round the centre, then grow the extent until the box holds [lower, upper].
      float center = static_cast<float>(0.5 * (lower[k] + upper[k]));
      node.center[k][slot] = center;
      node.extent[k][slot] = round_up(std::max(center - lower[k], upper[k] - center));
    }
    node.child[slot] = code;
  };
  // Returns the code of the flattened subtree. The traversal stack holds at most kWidth - 1
  // entries per level plus kWidth, so the depth is bounded (Embree's maxDepth is 32; checked).
  const int max_depth = (kStackCapacity - kWidth) / (kWidth - 1);
  auto flatten = [&](auto&& self, const BuildNode* node, int depth) -> uint32_t {
    if (node->is_leaf) return flatten_leaf(reinterpret_cast<const BuildLeaf*>(node));
    if (depth > max_depth)
      throw std::runtime_error("LineQuery: BVH deeper than " + std::to_string(max_depth));
    auto* inner = reinterpret_cast<const BuildInner*>(node);
    uint32_t index = new_node();
    for (unsigned i = 0; i < inner->child_count; ++i) {
      uint32_t code = self(self, inner->children[i], depth + 1);
      set_slot(index, static_cast<int>(i), inner->bounds[i], code);
    }
    return index;
  };
  if (root->is_leaf) {
    // A single leaf: give it a root node, with the union of its triangles' boxes.
    uint32_t index = new_node();
    set_slot(index, 0, all_bounds, flatten_leaf(reinterpret_cast<const BuildLeaf*>(root)));
  } else {
    try {
      flatten(flatten, root, 1);
    } catch (...) {
      rtcReleaseBVH(bvh);
      rtcReleaseDevice(device);
      throw;
    }
  }
  rtcReleaseBVH(bvh);
  rtcReleaseDevice(device);
  use_avx_ = options_.allow_avx && cpu_has_avx();
  // Prefetch only when the structure is larger than a typical L2 cache.
  prefetch_ = nodes_.size() * sizeof(Node) + triangles_.size() * sizeof(OccluderTriangle) >
              (size_t{1} << 20);
  if (status.oversized_leaf)
    throw std::runtime_error("LineQuery: Embree made a leaf larger than " +
                             std::to_string(RTC_BUILD_MAX_PRIMITIVES_PER_LEAF) + " triangles");
}

void LineQuery::visible_intervals(const Vec3& x, const Vec3& a, const Vec3& b, IntervalList& out,
                                  LineQueryStats* stats) const {
  out.reset();
  const Traversal traversal{nodes_.data(), triangles_.data(), nodes_.empty(),
                            prefetch_,     scene_max_abs_,    options_.tolerances};
  const bool answered = use_avx_ ? query_avx(traversal, x, a, b, out, stats)
                                 : query_sse(traversal, x, a, b, out, stats);
  if (answered) return;
  // Non-finite input: nothing visible. Degenerate shadow triangle: the segment is seen along
  // one direction, one shadow ray decides.
  if (!is_finite(x) || !is_finite(a) || !is_finite(b) || occluded(x, 0.5 * (a + b))) out.clear();
}

bool LineQuery::occluded(const Vec3& x, const Vec3& p) const {
  if (nodes_.empty() || !is_finite(x) || !is_finite(p)) return false;
  const double s_min = options_.tolerances.self_occlusion_epsilon;
  const double s_max = 1 - options_.tolerances.light_plane_epsilon;
  Vec3 direction = p - x;
  // Boxes are padded by a few float ulps of the scene's extent before the slab test.
  double pad = 4 * FLT_EPSILON * (max_component(scene_max_abs_) + max_component(absolute(x)));
  uint32_t stack[kStackCapacity];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    uint32_t code = stack[--top];
    if (code & kLeafFlag) {
      uint32_t first = (code & ~kLeafFlag) >> kCountBits;
      uint32_t count = (code & ((1u << kCountBits) - 1)) + 1;
      for (uint32_t i = first; i < first + count; ++i) {
        const OccluderTriangle& t = triangles_[i];
        if (segment_hits_triangle(x, p, s_min, s_max, t.vertex(0), t.vertex(1), t.vertex(2)))
          return true;
      }
      continue;
    }
    const Node& node = nodes_[code];
    for (int slot = 0; slot < kWidth; ++slot) {
      if (std::isnan(node.center[0][slot])) continue;
      // Slab test of the parameter range [0, 1] of x + s (p - x).
      double enter = 0, exit = 1;
      for (int k = 0; k < 3 && enter <= exit; ++k) {
        double center = node.center[k][slot], extent = node.extent[k][slot];
        double lower = center - extent - pad, upper = center + extent + pad;
        if (direction[k] == 0) {
          if (x[k] < lower || x[k] > upper) exit = -1;
          continue;
        }
        double s0 = (lower - x[k]) / direction[k], s1 = (upper - x[k]) / direction[k];
        enter = std::max(enter, std::min(s0, s1));
        exit = std::min(exit, std::max(s0, s1));
      }
      if (enter <= exit) stack[top++] = node.child[slot];
    }
  }
  return false;
}

}  // namespace penumbra
