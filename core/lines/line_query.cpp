#include "core/lines/line_query.h"

#include <embree3/rtcore.h>
#include <immintrin.h>

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

// Set from Embree's build threads when a leaf is larger than asked (Embree promises not to).
struct BuildStatus {
  std::atomic<bool> oversized_leaf{false};
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
// Traversal. The node test needs, per query, a few linear functions f(p) = dot(gradient, p) +
// offset over boxes: their value at a box's centre (`middle`) and a radius, so that
// [middle - radius, middle + radius] contains the exact range of f over the box. The constants
// are stored as floats, once: the AVX test broadcasts them from memory (one instruction), the
// SSE test with a load and a shuffle.

inline __m128 sse(float value) {
  return _mm_set1_ps(value);
}

// Three doubles rounded to float (as static_cast<float> does, lane by lane) in lanes 0-2.
inline __m128 to_floats(const Vec3& v) {
  return _mm_movelh_ps(_mm_cvtpd_ps(_mm_set_pd(v.y, v.x)), _mm_cvtpd_ps(_mm_set_sd(v.z)));
}

struct LinearFunction {
  alignas(16) float gradient[4];   // lanes 0-2
  alignas(16) float magnitude[4];  // |gradient|
  float offset, error;

  // `coordinate_bound` is max |p| over the scene plus |x|, per axis (computed once per query).
  void set(const Vec3& gradient_d, const Vec3& x, const Vec3& coordinate_bound) {
    // Float error of evaluating dot(g, c) + offset and dot(|g|, e) with g, offset, c, e rounded
    // to float: a few ulps of the largest partial sum, bounded by |g|.(max |p| + |x|) since
    // centres and extents are bounded by the scene's extent; 32 ulps to be safe.
    error =
        static_cast<float>(32 * (FLT_EPSILON / 2) * dot(absolute(gradient_d), coordinate_bound));
    offset = static_cast<float>(-dot(gradient_d, x));
    // |float(g)| == float(|g|) (rounding is symmetric): the magnitudes are the gradients with
    // the sign bit cleared.
    const __m128 rounded = to_floats(gradient_d);
    _mm_store_ps(gradient, rounded);
    _mm_store_ps(magnitude, _mm_andnot_ps(_mm_set1_ps(-0.0f), rounded));
  }
};

// Everything the node test needs from one query.
struct NodeTestSetup {
  float region_lower[3], region_upper[3];  // bounding box of the crossing region
  LinearFunction distance, alpha, beta;    // see shadow_triangle.h
  // Depth s = alpha + beta: its range over a box lies within the sum of theirs, widened by
  // depth_error (the rounding of the two extra sums; see visible_intervals).
  float depth_error;
  float s_min, s_max;
};

// What the node test returns for each surviving child: the t-range its box projects to on the
// segment and the lower bound of its depth s (the near-to-far order).
struct ChildRanges {
  alignas(32) float t_lower[LineQuery::kWidth];
  alignas(32) float t_upper[LineQuery::kWidth];
  alignas(32) float depth_lower[LineQuery::kWidth];
};

// The node test, the same float operations in the same order per lane in both versions (no
// fused multiply-add: the build has -ffp-contract=off and the AVX version does not enable
// FMA), so they keep the same children. Ordered comparisons: NaN centres (empty slots) fail.
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
using NodeTest = unsigned (*)(const LineQuery::Node& node, const NodeTestSetup& setup,
                              ChildRanges& out);

unsigned test_children_sse(const LineQuery::Node& node, const NodeTestSetup& setup,
                           ChildRanges& out) {
  const __m128 zero = _mm_setzero_ps();
  const __m128 tiny = _mm_set1_ps(FLT_MIN);
  const __m128 sign_bit = _mm_set1_ps(-0.0f);
  auto middle_of = [](const LinearFunction& f, const __m128 center[3]) {
    return _mm_add_ps(_mm_add_ps(sse(f.offset), _mm_mul_ps(sse(f.gradient[0]), center[0])),
                      _mm_add_ps(_mm_mul_ps(sse(f.gradient[1]), center[1]),
                                 _mm_mul_ps(sse(f.gradient[2]), center[2])));
  };
  auto radius_of = [](float error, const float magnitude[3], const __m128 extent[3]) {
    return _mm_add_ps(_mm_add_ps(sse(error), _mm_mul_ps(sse(magnitude[0]), extent[0])),
                      _mm_add_ps(_mm_mul_ps(sse(magnitude[1]), extent[1]),
                                 _mm_mul_ps(sse(magnitude[2]), extent[2])));
  };
  unsigned result = 0;
  for (int half = 0; half < LineQuery::kWidth; half += 4) {
    const __m128 center[3] = {_mm_load_ps(node.center[0] + half),
                              _mm_load_ps(node.center[1] + half),
                              _mm_load_ps(node.center[2] + half)};
    const __m128 extent[3] = {_mm_load_ps(node.extent[0] + half),
                              _mm_load_ps(node.extent[1] + half),
                              _mm_load_ps(node.extent[2] + half)};
    __m128 keep = _mm_cmple_ps(_mm_sub_ps(center[0], extent[0]), sse(setup.region_upper[0]));
    keep = _mm_and_ps(keep,
                      _mm_cmpge_ps(_mm_add_ps(center[0], extent[0]), sse(setup.region_lower[0])));
    for (int k = 1; k < 3; ++k) {
      keep = _mm_and_ps(keep,
                        _mm_cmple_ps(_mm_sub_ps(center[k], extent[k]), sse(setup.region_upper[k])));
      keep = _mm_and_ps(keep,
                        _mm_cmpge_ps(_mm_add_ps(center[k], extent[k]), sse(setup.region_lower[k])));
    }
    if (_mm_movemask_ps(keep) == 0) continue;
    const __m128 distance_middle = middle_of(setup.distance, center);
    const __m128 distance_radius =
        radius_of(setup.distance.error, setup.distance.magnitude, extent);
    keep =
        _mm_and_ps(keep, _mm_cmple_ps(_mm_andnot_ps(sign_bit, distance_middle), distance_radius));
    if (_mm_movemask_ps(keep) == 0) continue;

    const __m128 alpha_middle = middle_of(setup.alpha, center);
    const __m128 alpha_radius = radius_of(setup.alpha.error, setup.alpha.magnitude, extent);
    const __m128 beta_middle = middle_of(setup.beta, center);
    const __m128 beta_radius = radius_of(setup.beta.error, setup.beta.magnitude, extent);
    const __m128 depth_middle = _mm_add_ps(alpha_middle, beta_middle);
    const __m128 depth_radius =
        _mm_add_ps(_mm_add_ps(alpha_radius, beta_radius), sse(setup.depth_error));
    const __m128 alpha_lower = _mm_sub_ps(alpha_middle, alpha_radius);
    const __m128 alpha_upper = _mm_add_ps(alpha_middle, alpha_radius);
    const __m128 beta_lower = _mm_sub_ps(beta_middle, beta_radius);
    const __m128 beta_upper = _mm_add_ps(beta_middle, beta_radius);
    const __m128 depth_lower = _mm_sub_ps(depth_middle, depth_radius);
    const __m128 depth_upper = _mm_add_ps(depth_middle, depth_radius);
    keep = _mm_and_ps(keep, _mm_cmpge_ps(alpha_upper, zero));
    keep = _mm_and_ps(keep, _mm_cmpge_ps(beta_upper, zero));
    keep = _mm_and_ps(keep, _mm_cmpgt_ps(depth_upper, sse(setup.s_min)));
    keep = _mm_and_ps(keep, _mm_cmplt_ps(depth_lower, sse(setup.s_max)));
    const unsigned mask = static_cast<unsigned>(_mm_movemask_ps(keep));
    if (mask == 0) continue;

    const __m128 beta_lower_clamped = _mm_max_ps(beta_lower, zero);
    const __m128 alpha_lower_clamped = _mm_max_ps(alpha_lower, zero);
    _mm_store_ps(out.t_lower + half,
                 _mm_div_ps(beta_lower_clamped,
                            _mm_max_ps(_mm_add_ps(alpha_upper, beta_lower_clamped), tiny)));
    _mm_store_ps(
        out.t_upper + half,
        _mm_div_ps(beta_upper, _mm_max_ps(_mm_add_ps(alpha_lower_clamped, beta_upper), tiny)));
    _mm_store_ps(out.depth_lower + half, depth_lower);
    result |= mask << half;
  }
  return result;
}

#if defined(__x86_64__) || defined(__i386__)
#define PENUMBRA_LINE_QUERY_AVX 1
#define PENUMBRA_AVX __attribute__((target("avx"), always_inline)) inline

// AVX helpers of the node test (lambdas would not inherit the target attribute).
PENUMBRA_AVX __m256 lanes(const float& value) {
  return _mm256_broadcast_ss(&value);
}
PENUMBRA_AVX __m256 middle_of(const LinearFunction& f, const __m256 center[3]) {
  return _mm256_add_ps(
      _mm256_add_ps(lanes(f.offset), _mm256_mul_ps(lanes(f.gradient[0]), center[0])),
      _mm256_add_ps(_mm256_mul_ps(lanes(f.gradient[1]), center[1]),
                    _mm256_mul_ps(lanes(f.gradient[2]), center[2])));
}
PENUMBRA_AVX __m256 radius_of(const float& error, const float magnitude[3],
                              const __m256 extent[3]) {
  return _mm256_add_ps(_mm256_add_ps(lanes(error), _mm256_mul_ps(lanes(magnitude[0]), extent[0])),
                       _mm256_add_ps(_mm256_mul_ps(lanes(magnitude[1]), extent[1]),
                                     _mm256_mul_ps(lanes(magnitude[2]), extent[2])));
}

// The same test on all eight children at once (AVX, 256-bit; selected at run time).
__attribute__((target("avx"))) unsigned test_children_avx(const LineQuery::Node& node,
                                                          const NodeTestSetup& setup,
                                                          ChildRanges& out) {
  static_assert(LineQuery::kWidth == 8, "the AVX node test handles eight children");
  const __m256 zero = _mm256_setzero_ps();
  const __m256 tiny = _mm256_set1_ps(FLT_MIN);
  const __m256 sign_bit = _mm256_set1_ps(-0.0f);
  const __m256 center[3] = {_mm256_load_ps(node.center[0]), _mm256_load_ps(node.center[1]),
                            _mm256_load_ps(node.center[2])};
  const __m256 extent[3] = {_mm256_load_ps(node.extent[0]), _mm256_load_ps(node.extent[1]),
                            _mm256_load_ps(node.extent[2])};
  __m256 keep =
      _mm256_cmp_ps(_mm256_sub_ps(center[0], extent[0]), lanes(setup.region_upper[0]), _CMP_LE_OQ);
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(_mm256_add_ps(center[0], extent[0]),
                                           lanes(setup.region_lower[0]), _CMP_GE_OQ));
  for (int k = 1; k < 3; ++k) {
    keep = _mm256_and_ps(keep, _mm256_cmp_ps(_mm256_sub_ps(center[k], extent[k]),
                                             lanes(setup.region_upper[k]), _CMP_LE_OQ));
    keep = _mm256_and_ps(keep, _mm256_cmp_ps(_mm256_add_ps(center[k], extent[k]),
                                             lanes(setup.region_lower[k]), _CMP_GE_OQ));
  }
  if (_mm256_movemask_ps(keep) == 0) return 0;
  const __m256 distance_middle = middle_of(setup.distance, center);
  const __m256 distance_radius = radius_of(setup.distance.error, setup.distance.magnitude, extent);
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(_mm256_andnot_ps(sign_bit, distance_middle),
                                           distance_radius, _CMP_LE_OQ));
  if (_mm256_movemask_ps(keep) == 0) return 0;

  const __m256 alpha_middle = middle_of(setup.alpha, center);
  const __m256 alpha_radius = radius_of(setup.alpha.error, setup.alpha.magnitude, extent);
  const __m256 beta_middle = middle_of(setup.beta, center);
  const __m256 beta_radius = radius_of(setup.beta.error, setup.beta.magnitude, extent);
  const __m256 depth_middle = _mm256_add_ps(alpha_middle, beta_middle);
  const __m256 depth_radius =
      _mm256_add_ps(_mm256_add_ps(alpha_radius, beta_radius), lanes(setup.depth_error));
  const __m256 alpha_lower = _mm256_sub_ps(alpha_middle, alpha_radius);
  const __m256 alpha_upper = _mm256_add_ps(alpha_middle, alpha_radius);
  const __m256 beta_lower = _mm256_sub_ps(beta_middle, beta_radius);
  const __m256 beta_upper = _mm256_add_ps(beta_middle, beta_radius);
  const __m256 depth_lower = _mm256_sub_ps(depth_middle, depth_radius);
  const __m256 depth_upper = _mm256_add_ps(depth_middle, depth_radius);
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(alpha_upper, zero, _CMP_GE_OQ));
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(beta_upper, zero, _CMP_GE_OQ));
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(depth_upper, lanes(setup.s_min), _CMP_GT_OQ));
  keep = _mm256_and_ps(keep, _mm256_cmp_ps(depth_lower, lanes(setup.s_max), _CMP_LT_OQ));
  const unsigned mask = static_cast<unsigned>(_mm256_movemask_ps(keep));
  if (mask == 0) return 0;

  const __m256 beta_lower_clamped = _mm256_max_ps(beta_lower, zero);
  const __m256 alpha_lower_clamped = _mm256_max_ps(alpha_lower, zero);
  _mm256_store_ps(
      out.t_lower,
      _mm256_div_ps(beta_lower_clamped,
                    _mm256_max_ps(_mm256_add_ps(alpha_upper, beta_lower_clamped), tiny)));
  _mm256_store_ps(
      out.t_upper,
      _mm256_div_ps(beta_upper,
                    _mm256_max_ps(_mm256_add_ps(alpha_lower_clamped, beta_upper), tiny)));
  _mm256_store_ps(out.depth_lower, depth_lower);
  return mask;
}
#endif

