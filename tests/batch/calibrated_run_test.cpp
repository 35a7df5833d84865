// A batch's calibrated equal-time run in the coordinator's core, without gRPC or a renderer: a
// fake worker completes tasks with synthetic tiles. The run renders its seconds budget, waits for
// a pass count, renders on to it in larger blocks (and waits again until a count is final); its
// image is bit for bit the one of a plain job of that spp, its compute seconds count every task,
// and a restart at any point loses nothing. Also the store's checkpoints: sealed blocks whose sums
// are not written yet are merged again from their task results after a restart. Built only with the
// farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include "proto/support/scene_packing.h"
#include "server/batch_manager.h"
#include "server/coordinator.h"
#include "server/store.h"
#include "tests/batch/batch_test_support.h"
#include "tests/farm/fake_worker.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;

constexpr double kTaskSeconds = 0.01;  // what every fake task reports

class CalibratedRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::fresh_directory("calibrated-run");
    scene_path_ = testing::write_scene(dir_, 40, 24);  // tiles of 16: 6 tiles
    options_.data_dir = (dir_ / "data").string();
    options_.lease_time = 10s;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::unique_ptr<Coordinator> make() {
    auto coordinator = std::make_unique<Coordinator>(options_, parse_wire_package);
    worker_ = testing::register_fake_worker(*coordinator, "fake");
    return coordinator;
  }
  std::vector<v1::Task> lease(Coordinator& coordinator, uint32_t n = 1000) {
    return testing::lease_tasks(coordinator, worker_, n);
  }
  void complete(Coordinator& coordinator, const v1::Task& task) {
    ASSERT_TRUE(testing::complete_fake_task(coordinator, worker_, task, kTaskSeconds));
    ++tasks_completed_;
  }
  // Leases and completes tasks, `limit` at most, until nothing is left to lease.
  void work(Coordinator& coordinator, size_t limit = 100000) {
    for (size_t done = 0; done < limit;) {
      std::vector<v1::Task> tasks = lease(coordinator, uint32_t(std::min<size_t>(limit - done, 4)));
      if (tasks.empty()) return;
      for (const v1::Task& task : tasks) complete(coordinator, task);
      done += tasks.size();
    }
  }
  // A calibrated run: a seconds budget of 0.1 s, blocks of 2 passes (6 tasks, 0.06 s each), so
  // the calibration renders 2 blocks (4 passes) before the budget is spent.
  std::string submit_calibrated(Coordinator& coordinator) {
    v1::JobSpec spec = testing::job_spec(scene_path_, "sa", 1, 5, 16, 2);
    spec.set_compute_seconds(0.1);
    return coordinator.submit_in_batch(spec, "batch-1", true).job_id();
  }
  Film plain_job_film(Coordinator& coordinator, uint32_t spp) {
    std::string job =
        coordinator.submit(testing::job_spec(scene_path_, "sa", spp, 5, 16, 4)).job_id();
    work(coordinator);
    EXPECT_EQ(coordinator.status(job).state(), v1::JOB_STATE_DONE);
    return coordinator.result_film(job);
  }

  std::filesystem::path dir_;
  std::string scene_path_;
  CoordinatorOptions options_;
  std::string worker_;
  size_t tasks_completed_ = 0;
};

