// The coordinator's core without gRPC or a renderer: fake workers lease tasks and complete them
// with synthetic tiles whose values depend on pixel and pass, so the assembled image is known.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/coordinator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <thread>

#include "core/image/metrics.h"
#include "fake_worker.h"
#include "farm_test_support.h"
#include "proto/support/scene_packing.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;

using testing::fake_radiance;
using testing::fake_render;

Film expected_film(int width, int height, uint32_t spp) {
  std::vector<TileAccumulator> tiles;
  TileRect rect{0, 0, width, height};
  tiles.emplace_back(rect);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (uint32_t pass = 0; pass < spp; ++pass)
        tiles.back().add_sample(int64_t(y) * width + x, fake_radiance(x, y, pass));
  return assemble_film(width, height, tiles);
}

class CoordinatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::fresh_directory("coordinator-unit");
    scene_path_ = testing::write_scene(dir_, 40, 24);
    options_.data_dir = (dir_ / "data").string();
    options_.lease_time = 200ms;
    // The fake workers do not heartbeat: here leases expire (after 200 ms) before a silent
    // worker would be declared dead (4.5 heartbeats of 67 ms); the dead-worker test sets its own.
    options_.missed_heartbeats = 4;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::unique_ptr<Coordinator> make() {
    return std::make_unique<Coordinator>(options_, parse_wire_package);
  }
  std::string register_worker(Coordinator& coordinator, const std::string& name) {
    return testing::register_fake_worker(coordinator, name);
  }
  std::vector<v1::Task> lease(Coordinator& coordinator, const std::string& worker, uint32_t n) {
    return testing::lease_tasks(coordinator, worker, n);
  }
  bool complete(Coordinator& coordinator, const std::string& worker, const v1::Task& task,
                double seconds = 0.01) {
    return testing::complete_fake_task(coordinator, worker, task, seconds);
  }
  v1::JobSpec spec(uint32_t spp) {
    // tiles of 16: 40x24 -> 3 x 2 = 6 tiles; 4 passes per task.
    return testing::job_spec(scene_path_, "sa", spp, 1, 16, 4);
  }

  std::filesystem::path dir_;
  std::string scene_path_;
  CoordinatorOptions options_;
};

TEST_F(CoordinatorTest, CompletionsInAnyOrderAssembleTheExactImage) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "fake");
  std::string job = coordinator->submit(spec(10)).job_id();  // blocks of 4, 4, 2 passes
  std::vector<v1::Task> tasks = lease(*coordinator, worker, 100);
  ASSERT_EQ(tasks.size(), 18u);
  EXPECT_EQ(tasks.back().pass_begin(), 8u);
  EXPECT_EQ(tasks.back().pass_end(), 10u);
  // Complete in reverse order: blocks seal only once every tile has finished them.
  for (auto it = tasks.rbegin(); it != tasks.rend(); ++it) {
    EXPECT_EQ(coordinator->status(job).passes_complete(), 0u);
    EXPECT_TRUE(complete(*coordinator, worker, *it));
    if (it->task_index() == 0) break;
  }
  v1::JobStatus status = coordinator->status(job);
  EXPECT_EQ(status.state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(status.passes_complete(), 10u);
  EXPECT_NEAR(status.compute_seconds(), 0.18, 1e-9);
  Film film = coordinator->result_film(job);
  Film expected = expected_film(40, 24, 10);
  EXPECT_TRUE(testing::same_bits(film.color, expected.color));
  EXPECT_TRUE(testing::same_bits(film.variance, expected.variance));
}

TEST_F(CoordinatorTest, ExpiredLeaseIsRequeuedAndItsLateResultDropped) {
  auto coordinator = make();
  std::string slow = register_worker(*coordinator, "slow");
  std::string fast = register_worker(*coordinator, "fast");
  std::string job = coordinator->submit(spec(4)).job_id();
  std::vector<v1::Task> held = lease(*coordinator, slow, 1);
  ASSERT_EQ(held.size(), 1u);
  // The slow worker neither heartbeats nor completes: after the lease time its task is queued
  // again (the coordinator's expiry thread runs every lease_time / 4).
  std::this_thread::sleep_for(400ms);
  std::vector<v1::Task> rest = lease(*coordinator, fast, 100);
  ASSERT_EQ(rest.size(), 6u);
  EXPECT_EQ(rest.front().task_index(), held[0].task_index()) << "requeued tasks go first";
  EXPECT_NE(rest.front().attempt_token(), held[0].attempt_token());
  EXPECT_FALSE(complete(*coordinator, slow, held[0])) << "a late result must be dropped";
  for (const v1::Task& task : rest) EXPECT_TRUE(complete(*coordinator, fast, task));
  EXPECT_FALSE(complete(*coordinator, fast, rest[0])) << "a duplicate must be dropped";
  EXPECT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
  EXPECT_TRUE(
      testing::same_bits(coordinator->result_film(job).color, expected_film(40, 24, 4).color));
}

