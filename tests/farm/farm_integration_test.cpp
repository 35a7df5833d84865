// The farm end to end on loopback with real processes: penumbra-coordinator and penumbra-worker
// binaries, a client through the jobs API. Every finished image is compared bit for bit with a
// render of the same job in this process (Renderer + assemble_film, other tiles and pass ranges).
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "farm_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::CoordinatorProcess;

void expect_bit_identical(FarmClient& client, const std::string& job_id,
                          const std::string& scene_path, const std::string& method, uint32_t spp,
                          uint64_t seed) {
  ImageMetadata metadata;
  Image variance;
  Image color = decode_exr(client.fetch(job_id), &metadata, &variance);
  Film local = testing::render_locally(scene_path, method, "stratified", spp, seed);
  EXPECT_TRUE(testing::same_bits(color, local.color)) << job_id << ": color differs";
  EXPECT_TRUE(testing::same_bits(variance, local.variance)) << job_id << ": variance differs";
  EXPECT_EQ(metadata["penumbra:spp"], std::to_string(spp));
  EXPECT_EQ(metadata["penumbra:method"], method);
}

v1::JobStatus wait_until(FarmClient& client, const std::string& job_id,
                         const std::function<bool(const v1::JobStatus&)>& condition,
                         std::chrono::milliseconds timeout = 60s) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    v1::JobStatus status = client.status(job_id);
    if (condition(status)) return status;
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error(job_id + ": condition not reached in time; state " +
                               v1::JobState_Name(status.state()));
    std::this_thread::sleep_for(10ms);
  }
}

TEST(FarmIntegration, TwoWorkersRenderBitIdenticalToLocal) {
  auto dir = testing::fresh_directory("two-workers");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker_a = testing::start_worker(coordinator.address(), dir, "a");
  auto worker_b = testing::start_worker(coordinator.address(), dir, "b");
  FarmClient client(coordinator.address());
  auto submitted = client.submit(testing::job_spec(scene, "sa", 16, 7));
  std::vector<v1::JobStatus> events;
  v1::JobStatus final_status = client.watch(
      submitted.job_id(), [&](const v1::JobStatus& s) { events.push_back(s); }, 60s);
  ASSERT_EQ(final_status.state(), v1::JOB_STATE_DONE) << final_status.error();
  EXPECT_EQ(final_status.passes_complete(), 16u);
  EXPECT_EQ(final_status.tiles_total(), 12u);  // 64x48 in 16x16 tiles
  EXPECT_EQ(final_status.tiles_complete(), 12u);
  EXPECT_EQ(final_status.tasks_complete(), 48u);  // 12 tiles x 4 blocks of 4 passes
  EXPECT_GT(final_status.compute_seconds(), 0.0);
  ASSERT_GE(events.size(), 2u);
  for (size_t i = 1; i < events.size(); ++i)
    EXPECT_GE(events[i].tasks_complete(), events[i - 1].tasks_complete());
  expect_bit_identical(client, submitted.job_id(), scene, "sa", 16, 7);
  auto workers = client.workers();
  ASSERT_EQ(workers.size(), 2u);
  uint64_t completed = 0;
  for (const auto& worker : workers) completed += worker.tasks_completed();
  EXPECT_EQ(completed, 48u);
}

}  // namespace
}  // namespace penumbra::farm