TEST_F(CalibratedRunTest, WaitsForItsPassCountThenRendersOnToTheSameImageAsAPlainJob) {
  auto coordinator = make();
  std::string job = submit_calibrated(*coordinator);
  EXPECT_FALSE(coordinator->awaits_pass_count(job));
  EXPECT_THROW(coordinator->set_pass_count(job, 20, 8), FarmError) << "still calibrating";
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(job));
  v1::JobStatus calibrated = coordinator->status(job);
  EXPECT_EQ(calibrated.state(), v1::JOB_STATE_RUNNING) << "it waits, it does not finish";
  EXPECT_EQ(calibrated.passes_complete(), 4u);
  EXPECT_NEAR(calibrated.compute_seconds(), 12 * kTaskSeconds, 1e-9);
  EXPECT_TRUE(lease(*coordinator).empty());

  // 21 passes: 4 rendered, then blocks of 8, 8 and 1 pass.
  coordinator->set_pass_count(job, 21, 8);
  EXPECT_FALSE(coordinator->awaits_pass_count(job));
  EXPECT_NO_THROW(coordinator->set_pass_count(job, 21, 8)) << "given again: nothing happens";
  std::vector<v1::Task> tasks = lease(*coordinator);
  ASSERT_EQ(tasks.size(), 18u);
  EXPECT_EQ(tasks.front().pass_begin(), 4u);
  EXPECT_EQ(tasks.front().pass_end(), 12u);
  EXPECT_EQ(tasks.back().pass_begin(), 20u);
  EXPECT_EQ(tasks.back().pass_end(), 21u);
  for (const v1::Task& task : tasks) complete(*coordinator, task);

  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_EQ(status.passes_complete(), 21u);
  EXPECT_EQ(status.spp_budget(), 21u);
  EXPECT_NEAR(status.compute_seconds(), 30 * kTaskSeconds, 1e-9)
      << "the run's compute seconds include its calibration passes";
  Film film = coordinator->result_film(job);
  Film plain = plain_job_film(*coordinator, 21);
  EXPECT_TRUE(testing::same_bits(film.color, plain.color));
  EXPECT_TRUE(testing::same_bits(film.variance, plain.variance));
}

TEST_F(CalibratedRunTest, ACountShortOfFinalWaitsAgainAndTheNextGoesOnFromThere) {
  auto coordinator = make();
  std::string job = submit_calibrated(*coordinator);
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(job));
  coordinator->set_pass_count(job, 15, 4, false);  // 4 rendered: blocks [4, 8), [8, 12), [12, 15)
  EXPECT_FALSE(coordinator->awaits_pass_count(job));
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(job)) << "a count short of final: it waits again";
  v1::JobStatus first = coordinator->status(job);
  EXPECT_EQ(first.state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(first.passes_complete(), 15u);
  EXPECT_NEAR(first.compute_seconds(), 30 * kTaskSeconds, 1e-9);
  // The final count goes on from pass 15 (the last block was a short one).
  coordinator->set_pass_count(job, 23, 5, true);
  std::vector<v1::Task> tasks = lease(*coordinator);
  ASSERT_EQ(tasks.size(), 12u);
  EXPECT_EQ(tasks.front().pass_begin(), 15u);
  EXPECT_EQ(tasks.front().pass_end(), 20u);
  EXPECT_EQ(tasks.back().pass_begin(), 20u);
  EXPECT_EQ(tasks.back().pass_end(), 23u);
  for (const v1::Task& task : tasks) complete(*coordinator, task);
  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_EQ(status.passes_complete(), 23u);
  EXPECT_NEAR(status.compute_seconds(), 42 * kTaskSeconds, 1e-9);
  EXPECT_TRUE(testing::same_bits(coordinator->result_film(job).color,
                                 plain_job_film(*coordinator, 23).color));
}

TEST_F(CalibratedRunTest, ACountBelowTheCalibrationsPassesEndsTheRunThere) {
  auto coordinator = make();
  std::string job = submit_calibrated(*coordinator);
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(job));
  coordinator->set_pass_count(job, 3, 8);
  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(status.passes_complete(), 4u);
  EXPECT_TRUE(testing::same_bits(coordinator->result_film(job).color,
                                 plain_job_film(*coordinator, 4).color));
}