TEST_F(CoordinatorTest, HeartbeatsKeepLeasesAndReportRevokedOnes) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  std::string job = coordinator->submit(spec(4)).job_id();
  std::vector<v1::Task> held = lease(*coordinator, worker, 2);
  for (int i = 0; i < 6; ++i) {
    std::this_thread::sleep_for(60ms);
    v1::HeartbeatRequest heartbeat;
    heartbeat.set_worker_id(worker);
    heartbeat.add_attempt_tokens(held[0].attempt_token());
    EXPECT_EQ(coordinator->heartbeat(heartbeat).revoked_tokens_size(), 0);
  }
  // 360 ms without a heartbeat for the second task: revoked. The first one is still valid.
  v1::HeartbeatRequest heartbeat;
  heartbeat.set_worker_id(worker);
  heartbeat.add_attempt_tokens(held[0].attempt_token());
  heartbeat.add_attempt_tokens(held[1].attempt_token());
  auto response = coordinator->heartbeat(heartbeat);
  ASSERT_EQ(response.revoked_tokens_size(), 1);
  EXPECT_EQ(response.revoked_tokens(0), held[1].attempt_token());
  EXPECT_TRUE(complete(*coordinator, worker, held[0]));
  coordinator->cancel(job);
  EXPECT_EQ(coordinator->heartbeat(heartbeat).revoked_tokens_size(), 2);
}

TEST_F(CoordinatorTest, ATaskFailingThreeTimesFailsTheJobWithTheWorkersError) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  std::string job = coordinator->submit(spec(4)).job_id();
  for (int attempt = 0; attempt < 3; ++attempt) {
    std::vector<v1::Task> tasks = lease(*coordinator, worker, 1);
    ASSERT_EQ(tasks.size(), 1u);
    EXPECT_EQ(tasks[0].task_index(), 0u);
    v1::FailTaskRequest failure;
    failure.set_worker_id(worker);
    failure.set_job_id(tasks[0].job_id());
    failure.set_task_index(tasks[0].task_index());
    failure.set_attempt_token(tasks[0].attempt_token());
    failure.set_error("out of cheese");
    coordinator->fail_task(failure);
  }
  v1::JobStatus status = coordinator->status(job);
  EXPECT_EQ(status.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(status.error().find("out of cheese"), std::string::npos) << status.error();
  EXPECT_TRUE(lease(*coordinator, worker, 10).empty());
  EXPECT_THROW(coordinator->result_exr(job), FarmError);
}

TEST_F(CoordinatorTest, RestartKeepsSealedBlocksAndCompletedTasks) {
  std::string job;
  std::string token_before_restart;
  {
    auto coordinator = make();
    std::string worker = register_worker(*coordinator, "w");
    job = coordinator->submit(spec(12)).job_id();
    std::vector<v1::Task> tasks = lease(*coordinator, worker, 100);
    ASSERT_EQ(tasks.size(), 18u);
    for (size_t i = 0; i < 8; ++i) EXPECT_TRUE(complete(*coordinator, worker, tasks[i]));
    EXPECT_EQ(coordinator->status(job).passes_complete(), 4u);  // block 0 sealed
    EXPECT_EQ(coordinator->status(job).tasks_complete(), 8u);
    token_before_restart = tasks[9].attempt_token();
  }
  auto coordinator = make();
  v1::JobStatus status = coordinator->status(job);
  EXPECT_EQ(status.passes_complete(), 4u);
  EXPECT_EQ(status.tasks_complete(), 8u);
  EXPECT_NEAR(status.compute_seconds(), 0.08, 1e-9) << "compute seconds lost in the restart";
  EXPECT_EQ(status.state(), v1::JOB_STATE_RUNNING);
  std::string worker = register_worker(*coordinator, "w");
  std::vector<v1::Task> tasks = lease(*coordinator, worker, 100);
  ASSERT_EQ(tasks.size(), 10u) << "only the unfinished tasks are queued again";
  for (const v1::Task& task : tasks) {
    EXPECT_GE(task.task_index(), 8u);
    EXPECT_NE(task.attempt_token(), token_before_restart);
    EXPECT_TRUE(complete(*coordinator, worker, task));
  }
  EXPECT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
  EXPECT_TRUE(
      testing::same_bits(coordinator->result_film(job).color, expected_film(40, 24, 12).color));
}

