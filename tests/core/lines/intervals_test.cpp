// IntervalList: subtraction of closed cuts against a point-membership reference, order
// independence, touching cuts, heap overflow, copies.

#include "core/lines/intervals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace penumbra {
namespace {

// Reference: t is visible when no cut contains it (cuts closed).
bool visible_by_reference(const std::vector<Interval>& cuts, double t) {
  for (const Interval& cut : cuts)
    if (cut.lo <= t && t <= cut.hi) return false;
  return true;
}

bool visible_in_list(const IntervalList& list, double t) {
  for (const Interval& piece : list)
    if (piece.lo < t && t < piece.hi) return true;
  return false;
}

void expect_well_formed(const IntervalList& list) {
  for (size_t i = 0; i < list.size(); ++i) {
    EXPECT_LT(list[i].lo, list[i].hi);
    EXPECT_GE(list[i].lo, 0.0);
    EXPECT_LE(list[i].hi, 1.0);
    if (i > 0) {
      EXPECT_LT(list[i - 1].hi, list[i].lo);  // disjoint, sorted, not touching
    }
  }
}

TEST(IntervalList, StartsFullyVisible) {
  IntervalList list;
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].lo, 0.0);
  EXPECT_EQ(list[0].hi, 1.0);
  EXPECT_DOUBLE_EQ(list.visible_length(), 1.0);
  EXPECT_FALSE(list.fully_occluded());
}

TEST(IntervalList, SubtractSplitsAndTrims) {
  IntervalList list;
  list.subtract(0.25, 0.5);
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0].hi, 0.25);
  EXPECT_EQ(list[1].lo, 0.5);
  list.subtract(-1, 0.1);
  EXPECT_EQ(list[0].lo, 0.1);
  list.subtract(0.9, 2);
  EXPECT_EQ(list[1].hi, 0.9);
  EXPECT_DOUBLE_EQ(list.visible_length(), 0.15 + 0.4);
  list.subtract(0.2, 0.6);  // covers the gap and trims both pieces
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0].hi, 0.2);
  EXPECT_EQ(list[1].lo, 0.6);
  list.subtract(0.0, 1.0);
  EXPECT_TRUE(list.fully_occluded());
  EXPECT_EQ(list.visible_length(), 0.0);
}

TEST(IntervalList, TouchingCutsLeaveNoGap) {
  IntervalList list;
  const double t = 0.1 + 0.2;  // not exactly representable in decimal
  list.subtract(0.0, t);
  list.subtract(t, 1.0);
  EXPECT_TRUE(list.fully_occluded());
  // The other order.
  list.reset();
  list.subtract(t, 1.0);
  list.subtract(0.0, t);
  EXPECT_TRUE(list.fully_occluded());
}

TEST(IntervalList, EmptyAndNanCutsChangeNothing) {
  IntervalList list;
  list.subtract(0.5, 0.5);
  list.subtract(0.7, 0.3);
  list.subtract(std::nan(""), 0.5);
  list.subtract(0.2, std::nan(""));
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list.visible_length(), 1.0);
}

TEST(IntervalList, OverlapsMatchesWhetherSubtractChangesTheList) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    // Few pieces (linear scans) or many (binary searches).
    IntervalList list;
    int cut_count = trial % 2 ? 6 : 30;
    for (int i = 0; i < cut_count; ++i) {
      double c = unit(rng), w = (trial % 2 ? 0.1 : 0.01) * unit(rng);
      list.subtract(c - w, c + w);
    }
    if (trial % 2 == 0) {
      EXPECT_GT(list.size(), 8u);
    }
    // Probe with random cuts and with cuts that end exactly on piece endpoints.
    std::vector<Interval> probes;
    for (int i = 0; i < 4; ++i) {
      double lo = unit(rng);
      probes.push_back({lo, lo + 0.05 * unit(rng)});
    }
    for (const Interval& piece : list) {
      probes.push_back({piece.hi, piece.hi + 0.01});
      probes.push_back({piece.lo - 0.01, piece.lo});
    }
    for (const Interval& probe : probes) {
      IntervalList changed = list;
      changed.subtract(probe.lo, probe.hi);
      bool same =
          changed.size() == list.size() && std::equal(changed.begin(), changed.end(), list.begin(),
                                                      [](const Interval& p, const Interval& q) {
                                                        return p.lo == q.lo && p.hi == q.hi;
                                                      });
      EXPECT_EQ(list.overlaps(probe.lo, probe.hi), !same);
    }
  }
}

TEST(IntervalList, RandomCutsAgreeWithPointMembershipAndOrder) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<Interval> cuts;
    int count = 1 + static_cast<int>(40 * unit(rng));
    for (int i = 0; i < count; ++i) {
      double c = 1.2 * unit(rng) - 0.1, w = 0.02 * unit(rng);
      cuts.push_back({c - w, c + w});
    }
    // Some cuts touch exactly.
    if (count > 2) cuts[1].lo = cuts[0].hi;
    IntervalList list;
    for (const Interval& cut : cuts) list.subtract(cut.lo, cut.hi);
    expect_well_formed(list);
    for (int i = 0; i < 200; ++i) {
      double t = unit(rng);
      EXPECT_EQ(visible_in_list(list, t), visible_by_reference(cuts, t)) << "t = " << t;
    }
    // Any order gives the same bits.
    std::shuffle(cuts.begin(), cuts.end(), rng);
    IntervalList shuffled;
    for (const Interval& cut : cuts) shuffled.subtract(cut.lo, cut.hi);
    ASSERT_EQ(shuffled.size(), list.size());
    for (size_t i = 0; i < list.size(); ++i) {
      EXPECT_EQ(shuffled[i].lo, list[i].lo);
      EXPECT_EQ(shuffled[i].hi, list[i].hi);
    }
  }
}

TEST(IntervalList, GrowsPastInlineCapacityAndCopies) {
  IntervalList list;
  const int pieces = 100;  // far past the inline capacity
  for (int i = 1; i < pieces; ++i) {
    double t = static_cast<double>(i) / pieces;
    list.subtract(t - 0.001, t + 0.001);
  }
  ASSERT_EQ(list.size(), static_cast<size_t>(pieces));
  EXPECT_NEAR(list.visible_length(), 1.0 - 0.002 * (pieces - 1), 1e-12);
  expect_well_formed(list);
  IntervalList copy = list;
  ASSERT_EQ(copy.size(), list.size());
  EXPECT_EQ(copy.visible_length(), list.visible_length());
  IntervalList moved = std::move(copy);
  EXPECT_EQ(moved.size(), list.size());
  // Back to a small list: reset reuses the storage.
  moved.reset(0.25, 0.75);
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved.visible_length(), 0.5);
  IntervalList small;
  small = list;
  EXPECT_EQ(small.size(), list.size());
}

}  // namespace
}  // namespace penumbra
