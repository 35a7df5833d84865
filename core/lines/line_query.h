#pragma once
// The shadow-triangle query of line sampling (Billen & Dutré 2016 Sec. 5.2; Salesin & Jarosz
// 2019 Sec. 4): which parts of a segment a->b on a light are visible from a shading point x.
// It is the cost centre of line sampling, so it has its own acceleration structure:
//
// - an 8-wide BVH (BVH8) built by Embree's rtcBuildBVH (SAH, MEDIUM quality by default) through
//   our own node callbacks, then flattened into one array of nodes with float boxes stored
//   structure-of-arrays, and leaf triangles stored contiguously in leaf order (float vertices
//   in canonical order, OccluderTriangle);
// - our own traversal, written once with GCC vector extensions (core/lines/lanes.h) and
//   compiled twice, for SSE2 and for AVX (chosen at run time; the same IEEE operations per
//   lane, so both make the same decisions bit for bit): the eight child boxes of a node are
//   tested together against the bounding box of the region that can hold a crossing, the
//   shadow triangle's plane, its side planes through x, the plane through the segment and
//   the self-occlusion plane near x, with a conservative float error bound; each surviving
//   child's box is projected from x onto the segment and skipped when that t-range is already
//   occluded (checked when it is popped); children are visited nearest to x first (near
//   occluders cut the most); the query stops as soon as nothing stays visible;
// - exact double-precision crossings at the leaves (core/lines/shadow_triangle.h, inlined
//   into both builds), watertight at shared edges, so the result equals
//   visible_intervals_brute_force.
//
// Thread safety: a built LineQuery is immutable; queries from many threads are fine.

#include <cstdint>
#include <vector>

#include "core/lines/intervals.h"
#include "core/lines/shadow_triangle.h"
#include "core/math/vec.h"

namespace penumbra {

struct Scene;

enum class LineQueryBuildQuality { Low, Medium, High };

struct LineQueryOptions {
  ShadowTriangleTolerances tolerances;
  // Embree's SAH builder quality. HIGH adds spatial splits (SBVH): a triangle may be referenced
  // by several leaves, each through the box of its part there (tighter for long, slanted
  // triangles; more memory).
  LineQueryBuildQuality build_quality = LineQueryBuildQuality::Medium;
  unsigned max_leaf_size = 4;  // triangles per leaf
  // Long slanted triangles enter the build as several pieces, each with a tight box (the leaves
  // still hold the whole triangle: the answers do not change, only which nodes are visited).
  bool split_long_triangles = true;
  // Run the traversal's AVX build when the CPU has AVX. The SSE2 build computes the same values
  // lane by lane (tests compare both): results and culling do not depend on it, only speed.
  bool allow_avx = true;
};

// Counters of one or more queries (for benchmarks and tests of the culling).
struct LineQueryStats {
  uint64_t nodes_visited = 0;     // inner nodes whose four children were tested
  uint64_t triangles_tested = 0;  // exact occluder_cut calls
  uint64_t cuts = 0;              // cuts subtracted
};

class LineQuery {
 public:
  // Builds from flat triangle arrays (3 indices per triangle into `positions`). Triangles of
  // zero area or with non-finite coordinates are dropped: they cannot occlude.
  LineQuery(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices,
            const LineQueryOptions& options = {});
  // Builds from a scene's occluder triangles (lights are not among them: they never occlude).
  explicit LineQuery(const Scene& scene, const LineQueryOptions& options = {});

  // The visible sub-intervals of t in [0,1] of the segment a + t (b - a) as seen from x. Every
  // occluder triangle crossing the shadow triangle (x, a, b) strictly between x and the segment
  // removes the interval its crossing projects to. Degenerate shadow triangles (a == b, x on
  // the segment's line) are answered with one shadow ray to the midpoint: all or nothing.
  // Non-finite input: nothing visible. `stats`, when given, is incremented.
  void visible_intervals(const Vec3& x, const Vec3& a, const Vec3& b, IntervalList& out,
                         LineQueryStats* stats = nullptr) const;

  // True when an occluder blocks the segment x->p, with the same tolerances as line queries
  // (a shadow ray through this structure).
  bool occluded(const Vec3& x, const Vec3& p) const;

  // Occluder triangles (after dropping those that cannot occlude).
  size_t triangle_count() const { return triangle_count_; }
  size_t node_count() const { return nodes_.size(); }
  // Bytes of the BVH's nodes and triangles.
  size_t memory_bytes() const {
    return nodes_.capacity() * sizeof(Node) + triangles_.capacity() * sizeof(OccluderTriangle);
  }
  const LineQueryOptions& options() const { return options_; }

  // One BVH8 node: the boxes of its eight children as centre and half extent (each box
  // contains the children's float boxes), structure-of-arrays so one AVX register (or two SSE
  // registers) holds one coordinate of all eight. Empty slots have a NaN centre (every test
  // rejects them).
  static constexpr int kWidth = 8;
  struct alignas(64) Node {
    float center[3][kWidth];  // [axis][child]
    float extent[3][kWidth];  // [axis][child], >= 0
    uint32_t child[kWidth];   // inner node index, or kLeafFlag | first << kCountBits | count - 1
  };
  // Read-only views of the BVH for other traversals of it (core/exact's shadow-pyramid query).
  const std::vector<Node>& nodes() const { return nodes_; }
  // The leaves' triangles in leaf order: a triangle split into pieces (split_long_triangles)
  // appears once in each leaf one of its pieces reached.
  const std::vector<OccluderTriangle>& triangles() const { return triangles_; }
  // True when queries run the AVX build (options().allow_avx and the CPU has AVX).
  bool uses_avx() const { return use_avx_; }
  static constexpr uint32_t kLeafFlag = 0x80000000u;
  static constexpr uint32_t kCountBits = 5;  // up to 32 triangles per leaf

 private:
  void build(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices);

  LineQueryOptions options_;
  std::vector<Node> nodes_;                  // nodes_[0] is the root
  std::vector<OccluderTriangle> triangles_;  // in leaf order
  size_t triangle_count_ = 0;
  Vec3 scene_max_abs_;     // per axis, the largest |coordinate| (float error bounds)
  bool prefetch_ = false;  // nodes and triangles exceed a typical L2 cache: prefetch children
  bool use_avx_ = false;
};

}  // namespace penumbra