// Cancelling keeps the sealed blocks as the job's result: an image of exactly the sealed passes
// (bit for bit the image of a job of that spp), its spp in the metadata, fetchable and previewed,
// with the task and tile counts of the moment of cancellation, across a restart too.
TEST_F(CoordinatorTest, CancelKeepsTheSealedPassesAsAPartialResult) {
  std::string job;
  v1::JobStatus before;
  {
    auto coordinator = make();
    std::string worker = register_worker(*coordinator, "w");
    job = coordinator->submit(spec(12)).job_id();  // 3 blocks of 4 passes x 6 tiles
    std::vector<v1::Task> tasks = lease(*coordinator, worker, 100);
    ASSERT_EQ(tasks.size(), 18u);
    for (size_t i = 0; i < 9; ++i) EXPECT_TRUE(complete(*coordinator, worker, tasks[i]));
    before = coordinator->status(job);
    ASSERT_EQ(before.passes_complete(), 4u);
    ASSERT_EQ(before.tasks_complete(), 9u);
    EXPECT_EQ(before.tasks_leased(), 9u);
    EXPECT_EQ(coordinator->cancel(job), v1::JOB_STATE_CANCELLED);
    for (const v1::JobStatus& after : {coordinator->status(job), coordinator->list().front()}) {
      EXPECT_EQ(after.state(), v1::JOB_STATE_CANCELLED);
      EXPECT_EQ(after.error(), "") << "the state says it; the error repeated it";
      EXPECT_EQ(after.tasks_total(), before.tasks_total());
      EXPECT_EQ(after.tasks_complete(), before.tasks_complete());
      EXPECT_EQ(after.tiles_complete(), before.tiles_complete());
      EXPECT_EQ(after.passes_complete(), 4u);
      EXPECT_EQ(after.tasks_leased(), 0u);
      EXPECT_TRUE(after.has_result());
    }
    ImageMetadata metadata;
    Image variance;
    Image color = decode_exr(coordinator->result_exr(job), &metadata, &variance);
    Film expected = expected_film(40, 24, 4);
    EXPECT_TRUE(testing::same_bits(color, expected.color));
    EXPECT_TRUE(testing::same_bits(variance, expected.variance));
    EXPECT_EQ(metadata["penumbra:spp"], "4");
    EXPECT_EQ(metadata["penumbra:cancelled"], "after 4 of 12 planned passes");
    uint32_t passes = 0;
    EXPECT_TRUE(testing::same_bits(coordinator->preview_film(job, &passes).color, expected.color));
    EXPECT_EQ(passes, 4u);
    // A late result of the cancelled job is dropped.
    EXPECT_FALSE(complete(*coordinator, worker, tasks[10]));
  }
  auto coordinator = make();
  v1::JobStatus restarted = coordinator->status(job);
  EXPECT_EQ(restarted.state(), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(restarted.tasks_complete(), before.tasks_complete());
  EXPECT_EQ(restarted.tasks_total(), before.tasks_total());
  EXPECT_TRUE(restarted.has_result());
  EXPECT_TRUE(
      testing::same_bits(coordinator->result_film(job).color, expected_film(40, 24, 4).color));

  // Cancelled before any block was sealed: nothing to fetch, and the refusal says why.
  std::string early = coordinator->submit(spec(8)).job_id();
  coordinator->cancel(early);
  EXPECT_FALSE(coordinator->status(early).has_result());
  try {
    coordinator->result_exr(early);
    ADD_FAILURE() << "a result without sealed passes";
  } catch (const FarmError& error) {
    EXPECT_EQ(error.code(), FarmErrorCode::FailedPrecondition);
    EXPECT_NE(std::string(error.what()).find("before any pass was sealed"), std::string::npos)
        << error.what();
  }
}

// A finished job's preview is its image (the per-tile sums are released when it ends; the
// preview comes from the stored result), with the job's pass count.
TEST_F(CoordinatorTest, AFinishedJobsPreviewIsItsImage) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  std::string job = coordinator->submit(spec(8)).job_id();
  for (const v1::Task& task : lease(*coordinator, worker, 100))
    EXPECT_TRUE(complete(*coordinator, worker, task));
  ASSERT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
  uint32_t passes = 0;
  Film preview = coordinator->preview_film(job, &passes);
  EXPECT_EQ(passes, 8u);
  EXPECT_TRUE(testing::same_bits(preview.color, expected_film(40, 24, 8).color));
  EXPECT_GT(*std::max_element(preview.color.rgb.begin(), preview.color.rgb.end()), 0.f);
}

