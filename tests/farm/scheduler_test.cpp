// Scheduler: priorities (higher first), FIFO among equal priorities and within a job, requeued
// tasks first.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/scheduler.h"

#include <gtest/gtest.h>

namespace penumbra::farm {
namespace {

std::vector<TaskRef> drain(Scheduler& scheduler) {
  std::vector<TaskRef> order;
  while (auto task = scheduler.next()) order.push_back(*task);
  return order;
}

TEST(Scheduler, HigherPriorityFirstThenSubmissionOrder) {
  Scheduler scheduler;
  scheduler.add_job(1, 0, 1);
  scheduler.add_job(2, 5, 2);
  scheduler.add_job(3, 0, 3);
  scheduler.add_job(4, 5, 4);
  for (uint64_t job : {1, 2, 3, 4})
    for (uint64_t task : {0, 1}) scheduler.enqueue({job, task});
  EXPECT_EQ(scheduler.queued_total(), 8u);
  std::vector<TaskRef> expected = {{2, 0}, {2, 1}, {4, 0}, {4, 1}, {1, 0}, {1, 1}, {3, 0}, {3, 1}};
  EXPECT_EQ(drain(scheduler), expected);
  EXPECT_EQ(scheduler.queued_total(), 0u);
}

TEST(Scheduler, RequeuedTaskGoesFirstWithinItsJob) {
  Scheduler scheduler;
  scheduler.add_job(7, 0, 1);
  for (uint64_t task = 0; task < 3; ++task) scheduler.enqueue({7, task});
  ASSERT_EQ(scheduler.next(), (TaskRef{7, 0}));
  scheduler.requeue({7, 0});
  std::vector<TaskRef> expected = {{7, 0}, {7, 1}, {7, 2}};
  EXPECT_EQ(drain(scheduler), expected);
}

TEST(Scheduler, LaterHighPriorityJobOvertakesQueuedWork) {
  Scheduler scheduler;
  scheduler.add_job(1, 0, 1);
  for (uint64_t task = 0; task < 4; ++task) scheduler.enqueue({1, task});
  ASSERT_EQ(scheduler.next(), (TaskRef{1, 0}));
  scheduler.add_job(2, 1, 2);
  scheduler.enqueue({2, 0});
  EXPECT_EQ(scheduler.next(), (TaskRef{2, 0}));
  EXPECT_EQ(scheduler.next(), (TaskRef{1, 1}));
}

TEST(Scheduler, RemovedJobLeavesNothingBehind) {
  Scheduler scheduler;
  scheduler.add_job(1, 0, 1);
  scheduler.add_job(2, 0, 2);
  scheduler.enqueue({1, 0});
  scheduler.enqueue({2, 0});
  scheduler.remove_job(1);
  EXPECT_EQ(scheduler.queued(1), 0u);
  EXPECT_EQ(scheduler.queued_total(), 1u);
  scheduler.requeue({1, 5});  // a late requeue of a removed job is ignored
  EXPECT_EQ(drain(scheduler), (std::vector<TaskRef>{{2, 0}}));
  EXPECT_THROW(scheduler.enqueue({9, 0}), std::logic_error);
}

// A batch's jobs (one group) are served one task each in turn, at the queue position of the
// group's first job; an ungrouped job submitted between them waits behind the whole group.
TEST(Scheduler, GroupedJobsAreServedRoundRobin) {
  Scheduler scheduler;
  scheduler.add_job(1, 0, 1, 9);
  scheduler.add_job(2, 0, 2);
  scheduler.add_job(3, 0, 3, 9);
  scheduler.add_job(4, 0, 4, 9);
  for (uint64_t task : {0, 1, 2}) scheduler.enqueue({1, task});
  for (uint64_t task : {0}) scheduler.enqueue({2, task});
  for (uint64_t task : {0, 1}) scheduler.enqueue({3, task});
  for (uint64_t task : {0, 1, 2}) scheduler.enqueue({4, task});
  std::vector<TaskRef> expected = {{1, 0}, {3, 0}, {4, 0}, {1, 1}, {3, 1},
                                   {4, 1}, {1, 2}, {4, 2}, {2, 0}};
  EXPECT_EQ(drain(scheduler), expected);
  // New tasks: the job served longest ago goes first; a requeued task goes first in its job.
  for (uint64_t task : {3, 4}) scheduler.enqueue({1, task});
  scheduler.enqueue({3, 2});
  ASSERT_EQ(scheduler.next(), (TaskRef{3, 2}));  // job 3 was served longest ago
  ASSERT_EQ(scheduler.next(), (TaskRef{1, 3}));
  scheduler.requeue({1, 3});
  std::vector<TaskRef> rest = {{1, 3}, {1, 4}};
  EXPECT_EQ(drain(scheduler), rest);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
