// line-bd16 estimates per second per thread (Billen & Dutré 2016 line samples).
//
// Scene: a 1 x 1 quad light at height 2 above the plane z = 0, 20 floating boxes (12 triangles
// each) and 200 small random triangles between them; 256 shading points on the plane under the
// light, random view directions. Each iteration is one full estimate: offset sampling, the line
// query through LineQuery, and the closed-form integral of every visible interval. Rows:
// lambert, phong n = 100 and n = 10000, directions u and rand; plus the line integral alone
// (no visibility) for the same materials, to separate shading from the query.
//
// items_per_second is estimates per second on one thread.
// Run: build-*/bench/bd16_bench [--benchmark_filter=phong]

#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

#include "core/lines/bd16_estimator.h"
#include "core/lines/occluder_meshes.h"
#include "core/scene/light_setup.h"

namespace penumbra {
namespace {

using namespace occluder_meshes;

struct Fixture {
  Light light = make_quad_light({-0.5, -0.5, 2}, {1, 0, 0}, {0, -1, 0}, {5, 5, 5});
  TriangleMesh mesh;
  std::unique_ptr<LineQuery> query;
  struct Point {
    Vec3 x, n, wo;
  };
  std::vector<Point> points;

  Fixture() {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 20; ++i) {
      Vec3 lower{unit(rng) * 2 - 1.1, unit(rng) * 2 - 1.1, 0.4 + unit(rng)};
      Vec3 size{0.05 + 0.15 * unit(rng), 0.05 + 0.15 * unit(rng), 0.05 + 0.1 * unit(rng)};
      mesh.append(box_mesh(lower, lower + size));
    }
    mesh.append(random_triangles_mesh(200, {-1, -1, 0.3}, {1, 1, 1.6}, 0.1, 5));
    query = std::make_unique<LineQuery>(mesh.positions, mesh.indices);
    for (int i = 0; i < 256; ++i) {
      Vec3 x{unit(rng) * 2 - 1, unit(rng) * 2 - 1, 0};
      Vec3 wo = normalize(Vec3{unit(rng) - 0.5, unit(rng) - 0.5, 0.5 + unit(rng)});
      points.push_back({x, {0, 0, 1}, wo});
    }
  }
};

const Fixture& fixture() {
  static Fixture instance;
  return instance;
}

Material material_for(int exponent) {
  Material m;
  m.name = "bench";
  if (exponent == 0) {
    m.albedo = {0.7, 0.7, 0.7};
  } else {
    m.type = MaterialType::Phong;
    m.kd = {0.2, 0.2, 0.2};
    m.ks = {0.6, 0.6, 0.6};
    m.exponent = exponent;
  }
  return m;
}

// range(0): phong exponent (0 = lambert); range(1): direction mode (0 = u, 2 = rand);
// range(2): 1 with the line query, 0 without.
void BM_Bd16Estimate(benchmark::State& state) {
  const Fixture& f = fixture();
  Material material = material_for(static_cast<int>(state.range(0)));
  Bd16Direction mode = static_cast<Bd16Direction>(state.range(1));
  bool occluded = state.range(2) != 0;
  std::vector<Bd16LineSampler> samplers;
  for (const auto& p : f.points) samplers.emplace_back(f.light, material, p.x, p.n, p.wo, mode);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> offsets(4096);
  for (double& u : offsets) u = unit(rng);
  size_t i = 0;
  Rgb sum{0, 0, 0};
  for (auto _ : state) {
    const Bd16LineSampler& sampler = samplers[(i / 16) % samplers.size()];
    Vec2 direction_u{static_cast<double>((i / 16) % 97) / 97.0, 0};  // one per shading point
    double u = offsets[i % offsets.size()];
    sum += occluded ? sampler.estimate(u, direction_u, *f.query)
                    : sampler.estimate_unoccluded(u, direction_u);
    ++i;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}

BENCHMARK(BM_Bd16Estimate)
    ->ArgNames({"exponent", "mode", "query"})
    ->Args({0, 0, 1})
    ->Args({0, 2, 1})
    ->Args({100, 0, 1})
    ->Args({100, 2, 1})
    ->Args({10000, 0, 1})
    ->Args({10000, 2, 1})
    ->Args({0, 0, 0})
    ->Args({100, 0, 0})
    ->Args({10000, 0, 0});

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