// A worker that stops calling is dead after two missed heartbeats (and half an interval): its
// tasks go to the others at once, long before its leases would expire, and its late results are
// dropped (the lease is the fence). Its name is refused to another process while it is alive,
// taken over once it is dead (a restart keeps its id), and it leaves the list after
// forget_worker_after.
TEST_F(CoordinatorTest, ADeadWorkersTasksAreReassignedAtItsFirstMissedHeartbeat) {
  options_.lease_time = 60s;  // expiry is not what reassigns here
  options_.heartbeat_interval = 600ms;
  // The default: dead at the first missed heartbeat, after 1.5 intervals of silence (900 ms;
  // the expiry thread looks every 150 ms). Two missed heartbeats would be 1.5 s.
  options_.missed_heartbeats = CoordinatorOptions{}.missed_heartbeats;
  options_.forget_worker_after = 1200ms;
  auto coordinator = make();
  const std::string dying = register_worker(*coordinator, "dying");
  const std::string alive = register_worker(*coordinator, "alive");
  EXPECT_EQ(dying, "dying") << "a worker's id is its name";
  EXPECT_THROW(register_worker(*coordinator, "dying"), FarmError) << "a live worker's name";
  std::string job = coordinator->submit(spec(4)).job_id();  // 6 tasks
  std::vector<v1::Task> lost = lease(*coordinator, dying, 3);
  const auto last_contact = std::chrono::steady_clock::now();
  ASSERT_EQ(lost.size(), 3u);
  for (const v1::Task& task : lease(*coordinator, alive, 3))
    EXPECT_TRUE(complete(*coordinator, alive, task));
  EXPECT_EQ(coordinator->status(job).tasks_leased(), 3u);
  // `alive` heartbeats every 5 ms; `dying` is silent. Its tasks come back once it is dead.
  while (coordinator->counters().workers_lost == 0 &&
         std::chrono::steady_clock::now() - last_contact < 3s) {
    std::this_thread::sleep_for(5ms);
    v1::HeartbeatRequest heartbeat;
    heartbeat.set_worker_id(alive);
    coordinator->heartbeat(heartbeat);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - last_contact).count();
  ASSERT_EQ(coordinator->counters().workers_lost, 1u);
  EXPECT_GE(seconds, 0.85) << "declared dead before a heartbeat was missed";
  EXPECT_LT(seconds, 1.35) << "not at the first missed heartbeat";
  EXPECT_EQ(coordinator->status(job).tasks_leased(), 0u);
  std::vector<v1::Task> reassigned = lease(*coordinator, alive, 3);
  ASSERT_EQ(reassigned.size(), 3u);
  EXPECT_EQ(coordinator->counters().workers_lost, 1u);
  for (const v1::WorkerInfo& worker : coordinator->workers())
    EXPECT_EQ(worker.alive(), worker.worker_id() == alive) << worker.worker_id();
  EXPECT_FALSE(complete(*coordinator, dying, lost[0])) << "the dead worker's result is late";
  for (const v1::Task& task : reassigned) EXPECT_TRUE(complete(*coordinator, alive, task));
  EXPECT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
  EXPECT_TRUE(
      testing::same_bits(coordinator->result_film(job).color, expected_film(40, 24, 4).color));
  // Dead, the name may be taken over (a restart keeps its id) ...
  EXPECT_EQ(register_worker(*coordinator, "dying"), "dying");
  // The leases stayed the fence: the old attempt tokens are revoked, whoever names them.
  v1::HeartbeatRequest stale;
  stale.set_worker_id(dying);
  for (const v1::Task& task : lost) stale.add_attempt_tokens(task.attempt_token());
  EXPECT_EQ(coordinator->heartbeat(stale).revoked_tokens_size(), 3);
  // ... and a dead worker is forgotten after forget_worker_after.
  const std::string gone = register_worker(*coordinator, "gone");
  bool listed = true;
  for (int i = 0; i < 100 && listed; ++i) {
    std::this_thread::sleep_for(50ms);
    listed = false;
    for (const v1::WorkerInfo& worker : coordinator->workers())
      listed |= worker.worker_id() == gone;
  }
  EXPECT_FALSE(listed) << "a dead worker stays listed";
}

