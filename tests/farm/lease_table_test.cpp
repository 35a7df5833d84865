// Lease table: tokens, extension by the holder only, expiry, stale tokens.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/lease_table.h"

#include <gtest/gtest.h>

#include <set>

namespace penumbra::farm {
namespace {

using std::chrono::milliseconds;

TEST(LeaseTable, ExpiresOnlyLeasesNotExtended) {
  LeaseTable leases(milliseconds(1000), 42);
  SteadyTime t0{};
  std::string a = leases.grant({1, 0}, "w1", t0);
  std::string b = leases.grant({1, 1}, "w2", t0);
  EXPECT_NE(a, b);
  EXPECT_TRUE(leases.extend(a, "w1", t0 + milliseconds(800)));
  auto expired = leases.expire(t0 + milliseconds(1500));
  ASSERT_EQ(expired.size(), 1u);
  EXPECT_EQ(expired[0].token, b);
  EXPECT_EQ(expired[0].task, (TaskRef{1, 1}));
  EXPECT_EQ(leases.size(), 1u);
  EXPECT_TRUE(leases.expire(t0 + milliseconds(1700)).empty());
  EXPECT_EQ(leases.expire(t0 + milliseconds(1900)).size(), 1u);
}

TEST(LeaseTable, OnlyTheHolderExtendsAndStaleTokensAreRefused) {
  LeaseTable leases(milliseconds(100), 1);
  SteadyTime t0{};
  std::string token = leases.grant({3, 9}, "w1", t0);
  EXPECT_FALSE(leases.extend(token, "w2", t0));
  ASSERT_TRUE(leases.release(token).has_value());
  EXPECT_FALSE(leases.release(token).has_value());  // a duplicate completion
  EXPECT_FALSE(leases.extend(token, "w1", t0));
  EXPECT_EQ(leases.find(token), nullptr);
}

TEST(LeaseTable, ReleaseJobAndCounts) {
  LeaseTable leases(milliseconds(100), 7);
  SteadyTime t0{};
  std::set<std::string> tokens;
  for (uint64_t task = 0; task < 5; ++task)
    tokens.insert(leases.grant({task % 2, task}, task < 3 ? "w1" : "w2", t0));
  EXPECT_EQ(tokens.size(), 5u);
  EXPECT_EQ(leases.count_for_worker("w1"), 3u);
  EXPECT_EQ(leases.count_for_job(0), 3u);
  EXPECT_EQ(leases.release_job(0).size(), 3u);
  EXPECT_EQ(leases.count_for_job(0), 0u);
  EXPECT_EQ(leases.size(), 2u);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