#ifdef PENUMBRA_LINE_QUERY_AVX
constexpr NodeTest node_test_avx = test_children_avx;
#else
constexpr NodeTest node_test_avx = test_children_sse;
#endif

bool cpu_has_avx() {
#ifdef PENUMBRA_LINE_QUERY_AVX
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx");
#else
  return false;
#endif
}

// Stack entry: a node or leaf code with the t-range its box projects to (re-checked when popped,
// since cuts found in the meantime may have covered it).
struct StackEntry {
  uint32_t code;
  float t_lower, t_upper;
};

// Slack on projected t-ranges (t is in [0,1]): float rounding of one add and one divide.
constexpr float kProjectionSlack = 1e-6f;
constexpr int kStackCapacity = 256;  // kWidth - 1 entries per level: depth checked at build

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
  if (occluders.empty()) return;
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
  if (occluders.size() >= (size_t{1} << (31 - kCountBits)))
    throw std::invalid_argument("LineQuery: too many triangles (" +
                                std::to_string(occluders.size()) + ")");

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
  arguments.primitives = primitives.data();
  arguments.primitiveCount = primitives.size();
  arguments.primitiveArrayCapacity = primitives.size();
  arguments.createNode = create_inner;
  arguments.setNodeChildren = set_children;
  arguments.setNodeBounds = set_bounds;
  arguments.createLeaf = create_leaf;
  arguments.splitPrimitive = nullptr;  // no spatial splits
  arguments.buildProgress = nullptr;
  BuildStatus status;
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
    uint32_t first = static_cast<uint32_t>(triangles_.size());
    for (unsigned i = 0; i < leaf->triangle_count; ++i)
      triangles_.push_back(occluders[leaf->triangles[i]]);
    return kLeafFlag | (first << kCountBits) | (leaf->triangle_count - 1);
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
    RTCBounds bounds{primitives[0].lower_x, primitives[0].lower_y, primitives[0].lower_z, 0,
                     primitives[0].upper_x, primitives[0].upper_y, primitives[0].upper_z, 0};
    for (const RTCBuildPrimitive& p : primitives) {
      bounds.lower_x = std::min(bounds.lower_x, p.lower_x);
      bounds.lower_y = std::min(bounds.lower_y, p.lower_y);
      bounds.lower_z = std::min(bounds.lower_z, p.lower_z);
      bounds.upper_x = std::max(bounds.upper_x, p.upper_x);
      bounds.upper_y = std::max(bounds.upper_y, p.upper_y);
      bounds.upper_z = std::max(bounds.upper_z, p.upper_z);
    }
    set_slot(index, 0, bounds, flatten_leaf(reinterpret_cast<const BuildLeaf*>(root)));
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
  std::optional<ShadowTriangle> shadow = ShadowTriangle::make(x, a, b, options_.tolerances);
  if (!shadow) {
    // Non-finite input: nothing visible. Degenerate shadow triangle: the segment is seen along
    // one direction, one shadow ray decides.
    if (!is_finite(x) || !is_finite(a) || !is_finite(b) || occluded(x, 0.5 * (a + b))) out.clear();
    return;
  }
  if (nodes_.empty()) return;

  // The shadow triangle's planes as linear functions over boxes (see shadow_triangle.h):
  // distance to the plane, alpha, beta and depth s = alpha + beta.
  // (The plane test is homogeneous in the normal: normalized, so that it stays far from float
  // denormals, which flush to zero, at any scene scale.)
  // One bound for all four error terms (|g|.(max |p| + |x|); double rounding of the sum is far
  // below the 32-ulp float margin).
  const Vec3 coordinate_bound = scene_max_abs_ + absolute(x);
  NodeTestSetup setup;
  setup.distance.set(normalize(shadow->plane_normal), x, coordinate_bound);
  setup.alpha.set(shadow->alpha_gradient, x, coordinate_bound);
  setup.beta.set(shadow->beta_gradient, x, coordinate_bound);
  // Depth s = alpha + beta over a box: within [alpha] + [beta] (each radius already holds its
  // own error bound), i.e. middle alpha_m + beta_m, radius alpha_r + beta_r. The two extra float
  // sums round by at most an ulp of (|g_alpha| + |g_beta|).(max |p| + |x|), far below the sum of
  // the two 32-ulp error terms added here.
  setup.depth_error = setup.alpha.error + setup.beta.error;
  setup.s_min = static_cast<float>(shadow->s_min);
  setup.s_max = static_cast<float>(shadow->s_max);
  // The bounding box of the part of the shadow triangle that can hold a crossing: depth s in
  // [s_min, s_max], the quadrilateral x + s (a - x), x + s (b - x). Box against box is the
  // triangle-box test's box-axis half (Akenine-Möller 2001); with the free zone near x left
  // out, it also drops the surface x lies on before its leaf is reached. Rounded outwards.
  for (int k = 0; k < 3; ++k) {
    // Per axis the corners are x + s v with s in {s_min, s_max} (both > 0) and v in
    // {to_a, to_b}: the extremes take s_max where v is on the far side of 0.
    const double v_lower = std::min(shadow->to_a[k], shadow->to_b[k]);
    const double v_upper = std::max(shadow->to_a[k], shadow->to_b[k]);
    const double lower = x[k] + (v_lower < 0 ? shadow->s_max : shadow->s_min) * v_lower;
    const double upper = x[k] + (v_upper > 0 ? shadow->s_max : shadow->s_min) * v_upper;
    // Rounding of the corners (double) and to float (half an ulp): 1e-6 of the coordinates
    // involved covers both.
    const double slack = 1e-6 * (std::fabs(x[k]) + std::fabs(lower) + std::fabs(upper));
    setup.region_lower[k] = static_cast<float>(lower - slack);
    setup.region_upper[k] = static_cast<float>(upper + slack);
  }
  const NodeTest test_children = use_avx_ ? node_test_avx : test_children_sse;

  const bool prefetch = prefetch_;
  StackEntry stack[kStackCapacity];
  int top = 0;
  stack[top++] = {0, 0.0f, 1.0f};
  uint64_t nodes_visited = 0, triangles_tested = 0, cuts = 0;
  ChildRanges ranges;

  while (top > 0) {
    const StackEntry entry = stack[--top];
    // Skip what cuts found since the push have covered. (Before the first cut the whole
    // segment is visible and every pushed range, within [0,1], overlaps it.)
    if (cuts != 0 &&
        !out.overlaps(entry.t_lower - kProjectionSlack, entry.t_upper + kProjectionSlack))
      continue;

    if (entry.code & kLeafFlag) {
      // Leaf: exact crossings in double.
      uint32_t first = (entry.code & ~kLeafFlag) >> kCountBits;
      uint32_t count = (entry.code & ((1u << kCountBits) - 1)) + 1;
      for (uint32_t i = first; i < first + count; ++i) {
        ++triangles_tested;
        std::optional<Interval> cut = occluder_cut(*shadow, triangles_[i]);
        if (!cut) continue;
        ++cuts;
        out.subtract(cut->lo, cut->hi);
        if (out.fully_occluded()) {
          top = 0;  // nothing stays visible: done
          break;
        }
      }
      continue;
    }

    const Node& node = nodes_[entry.code];
    ++nodes_visited;
    unsigned mask = test_children(node, setup, ranges);
    if (mask == 0) continue;

    // Surviving children, nearest to x first. (Whether their projection is already occluded
    // is checked when they are popped.)
    int order[kWidth];
    int kept = 0;
    for (; mask != 0; mask &= mask - 1) {
      const int slot = __builtin_ctz(mask);
      int position = kept++;
      while (position > 0 && ranges.depth_lower[order[position - 1]] > ranges.depth_lower[slot]) {
        order[position] = order[position - 1];
        --position;
      }
      order[position] = slot;
    }
    // Push far to near so the nearest is popped first.
    for (int i = kept - 1; i >= 0; --i) {
      const int slot = order[i];
      const uint32_t code = node.child[slot];
      stack[top++] = {code, ranges.t_lower[slot], ranges.t_upper[slot]};
      // Start loading it now: the walk is bound by memory on large scenes (small ones stay in
      // cache, and the prefetches would only cost instructions).
      if (!prefetch) continue;
      if (code & kLeafFlag) {
        const char* leaf =
            reinterpret_cast<const char*>(&triangles_[(code & ~kLeafFlag) >> kCountBits]);
        _mm_prefetch(leaf, _MM_HINT_T0);
        _mm_prefetch(leaf + 64, _MM_HINT_T0);
      } else {
        const char* child = reinterpret_cast<const char*>(&nodes_[code]);
        for (size_t line = 0; line < sizeof(Node); line += 64)
          _mm_prefetch(child + line, _MM_HINT_T0);
      }
    }
  }
  if (stats) {
    stats->nodes_visited += nodes_visited;
    stats->triangles_tested += triangles_tested;
    stats->cuts += cuts;
  }
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