// The scene reader's warnings travel in the job's status and EXR, or refuse the job under
// spec.strict; a reference of another scene (by scene_hash) is refused unless
// accept_reference_mismatch, which records a warning.
TEST_F(CoordinatorTest, SceneWarningsAndReferenceMismatchesAreCarriedOrRefused) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  std::string json = testing::small_scene_json(40, 24);
  json.replace(json.find("\"fov_y_deg\": 40"), 15, "\"fov_y_deg\": 40, \"fovy\": 30");
  std::ofstream(dir_ / "typo.json") << json;
  v1::JobSpec typo = testing::job_spec((dir_ / "typo.json").string(), "sa", 4, 1, 16, 4);
  v1::JobSpec strict = typo;
  strict.set_strict(true);
  try {
    coordinator->submit(strict);
    ADD_FAILURE() << "a scene with warnings passed spec.strict";
  } catch (const FarmError& error) {
    EXPECT_EQ(error.code(), FarmErrorCode::InvalidArgument);
    EXPECT_NE(std::string(error.what()).find("$.camera.fovy"), std::string::npos) << error.what();
  }
  std::string job = coordinator->submit(typo).job_id();
  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.warnings_size(), 1);
  EXPECT_NE(status.warnings(0).find("$.camera.fovy"), std::string::npos);
  for (const v1::Task& task : lease(*coordinator, worker, 100))
    EXPECT_TRUE(complete(*coordinator, worker, task));
  ImageMetadata metadata;
  const std::string exr = coordinator->result_exr(job);
  decode_exr(exr, &metadata);
  EXPECT_NE(metadata["penumbra:warnings"].find("$.camera.fovy"), std::string::npos);

  // `exr` is of the typo scene (another hash than spec(4)'s scene): refused as a reference,
  // as is the job itself; accepted on request with a warning.
  v1::JobSpec by_exr = spec(4);
  by_exr.set_reference_exr(exr);
  v1::JobSpec by_job = spec(4);
  by_job.set_reference_job(job);
  for (v1::JobSpec* refused : {&by_exr, &by_job}) {
    try {
      coordinator->submit(*refused);
      ADD_FAILURE() << "a reference of another scene was accepted";
    } catch (const FarmError& error) {
      EXPECT_EQ(error.code(), FarmErrorCode::InvalidArgument);
      EXPECT_NE(std::string(error.what()).find("another scene"), std::string::npos) << error.what();
    }
    refused->set_accept_reference_mismatch(true);
    v1::JobStatus accepted = coordinator->status(coordinator->submit(*refused).job_id());
    ASSERT_EQ(accepted.warnings_size(), 1);
    EXPECT_NE(accepted.warnings(0).find("another scene"), std::string::npos);
  }
  // The same scene's result is a reference without a word.
  v1::JobSpec same = typo;
  same.set_reference_job(job);
  EXPECT_EQ(coordinator->status(coordinator->submit(same).job_id()).warnings_size(), 1);
}

