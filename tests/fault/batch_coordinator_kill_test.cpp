// Fault: the coordinator SIGKILLed at random moments while a batch (penumbra.v1.Batches) runs
// (each kill once its jobs have sealed a random number of passes more, with one part-way),
// restarted each time on its data directory and port. Sealed passes are never lost across a
// restart; the batch resumes and ends DONE; its reference job and every run are bit-identical to
// local renders of the same method, spp and seed.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <random>

#include "fault_support.h"
#include "proto/support/batch_client.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultBatchCoordinatorKill, RandomKillsDuringABatchLoseNothing) {
  CoordinatorKillFarm farm("fault-batch-kill");
  const std::string& address = farm.address;

  // spp levels only (no calibration): every run's pass count, and so its image, is fixed.
  const std::string spec = R"({
    "format": "penumbra/batch@1", "name": "fault-batch", "scene": "farm-test.json",
    "methods": ["sa"], "budget": {"spp": [32, 128]},
    "reference": {"method": "sa", "sampler": "stratified", "spp": 256, "seed": 9},
    "seed": 3, "repeats": 2
  })";
  std::string batch_id;
  {
    BatchClient client(address);
    batch_id =
        client
            .submit(make_batch_request_from_text(spec, "fault-batch.json", farm.dir.string(),
                                                 [](const std::string& name) { return name; }))
            .batch_id();
  }
  auto batch_status = [&]() -> std::optional<v1::BatchStatus> {
    try {
      return BatchClient(address).status(batch_id);
    } catch (const FarmCallError&) {
      return std::nullopt;  // restarting
    }
  };

  // Each kill comes after 1-64 more passes sealed since the last start with a job of the batch
  // part-way (the reference seals 8 passes per block; a run about a quarter of its passes: 8 for
  // 32 spp, 32 for 128). The batch has 576 passes (reference 256, runs 2 x (32 + 128)); 5 kills
  // use at most 5 x (64 + 32) of them, a block or two per kill sealed while the test looked
  // included, so the batch outlasts the kills on any machine and they fall in the reference and
  // in the runs.
  std::mt19937 random(1907);
  const int wanted_kills = 5;
  // The batch's state, asked at most every 50 ms (a new channel each time: it survives restarts).
  auto last_ask = Clock::now() - 1s;
  bool ended = false;
  auto batch_ended = [&] {
    if (!ended && Clock::now() - last_ask >= 50ms) {
      last_ask = Clock::now();
      auto status = batch_status();
      ended = status && is_terminal(status->state());
    }
    return ended;
  };
  auto start = Clock::now();
  int kills = kill_coordinator_on_progress(
      farm.coordinator, wanted_kills, 64, random, [](const FarmProgress&) {}, batch_ended,
      [&] {
        auto status = batch_status();
        ASSERT_TRUE(status.has_value()) << "the restarted coordinator does not know the batch";
        EXPECT_NE(status->state(), v1::BATCH_STATE_FAILED) << status->error();
      },
      180s);
  std::printf("%d coordinator kills during the batch in %.1f s\n", kills, seconds_since(start));
  EXPECT_EQ(kills, wanted_kills) << (batch_ended() ? "the batch ended before the last kill"
                                                   : "the kills took longer than 180 s");

  std::optional<v1::BatchStatus> final;
  auto deadline = Clock::now() + 60s;
  while (Clock::now() < deadline) {
    final = batch_status();
    if (final && is_terminal(final->state())) break;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(final.has_value());
  ASSERT_EQ(final->state(), v1::BATCH_STATE_DONE) << final->error();

  std::vector<SubmittedJob> jobs;
  jobs.push_back({final->reference().job_id(), "sa", 256, 9});
  for (const v1::BatchMethodStatus& method : final->methods())
    for (const v1::BatchRun& run : method.runs())
      jobs.push_back({run.job_id(), method.method(), run.spp_planned(), run.seed()});
  EXPECT_EQ(jobs.size(), 5u) << "a reference and 2 spp levels x 2 repeats";
  FaultRow row{"coordinator SIGKILL + restart during a batch", kills};
  check_jobs(address, farm.scene, jobs, row);
  record_fault_row(row);
  EXPECT_EQ(row.lost_jobs, 0);
  EXPECT_EQ(row.mismatched_images, 0);
}

}  // namespace
}  // namespace penumbra::farm::fault
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
