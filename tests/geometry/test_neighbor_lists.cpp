// NeighborLists: the shared radius search answers a smaller radius, a capped radius and the k
// nearest exactly as a search of its own would, whatever was kept, for any thread count.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stop_token>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using Pairs = std::vector<std::pair<float, std::uint32_t>>;

Pairs as_sorted_pairs(const NeighborList& list) {
  Pairs out;
  for (std::size_t j = 0; j < list.size(); ++j) out.emplace_back(list.sq_dists[j], list.indices[j]);
  std::sort(out.begin(), out.end());
  return out;
}

class NeighborListsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_ = test::random_box(4000, 0.3f, 7);
    for (int i = 0; i < 4000; i += 89) cloud_.xyz[i] = Vec3f::Constant(NAN);
    // 60 coincident points: a capped neighbourhood is cut there.
    for (int i = 1; i <= 60; ++i) cloud_.xyz[i] = cloud_.xyz[0];
    search_ = std::make_unique<NeighborSearch>(cloud_.xyz);
  }
  PointCloud cloud_;
  std::unique_ptr<NeighborSearch> search_;
};

TEST_F(NeighborListsTest, SmallerAndCappedRadiiMatchTheirOwnSearch) {
  const NeighborLists lists(cloud_.xyz, *search_, Neighborhood::Hybrid(0.06f, 50), 1 << 30);
  EXPECT_GT(lists.kept_points(), 3000u);
  NeighborList got, want;
  for (const Neighborhood hood : {Neighborhood::Radius(0.04f), Neighborhood::Hybrid(0.06f, 50),
                                  Neighborhood::Hybrid(0.05f, 8), Neighborhood::Radius(0.06f)}) {
    std::size_t nonempty = 0;
    for (std::size_t i = 0; i < cloud_.size(); ++i) {
      lists.find(i, hood, got);
      search_->find(cloud_.xyz[i], hood, want, /*sorted=*/false);
      ASSERT_EQ(as_sorted_pairs(got), as_sorted_pairs(want)) << hood.describe() << " point " << i;
      nonempty += !got.indices.empty();
    }
    EXPECT_GT(nonempty, 3500u) << hood.describe();
  }
  // A radius beyond the lists' is refused rather than answered short.
  EXPECT_THROW(lists.find(5, Neighborhood::Radius(0.07f), got), std::invalid_argument);
}

// view() answers with find()'s indices in find()'s order: the kept list itself at the lists'
// radius, the indices alone filtered for a smaller one, and a list that was not kept (a budget of
// a few lists) searched again into the scratch and filtered there in place.
TEST_F(NeighborListsTest, ViewIsFindsIndicesInItsOrderWhateverWasKept) {
  for (const std::size_t budget : {std::size_t(1) << 30, std::size_t(4096)}) {
    const NeighborLists lists(cloud_.xyz, *search_, Neighborhood::Hybrid(0.06f, 50), budget);
    NeighborList scratch, want;
    for (const Neighborhood hood : {Neighborhood::Radius(0.04f), Neighborhood::Hybrid(0.06f, 50),
                                    Neighborhood::Hybrid(0.05f, 8), Neighborhood::Radius(0.06f)})
      for (std::size_t i = 0; i < cloud_.size(); ++i) {
        scratch.indices.assign(7, 12345u);  // stale contents must not leak into the answer
        const std::span<const std::uint32_t> got = lists.view(i, hood, scratch);
        lists.find(i, hood, want);
        ASSERT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), want.indices)
            << hood.describe() << " point " << i << " budget " << budget;
      }
    EXPECT_THROW(lists.view(5, Neighborhood::Radius(0.07f), scratch), std::invalid_argument);
  }
}