TEST_F(CalibratedRunTest, OnlyAWaitingBatchRunTakesAPassCount) {
  auto coordinator = make();
  std::string plain = coordinator->submit(testing::job_spec(scene_path_, "sa", 8, 5)).job_id();
  EXPECT_FALSE(coordinator->awaits_pass_count(plain));
  try {
    coordinator->set_pass_count(plain, 16, 4);
    ADD_FAILURE() << "a plain job took a pass count";
  } catch (const FarmError& error) {
    EXPECT_EQ(error.code(), FarmErrorCode::FailedPrecondition);
    EXPECT_NE(std::string(error.what()).find("does not await a pass count"), std::string::npos)
        << error.what();
  }
  std::string job = submit_calibrated(*coordinator);
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(job));
  EXPECT_THROW(coordinator->set_pass_count(job, 0, 8), FarmError);
  EXPECT_THROW(coordinator->set_pass_count(job, 16, 0), FarmError);
  coordinator->cancel(job);
  EXPECT_THROW(coordinator->set_pass_count(job, 16, 8), FarmError) << "cancelled";
  v1::JobSpec spp_spec = testing::job_spec(scene_path_, "sa", 8, 5);
  EXPECT_THROW(coordinator->submit_in_batch(spp_spec, "batch-1", true), FarmError)
      << "a calibrated run starts with a seconds budget";
}

TEST_F(CalibratedRunTest, RestartsWhileWaitingAndWhileRenderingOnLoseNothing) {
  std::string job;
  {
    auto coordinator = make();
    job = submit_calibrated(*coordinator);
    work(*coordinator);
    ASSERT_TRUE(coordinator->awaits_pass_count(job));
  }
  {
    auto coordinator = make();
    ASSERT_TRUE(coordinator->awaits_pass_count(job)) << "still waiting after a restart";
    EXPECT_EQ(coordinator->status(job).passes_complete(), 4u);
    EXPECT_TRUE(lease(*coordinator).empty());
    coordinator->set_pass_count(job, 10, 3, false);  // 2 blocks of 3 more passes
    work(*coordinator);
    ASSERT_TRUE(coordinator->awaits_pass_count(job));
  }
  {
    auto coordinator = make();
    ASSERT_TRUE(coordinator->awaits_pass_count(job)) << "waits at its first count after a restart";
    EXPECT_EQ(coordinator->status(job).passes_complete(), 10u);
    coordinator->set_pass_count(job, 30, 2);  // 10 blocks of 2 more passes
    work(*coordinator, 6 * 4 + 3);            // 4 blocks sealed and half of the next
    EXPECT_EQ(coordinator->status(job).passes_complete(), 18u);
  }
  auto coordinator = make();
  EXPECT_FALSE(coordinator->awaits_pass_count(job));
  v1::JobStatus resumed = coordinator->status(job);
  EXPECT_EQ(resumed.passes_complete(), 18u) << "sealed passes lost in the restart";
  EXPECT_EQ(resumed.tasks_complete(), 6u * 8 + 3);
  EXPECT_NEAR(resumed.compute_seconds(), double(6 * 8 + 3) * kTaskSeconds, 1e-9);
  EXPECT_EQ(resumed.spp_budget(), 30u);
  work(*coordinator);
  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_EQ(status.passes_complete(), 30u);
  EXPECT_NEAR(status.compute_seconds(), 6 * 14 * kTaskSeconds, 1e-9);
  EXPECT_EQ(tasks_completed_, 6u * 14) << "no task rendered twice";
  EXPECT_TRUE(testing::same_bits(coordinator->result_film(job).color,
                                 plain_job_film(*coordinator, 30).color));
}