// Every curve point measures the scene's regions and the spec's (a batch's) besides the full
// image: exactly the MRSE of the image of that many passes there, also after a restart.
TEST_F(CoordinatorTest, CurvePointsCarryTheMrseOfEveryRegion) {
  const std::map<std::string, Region> regions = {{"shadow", {8, 8, 24, 24}},
                                                 {"left", {0, 0, 16, 24}}};
  const Image reference = expected_film(40, 24, 16).color;
  v1::JobSpec job_spec = spec(8);  // 2 blocks of 4 passes: curve points at 4 and 8 passes
  job_spec.set_reference_exr(encode_exr(reference, nullptr, {}));
  v1::BatchRegion* left = job_spec.add_regions();
  left->set_name("left");
  left->mutable_rect()->set_x1(16);
  left->mutable_rect()->set_y1(24);
  std::string job;
  auto check = [&](const v1::JobStatus& status) {
    ASSERT_EQ(status.curve_size(), 2);
    for (const v1::ErrorSample& point : status.curve()) {
      const auto expected =
          error_summary(expected_film(40, 24, point.passes()).color, reference, regions);
      EXPECT_EQ(point.mrse(), expected.at("image").mrse);
      ASSERT_EQ(point.regions_size(), 2) << point.passes();
      for (const v1::RegionError& error : point.regions())
        EXPECT_EQ(error.mrse(), expected.at(error.region()).mrse)
            << error.region() << " at " << point.passes();
    }
    bool final_left = false;
    for (const v1::RegionError& error : status.errors()) final_left |= error.region() == "left";
    EXPECT_TRUE(final_left) << "the final errors lack the spec's region";
  };
  {
    auto coordinator = make();
    std::string worker = register_worker(*coordinator, "w");
    v1::JobSpec outside = job_spec;
    outside.mutable_regions(0)->mutable_rect()->set_x1(41);
    try {
      coordinator->submit(outside);
      ADD_FAILURE() << "a region outside the image was accepted";
    } catch (const FarmError& error) {
      EXPECT_EQ(error.code(), FarmErrorCode::InvalidArgument);
      EXPECT_NE(std::string(error.what()).find("spec.regions[0].rect"), std::string::npos)
          << error.what();
    }
    job = coordinator->submit(job_spec).job_id();
    for (const v1::Task& task : lease(*coordinator, worker, 100))
      EXPECT_TRUE(complete(*coordinator, worker, task));
    ASSERT_EQ(coordinator->status(job).state(), v1::JOB_STATE_DONE);
    check(coordinator->status(job, true));
  }
  check(make()->status(job, true));
}

TEST_F(CoordinatorTest, SecondsBudgetOpensBlocksUntilTheBudgetIsSpent) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  v1::JobSpec seconds_spec = spec(1);
  seconds_spec.set_compute_seconds(1.0);
  std::string job = coordinator->submit(seconds_spec).job_id();
  // Each task costs 0.05 s: 6 tiles -> 0.3 s per block; blocks open while spent + in flight < 1.
  int guard = 0;
  while (coordinator->status(job).state() != v1::JOB_STATE_DONE && guard++ < 100) {
    std::vector<v1::Task> tasks = lease(*coordinator, worker, 3);
    ASSERT_FALSE(tasks.empty());
    for (const v1::Task& task : tasks) EXPECT_TRUE(complete(*coordinator, worker, task, 0.05));
  }
  v1::JobStatus status = coordinator->status(job);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(status.passes_complete() % 4, 0u);
  EXPECT_EQ(status.passes_complete(), status.passes_planned());
  EXPECT_GE(status.compute_seconds(), 1.0 - 1e-9);
  EXPECT_LE(status.compute_seconds(), 1.0 + 0.3 + 1e-9) << "at most one block past the budget";
  EXPECT_TRUE(testing::same_bits(coordinator->result_film(job).color,
                                 expected_film(40, 24, status.passes_complete()).color));
}

TEST_F(CoordinatorTest, AFullQueueRefusesNewJobsWithResourceExhausted) {
  options_.max_queued_tasks = 20;
  auto coordinator = make();
  coordinator->submit(spec(12));  // 18 tasks
  try {
    coordinator->submit(spec(4));  // 6 more
    ADD_FAILURE() << "the queue limit was not enforced";
  } catch (const FarmError& error) {
    EXPECT_EQ(error.code(), FarmErrorCode::ResourceExhausted);
  }
  EXPECT_EQ(coordinator->list().size(), 1u);
}

TEST_F(CoordinatorTest, MalformedResultsAreRefused) {
  auto coordinator = make();
  std::string worker = register_worker(*coordinator, "w");
  coordinator->submit(spec(4));
  std::vector<v1::Task> tasks = lease(*coordinator, worker, 2);
  v1::CompleteTaskRequest request;
  request.set_worker_id(worker);
  request.set_job_id(tasks[0].job_id());
  request.set_task_index(tasks[0].task_index());
  request.set_attempt_token(tasks[0].attempt_token());
  request.set_tile("garbage");
  EXPECT_THROW(coordinator->complete_task(request), FarmError);
  request.set_tile(fake_render(tasks[1]).serialize());  // another tile's rectangle
  EXPECT_THROW(coordinator->complete_task(request), FarmError);
  v1::Task short_task = tasks[0];
  short_task.set_pass_end(2);  // fewer passes than asked
  request.set_tile(fake_render(short_task).serialize());
  EXPECT_THROW(coordinator->complete_task(request), FarmError);
  EXPECT_TRUE(complete(*coordinator, worker, tasks[0]));
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