TEST_F(NeighborListsTest, WhatIsKeptChangesNeitherTheSetsNorTheirOrder) {
  const Neighborhood hood = Neighborhood::Hybrid(0.05f, 50);
  const NeighborLists all(cloud_.xyz, *search_, hood, 1 << 30, RunContext{2});
  const NeighborLists some(cloud_.xyz, *search_, hood, 200'000, RunContext{1});
  const NeighborLists none(cloud_.xyz, *search_, hood, 0, RunContext{1});
  EXPECT_LT(some.kept_points(), all.kept_points());
  EXPECT_GT(some.kept_points(), 0u);
  EXPECT_EQ(none.kept_points(), 0u);
  NeighborList a, b, c;
  for (std::size_t i = 0; i < cloud_.size(); ++i) {
    all.find(i, Neighborhood::Radius(0.03f), a);
    some.find(i, Neighborhood::Radius(0.03f), b);
    none.find(i, Neighborhood::Radius(0.03f), c);
    ASSERT_EQ(a.indices, b.indices) << i;  // the order too: FPFH sums follow it
    ASSERT_EQ(a.indices, c.indices) << i;
    ASSERT_EQ(a.sq_dists, c.sq_dists) << i;
  }
}

TEST_F(NeighborListsTest, ListsForASubsetAndItsNeighboursAnswerEveryPointAlike) {
  const Neighborhood hood = Neighborhood::Hybrid(0.05f, 50);
  // A corner of the box is wanted: its points and their neighbours are searched up front.
  std::vector<std::uint8_t> wanted(cloud_.size(), 0);
  for (std::size_t i = 0; i < cloud_.size(); ++i)
    wanted[i] = is_finite(cloud_.xyz[i]) && cloud_.xyz[i].x() < -0.1f && cloud_.xyz[i].y() < 0.0f;
  const NeighborLists all(cloud_.xyz, *search_, hood, 1 << 30, RunContext{2});
  const NeighborLists some(cloud_.xyz, *search_, hood, 1 << 30, wanted, RunContext{2});
  const NeighborLists one(cloud_.xyz, *search_, hood, 1 << 30, wanted, RunContext{1});
  std::size_t wanted_count = 0;
  for (std::uint8_t flag : wanted) wanted_count += flag;
  EXPECT_GT(some.kept_points(), wanted_count);  // their neighbours too
  EXPECT_LT(some.kept_points(), all.kept_points() / 2);
  EXPECT_EQ(some.kept_points(), one.kept_points());
  NeighborList a, b;
  for (std::size_t i = 0; i < cloud_.size(); ++i) {
    all.find(i, Neighborhood::Radius(0.04f), a);
    some.find(i, Neighborhood::Radius(0.04f), b);
    ASSERT_EQ(a.indices, b.indices) << i;  // kept or searched again: the same list, same order
    ASSERT_EQ(a.sq_dists, b.sq_dists) << i;
  }
  EXPECT_THROW(NeighborLists(cloud_.xyz, *search_, hood, 1 << 30,
                             std::vector<std::uint8_t>(cloud_.size() - 1, 1)),
               std::invalid_argument);
}

TEST_F(NeighborListsTest, NearestMatchesTheTreeAmongAllowedPoints) {
  const NeighborLists lists(cloud_.xyz, *search_, Neighborhood::Hybrid(0.08f, 50), 1 << 30);
  std::vector<std::uint8_t> allowed(cloud_.size(), 1);
  for (std::size_t i = 0; i < allowed.size(); i += 3) allowed[i] = 0;
  for (std::size_t i = 0; i < cloud_.size(); ++i)
    if (!is_finite(cloud_.xyz[i])) allowed[i] = 0;
  NeighborList got, want;
  std::size_t answered = 0, refused = 0;
  for (std::size_t i = 0; i < cloud_.size(); ++i) {
    if (!lists.nearest(i, 9, allowed, got)) {
      ++refused;
      continue;
    }
    ++answered;
    search_->find(cloud_.xyz[i], Neighborhood::Knn(9), allowed, want);
    ASSERT_EQ(got.indices, want.indices) << i;
    ASSERT_EQ(got.sq_dists, want.sq_dists) << i;
  }
  EXPECT_GT(answered, 3000u);
  // The cut list at the coincident points cannot answer: the caller searches.
  EXPECT_FALSE(lists.nearest(0, 9, allowed, got));
  // Too few allowed points within the radius: refused, not answered short.
  const std::vector<std::uint8_t> sparse(cloud_.size(), 0);
  EXPECT_FALSE(lists.nearest(100, 1, sparse, got));
  EXPECT_GT(refused, 0u);  // the coincident points' cut lists at least
}

TEST_F(NeighborListsTest, ThreadCountDoesNotMatter) {
  const Neighborhood hood = Neighborhood::Hybrid(0.05f, 50);
  const NeighborLists one(cloud_.xyz, *search_, hood, 300'000, RunContext{1});
  const NeighborLists two(cloud_.xyz, *search_, hood, 300'000, RunContext{2});
  EXPECT_EQ(one.kept_points(), two.kept_points());
  NeighborList a, b;
  for (std::size_t i = 0; i < cloud_.size(); ++i) {
    one.find(i, hood, a);
    two.find(i, hood, b);
    ASSERT_EQ(a.indices, b.indices) << i;
  }
}

TEST_F(NeighborListsTest, StopAndKnnAreRefused) {
  std::stop_source stop;
  stop.request_stop();
  EXPECT_THROW(NeighborLists(cloud_.xyz, *search_, Neighborhood::Radius(0.05f), 1 << 30,
                             RunContext{2, stop.get_token()}),
               Cancelled);
  EXPECT_THROW(NeighborLists(cloud_.xyz, *search_, Neighborhood::Knn(8), 1 << 30),
               std::invalid_argument);
}

}  // namespace
}  // namespace primlabel
