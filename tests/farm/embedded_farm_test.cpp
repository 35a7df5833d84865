// The embedded farm (what `penumbra demo` runs): a coordinator and workers in this process on a
// loopback port; its films are bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/embedded_farm.h"

#include <gtest/gtest.h>

#include "farm_test_support.h"

namespace penumbra::farm {
namespace {

TEST(EmbeddedFarm, RunsJobsAndReturnsTheirFilms) {
  auto dir = testing::fresh_directory("embedded");
  std::string scene = testing::write_scene(dir, 64, 48);
  EmbeddedFarmOptions options;
  options.workers = 2;
  options.threads_per_worker = 1;
  EmbeddedFarm farm(options);
  int events = 0;
  Film film = farm.run(testing::job_spec(scene, "sa", 12, 4, 32, 4),
                       [&](const v1::JobStatus&) { ++events; });
  EXPECT_GE(events, 1);
  Film local = testing::render_locally(scene, "sa", "stratified", 12, 4);
  EXPECT_TRUE(testing::same_bits(film.color, local.color));
  EXPECT_TRUE(testing::same_bits(film.variance, local.variance));
  // A failing job is reported, not hidden.
  EXPECT_THROW(farm.run(testing::job_spec(scene, "no-such-method", 4, 1)), FarmCallError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
