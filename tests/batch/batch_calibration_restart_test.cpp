// A seconds-budget batch on real processes (penumbra-coordinator, one penumbra-worker) whose
// coordinator is SIGKILLed and restarted twice: while the methods calibrate (their equal-time
// runs render their first passes), and once a run was given its pass count and renders on. The
// batch ends DONE; no sealed pass is lost across a restart; each equal-time run is bit for bit a
// local render of its method, spp and seed, and its compute seconds include the calibration's.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <optional>
#include <thread>

#include "tests/batch/batch_test_support.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

using testing::CoordinatorProcess;
using Clock = std::chrono::steady_clock;

// Every run's sealed passes, by job.
std::map<std::string, uint32_t> sealed_passes(const v1::BatchStatus& status) {
  std::map<std::string, uint32_t> passes;
  for (const v1::BatchMethodStatus& method : status.methods())
    for (const v1::BatchRun& run : method.runs())
      passes[run.job_id()] = run.job().passes_complete();
  return passes;
}

TEST(BatchCalibrationRestart, KillsWhileCalibratingAndWhileRenderingOnLoseNothing) {
  auto dir = testing::fresh_directory("batch-calibration-restart");
  std::string scene = testing::write_batch_scene(dir);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w1", 1);

  const double budget = 3.0;
  const std::string spec = R"({
    "format": "penumbra/batch@1", "name": "restarts", "scene": "batch-test.json",
    "methods": ["sa", "area"], "budget": {"seconds": )" +
                           std::to_string(budget) + R"(},
    "reference": {"method": "sa", "spp": 16}, "seed": 7, "repeats": 1})";
  std::string batch_id =
      BatchClient(coordinator.address()).submit(testing::batch_request(dir, spec)).batch_id();
  auto status_now = [&]() -> std::optional<v1::BatchStatus> {
    try {
      return BatchClient(coordinator.address()).status(batch_id);
    } catch (const FarmCallError&) {
      return std::nullopt;  // restarting
    }
  };
  // Waits until `ready` holds for the batch's status, then kills and restarts the coordinator
  // and checks that no run lost a sealed pass.
  auto kill_when = [&](const std::string& moment,
                       const std::function<bool(const v1::BatchStatus&)>& ready) {
    auto deadline = Clock::now() + std::chrono::seconds(120);
    std::optional<v1::BatchStatus> before;
    while (Clock::now() < deadline) {
      before = status_now();
      if (before && (ready(*before) || is_terminal(before->state()))) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    ASSERT_TRUE(before && ready(*before)) << "the batch went past the moment " << moment;
    coordinator.restart();
    std::optional<v1::BatchStatus> after = status_now();
    ASSERT_TRUE(after.has_value()) << "the restarted coordinator does not answer";
    EXPECT_NE(after->state(), v1::BATCH_STATE_FAILED) << after->error();
    std::map<std::string, uint32_t> resumed = sealed_passes(*after);
    for (const auto& [job, passes] : sealed_passes(*before))
      EXPECT_GE(resumed[job], passes) << job << ": sealed passes lost in the restart " << moment;
    std::printf("killed %s\n", moment.c_str());
  };

  kill_when("while calibrating", [](const v1::BatchStatus& status) {
    if (status.state() != v1::BATCH_STATE_CALIBRATING) return false;
    for (const v1::BatchMethodStatus& method : status.methods())
      if (method.seconds_per_pass() == 0 && method.runs_size() > 0 &&
          method.runs(0).job().passes_complete() > 0)
        return true;
    return false;
  });
  kill_when("while a calibrated run renders on", [](const v1::BatchStatus& status) {
    for (const v1::BatchMethodStatus& method : status.methods())
      if (method.seconds_per_pass() > 0 && method.runs_size() > 0 &&
          method.runs(0).job().state() == v1::JOB_STATE_RUNNING &&
          method.runs(0).job().passes_complete() > method.calibration_passes())
        return true;
    return false;
  });

  BatchClient client(coordinator.address());
  v1::BatchStatus status = testing::run_to_end(client, batch_id);
  ASSERT_EQ(status.state(), v1::BATCH_STATE_DONE) << status.error();
  for (const v1::BatchMethodStatus& method : status.methods()) {
    ASSERT_EQ(method.runs_size(), 1) << method.label();
    const v1::BatchRun& run = method.runs(0);
    EXPECT_EQ(method.calibration_job(), run.job_id()) << "the calibration is the run's start";
    ASSERT_EQ(run.job().state(), v1::JOB_STATE_DONE) << run.job().error();
    EXPECT_GT(method.calibration_passes(), 0u);
    EXPECT_EQ(run.calibration_passes(), method.calibration_passes());
    EXPECT_GT(run.first_pass_count(), method.calibration_passes());
    EXPECT_LE(run.first_pass_count(), run.job().passes_complete());
    EXPECT_EQ(run.job().passes_complete(), run.spp_planned()) << "the final count";
    EXPECT_GE(run.job().compute_seconds(),
              0.999 * method.seconds_per_pass() * method.calibration_passes())
        << "the run's compute seconds include its calibration";
    std::printf("%s: %u spp (%u calibrating), %.3f compute s\n", method.label().c_str(),
                run.job().passes_complete(), method.calibration_passes(),
                run.job().compute_seconds());
    Image color = decode_exr(client.fetch_result(run.job_id()));
    Film local = testing::render_locally(scene, method.method(), "stratified",
                                         run.job().passes_complete(), run.seed());
    EXPECT_TRUE(testing::same_bits(color, local.color)) << method.label() << ": image differs";
  }
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
