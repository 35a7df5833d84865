// SQLite store: what is written survives reopening; sealing replaces task results by tile sums.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/store.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

namespace penumbra::farm {
namespace {

std::string fresh_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() /
             ("penumbra_store_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir.string();
}

TEST(Store, JobsScenesAndResultsSurviveReopening) {
  std::string dir = fresh_dir("reopen");
  JobRecord job;
  job.spec = std::string("spec\0bytes", 10);
  job.priority = 3;
  job.state = 1;
  job.submitted_unix_ms = 1234;
  {
    Store store(dir);
    store.put_scene("abc", std::string("pkg\0", 4));
    job.id = store.add_job(job);
    EXPECT_EQ(store.add_job(job), job.id + 1);
    job.blocks_opened = 4;
    job.compute_seconds = 2.5;
    store.update_job(job);
    store.add_task_result(job.id, {17, "tile-17", 0.5});
    store.add_task_result(job.id, {18, "tile-18", 0.25});
    job.state = 3;
    store.finish_job(job, "exr-bytes");
  }
  Store store(dir);
  EXPECT_EQ(store.scene("abc"), std::string("pkg\0", 4));
  EXPECT_FALSE(store.scene("missing").has_value());
  auto jobs = store.jobs();
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].id, job.id);
  EXPECT_EQ(jobs[0].spec, job.spec);
  EXPECT_EQ(jobs[0].priority, 3);
  EXPECT_EQ(jobs[0].state, 3);
  EXPECT_EQ(jobs[0].blocks_opened, 4u);
  EXPECT_DOUBLE_EQ(jobs[0].compute_seconds, 2.5);
  EXPECT_EQ(jobs[0].submitted_unix_ms, 1234);
  auto results = store.task_results(job.id);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0].task_index, 17u);
  EXPECT_EQ(results[1].tile, "tile-18");
  EXPECT_EQ(store.result(job.id), "exr-bytes");
  EXPECT_FALSE(store.result(jobs[1].id).has_value());
  std::filesystem::remove_all(dir);
}

TEST(Store, SealingReplacesTaskResultsWithTileSums) {
  std::string dir = fresh_dir("seal");
  Store store(dir);
  JobRecord job;
  job.id = store.add_job(job);
  for (uint64_t task = 0; task < 6; ++task) store.add_task_result(job.id, {task, "r", 0.1});
  job.blocks_sealed = 1;
  store.seal_block(job, {{0, "sum0"}, {1, "sum1"}, {2, "sum2"}}, 0, 3,
                   CurvePoint{8, 1.5, 2.0, 0.25, {{"shadow", 0.5}, {"corner", 0.125}}});
  auto results = store.task_results(job.id);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_EQ(results[0].task_index, 3u);
  auto tiles = store.tiles(job.id);
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[2], "sum2");
  store.seal_block(job, {{2, "sum2b"}}, 3, 6, std::nullopt);
  EXPECT_EQ(store.tiles(job.id)[2], "sum2b");
  EXPECT_TRUE(store.task_results(job.id).empty());
  auto curve = store.curve(job.id);
  ASSERT_EQ(curve.size(), 1u);
  EXPECT_EQ(curve[0].passes, 8u);
  EXPECT_DOUBLE_EQ(curve[0].mrse, 0.25);
  EXPECT_EQ(curve[0].regions,
            (std::vector<std::pair<std::string, double>>{{"corner", 0.125}, {"shadow", 0.5}}));
  EXPECT_EQ(store.jobs()[0].blocks_sealed, 1u);
  store.drop_work(job);
  EXPECT_TRUE(store.tiles(job.id).empty());
  std::filesystem::remove_all(dir);
}

TEST(Store, ConcurrentTaskResultsAreAllCommitted) {
  std::string dir = fresh_dir("group");
  Store store(dir);
  JobRecord job;
  job.id = store.add_job(job);
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (uint64_t i = 0; i < 50; ++i)
        store.add_task_result(job.id,
                              {uint64_t(t) * 1000 + i, std::string(100, char('a' + t)), 0.5});
    });
  for (auto& thread : threads) thread.join();
  auto results = store.task_results(job.id);
  ASSERT_EQ(results.size(), 400u);
  double seconds = 0;
  for (const auto& result : results) {
    seconds += result.compute_seconds;
    EXPECT_EQ(result.tile, std::string(100, char('a' + result.task_index / 1000)));
  }
  EXPECT_DOUBLE_EQ(seconds, 200.0);
  std::filesystem::remove_all(dir);
}

TEST(Store, UnwritableDirectoryIsReported) {
  EXPECT_THROW(Store("/proc/penumbra-cannot-write-here"), std::runtime_error);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