TEST_F(CalibratedRunTest, SealedBlocksBetweenCheckpointsAreMergedAgainAfterARestart) {
  options_.checkpoint_blocks = 3;
  std::string job;
  {
    auto coordinator = make();
    // 40 passes in blocks of 2: 20 blocks; the sums are written after blocks 3, 6, 9, ...
    job = coordinator->submit(testing::job_spec(scene_path_, "sa", 40, 5, 16, 2)).job_id();
    work(*coordinator, 6 * 11);  // 11 blocks: sums written up to block 9, 2 more sealed
    EXPECT_EQ(coordinator->status(job).passes_complete(), 22u);
  }
  {
    // The store: sums of 9 blocks, the task results of the 2 after them.
    Store store(options_.data_dir);
    std::vector<JobRecord> jobs = store.jobs();
    ASSERT_EQ(jobs.size(), 1u);
    EXPECT_EQ(jobs[0].blocks_sealed, 9u);
    EXPECT_NEAR(jobs[0].compute_seconds, 6 * 9 * kTaskSeconds, 1e-9);
    std::vector<TaskResultRecord> results = store.task_results(jobs[0].id);
    ASSERT_EQ(results.size(), 12u);
    EXPECT_EQ(results.front().task_index, 6u * 9);
    EXPECT_EQ(store.tiles(jobs[0].id).size(), 6u);
  }
  auto coordinator = make();
  v1::JobStatus resumed = coordinator->status(job);
  EXPECT_EQ(resumed.passes_complete(), 22u);
  EXPECT_NEAR(resumed.compute_seconds(), 6 * 11 * kTaskSeconds, 1e-9);
  work(*coordinator);
  ASSERT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(tasks_completed_, 6u * 20);
  EXPECT_TRUE(testing::same_bits(coordinator->result_film(job).color,
                                 plain_job_film(*coordinator, 40).color));
}

// A coordinator killed after a batch submitted its runs but before the batch was stored leaves
// jobs the stored batch never names (the batch then submits its runs again): the batch manager
// cancels them when it loads the batch, so that an equal-time job among them does not wait for
// a pass count forever. The jobs the batch does name are left alone.
TEST_F(CalibratedRunTest, JobsABatchNeverRecordedAreCancelledWhenItIsLoaded) {
  auto coordinator = make();
  BatchManagerOptions batch_options;
  batch_options.data_dir = options_.data_dir;
  batch_options.poll = 10ms;
  auto manager = std::make_unique<BatchManager>(*coordinator, parse_wire_package, batch_options);
  const std::string spec_json = R"({"format": "penumbra/batch@1", "name": "orphans", "scene": ")" +
                                scene_path_ + R"(", "methods": ["sa", "area"],
    "budget": {"seconds": 10}, "reference": {"method": "sa", "spp": 2}, "repeats": 1})";
  const std::string batch_id =
      manager->submit(testing::batch_request(dir_, spec_json), CallContext::of_client("tester"))
          .batch_id();
  // The reference renders; then the batch submits its equal-time runs and stores them.
  v1::BatchStatus status;
  for (int round = 0; round < 500; ++round) {
    work(*coordinator);
    status = manager->status(batch_id, false);
    if (status.methods_size() == 2 && status.methods(0).runs_size() > 0 &&
        status.methods(1).runs_size() > 0)
      break;
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(status.methods(1).runs_size(), 0) << v1::BatchState_Name(status.state());
  const std::string known = status.methods(0).runs(0).job_id();
  manager.reset();

  // What a killed coordinator could leave: a waiting run of this batch that it never recorded.
  v1::JobSpec spec = testing::job_spec(scene_path_, "sa", 1, 5, 16, 2);
  spec.set_compute_seconds(0.05);
  const std::string orphan = coordinator->submit_in_batch(spec, batch_id, true).job_id();
  work(*coordinator);
  ASSERT_TRUE(coordinator->awaits_pass_count(orphan));

  manager = std::make_unique<BatchManager>(*coordinator, parse_wire_package, batch_options);
  EXPECT_EQ(coordinator->status(orphan, false).state(), v1::JOB_STATE_CANCELLED);
  EXPECT_NE(coordinator->status(known, false).state(), v1::JOB_STATE_CANCELLED);
  const std::vector<std::string> unfinished = coordinator->unfinished_jobs_in_batch(batch_id);
  EXPECT_EQ(std::count(unfinished.begin(), unfinished.end(), orphan), 0);
  manager.reset();
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
