#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <random>
#include <stop_token>
#include <thread>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "test_util.hpp"

// As core/geometry/src/search/neighbor_search.cpp compiles it (ties lowest index first).
#define NANOFLANN_FIRST_MATCH
#include <nanoflann.hpp>

namespace primlabel {
namespace {

// Brute force reference: (sq_dist, index) pairs sorted like the search promises.
std::vector<std::pair<float, std::uint32_t>> brute_force(const std::vector<Vec3f>& pts,
                                                         const Vec3f& q) {
  std::vector<std::pair<float, std::uint32_t>> all;
  for (std::uint32_t i = 0; i < pts.size(); ++i)
    if (is_finite(pts[i])) all.emplace_back((pts[i] - q).squaredNorm(), i);
  std::sort(all.begin(), all.end());
  return all;
}

class NeighborSearchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_ = test::random_box(3000, 1.0f, 42);
    // Invalid points must never be returned.
    for (int i = 0; i < 3000; i += 97) cloud_.xyz[i] = Vec3f::Constant(NAN);
  }
  PointCloud cloud_;
};

TEST_F(NeighborSearchTest, RadiusMatchesBruteForce) {
  NeighborSearch search(cloud_.xyz);
  NeighborList found;
  const float r = 0.2f;
  for (int qi = 1; qi < 3000; qi += 151) {
    const Vec3f q = cloud_.xyz[qi];
    if (!is_finite(q)) continue;
    search.find(q, Neighborhood::Radius(r), found);
    auto expected = brute_force(cloud_.xyz, q);
    expected.erase(std::remove_if(expected.begin(), expected.end(),
                                  [&](auto& e) { return !(e.first < r * r); }),
                   expected.end());
    ASSERT_EQ(found.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(found.indices[i], expected[i].second);
      EXPECT_FLOAT_EQ(found.sq_dists[i], expected[i].first);
    }
    EXPECT_EQ(found.indices[0], static_cast<std::uint32_t>(qi));  // the query point itself
  }
}

TEST(NeighborSearch, SparseAndDenseCloudsAgreeWithBruteForce) {
  // A sparse cloud (cells far outnumber points) is answered by the k-d tree, a dense one by the
  // radius grid; both must return exactly the brute-force set, in distance order.
  for (const bool sparse : {true, false}) {
    PointCloud cloud = test::random_box(2000, 1.0f, 17);
    if (sparse)  // two dense blobs 100 apart: a grid over the bounding box would be mostly empty
      for (int i = 0; i < 2000; ++i) cloud.xyz[i].x() += i % 2 ? 50.0f : -50.0f;
    NeighborSearch search(cloud.xyz);
    NeighborList found;
    const float r = 0.15f;
    for (int qi = 0; qi < 2000; qi += 97) {
      const Vec3f q = cloud.xyz[qi];
      search.find(q, Neighborhood::Radius(r), found);
      auto expected = brute_force(cloud.xyz, q);
      expected.erase(std::remove_if(expected.begin(), expected.end(),
                                    [&](auto& e) { return !(e.first < r * r); }),
                     expected.end());
      ASSERT_EQ(found.size(), expected.size()) << (sparse ? "sparse" : "dense");
      for (std::size_t i = 0; i < expected.size(); ++i)
        EXPECT_EQ(found.indices[i], expected[i].second);
    }
  }
}

// The radius grid reads only the rows and x-spans its sphere reaches, in cells half the
// radius wide: points exactly on cell faces and at exactly the radius, near the origin and a
// kilometre away (where float rounding of the cell coordinates is coarsest), must all be found.
TEST(NeighborSearch, GridRowCullingMissesNoPointOnCellFacesOrAtTheRadius) {
  const float r = 0.03f;
  for (const float offset : {0.0f, 1000.0f}) {
    std::vector<Vec3f> points;
    const float step = r / 2.0f;  // the grid cell width: lattice points sit on cell faces
    for (int x = 0; x < 40; ++x)
      for (int y = 0; y < 40; ++y)
        for (int z = 0; z < 6; ++z)
          points.emplace_back(offset + step * float(x), -offset + step * float(y),
                              0.5f * offset + step * float(z));
    NeighborSearch search(points);
    NeighborList found;
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
    std::uniform_real_distribution<float> jitter(-step, step);
    for (int trial = 0; trial < 300; ++trial) {
      Vec3f q = points[pick(rng)];
      if (trial % 2) q += Vec3f(jitter(rng), jitter(rng), jitter(rng));
      search.find(q, Neighborhood::Radius(r), found, /*sorted=*/false);
      std::vector<std::uint32_t> expected;
      for (std::uint32_t i = 0; i < points.size(); ++i) {
        const float dx = q.x() - points[i].x(), dy = q.y() - points[i].y(),
                    dz = q.z() - points[i].z();
        if ((dx * dx + dy * dy) + dz * dz < r * r) expected.push_back(i);
      }
      std::vector<std::uint32_t> got = found.indices;
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, expected) << "offset " << offset << ", trial " << trial;
    }
  }
}

TEST_F(NeighborSearchTest, UnsortedRadiusHasTheSameSetAndIsRepeatable) {
  NeighborSearch search(cloud_.xyz);
  NeighborList sorted, unsorted, again;
  const Vec3f q = cloud_.xyz[5];
  search.find(q, Neighborhood::Radius(0.3f), sorted, true);
  search.find(q, Neighborhood::Radius(0.3f), unsorted, false);
  search.find(q, Neighborhood::Radius(0.3f), again, false);
  EXPECT_EQ(unsorted.indices, again.indices);
  auto a = sorted.indices, b = unsorted.indices;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
}

TEST_F(NeighborSearchTest, KnnMatchesBruteForce) {
  NeighborSearch search(cloud_.xyz);
  NeighborList found;
  for (int qi = 2; qi < 3000; qi += 211) {
    const Vec3f q = cloud_.xyz[qi] + Vec3f(0.001f, 0, 0);
    search.find(q, Neighborhood::Knn(15), found);
    const auto expected = brute_force(cloud_.xyz, q);
    ASSERT_EQ(found.size(), 15u);
    for (std::size_t i = 0; i < 15; ++i) EXPECT_EQ(found.indices[i], expected[i].second);
  }
}

TEST_F(NeighborSearchTest, HybridIsNearestWithinRadius) {
  NeighborSearch search(cloud_.xyz);
  NeighborList found;
  const Vec3f q = cloud_.xyz[10];
  const auto expected = brute_force(cloud_.xyz, q);
  // Radius holds more than the cap: exactly the cap, nearest first.
  search.find(q, Neighborhood::Hybrid(0.5f, 20), found);
  ASSERT_EQ(found.size(), 20u);
  for (std::size_t i = 0; i < 20; ++i) EXPECT_EQ(found.indices[i], expected[i].second);
  // Radius holds fewer than the cap: everything inside the radius.
  const float r = 0.08f;
  const auto inside =
      std::count_if(expected.begin(), expected.end(), [&](auto& e) { return e.first < r * r; });
  search.find(q, Neighborhood::Hybrid(r, 1000), found);
  EXPECT_EQ(found.size(), static_cast<std::size_t>(inside));
}

TEST(NeighborSearch, TiesAreReportedLowestIndexFirst) {
  std::vector<Vec3f> pts = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {5, 5, 5}};
  NeighborSearch search(pts);
  NeighborList found;
  search.find(Vec3f::Zero(), Neighborhood::Knn(3), found);
  EXPECT_EQ(found.indices, (std::vector<std::uint32_t>{0, 1, 2}));
  search.find(Vec3f::Zero(), Neighborhood::Radius(1.5f), found);
  EXPECT_EQ(found.indices, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
}

TEST(NeighborSearch, NonFiniteQueryEmptyCloudAndBadParameters) {
  std::vector<Vec3f> none;
  NeighborSearch empty(none);
  NeighborList found;
  empty.find(Vec3f::Zero(), Neighborhood::Knn(3), found);
  EXPECT_EQ(found.size(), 0u);

  std::vector<Vec3f> pts = {{0, 0, 0}, {1, 0, 0}, {Vec3f::Constant(NAN)}};
  NeighborSearch search(pts);
  EXPECT_EQ(search.indexed_points(), 2u);
  search.find(Vec3f::Constant(std::numeric_limits<float>::infinity()), Neighborhood::Knn(1), found);
  EXPECT_EQ(found.size(), 0u);
  search.find(Vec3f::Zero(), Neighborhood::Knn(10), found);  // more asked than indexed
  EXPECT_EQ(found.size(), 2u);
  EXPECT_THROW(search.find(Vec3f::Zero(), Neighborhood{-1.0f, 0, 0}, found), std::invalid_argument);
  EXPECT_THROW(search.find(Vec3f::Zero(), Neighborhood{}, found), std::invalid_argument);
}

// ---- Cancellation of the index build ------------------------------------------------------------

std::stop_token stopped_token(std::stop_source& source) {
  source.request_stop();
  return source.get_token();
}

TEST(NeighborSearchCancellation, AStoppedTokenCancelsTheBuild) {
  // Small (one nanoflann call) and large (split into checked subtrees) clouds alike.
  for (int n : {0, 500, 200000}) {
    const PointCloud cloud = test::random_box(n, 1.0f, 3);
    std::stop_source source;
    EXPECT_THROW(NeighborSearch(cloud.xyz, stopped_token(source)), Cancelled) << n;
  }
}

// nanoflann's own build (KdTree::buildIndex, no stop checks) over the same points, as the search
// built it before it took a stop token.
struct Points {
  std::vector<Vec3f> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};
using ReferenceTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Points>, Points, 3,
                                        std::uint32_t>;

// Unsorted radius results in nanoflann's tree order (what NeighborSearch reports for a radius
// that gets no grid).
std::vector<std::uint32_t> tree_order(const ReferenceTree& tree, const Vec3f& q, float radius) {
  std::vector<std::pair<std::uint32_t, float>> found;
  nanoflann::SearchParams params(32, 0.0f, false);
  tree.radiusSearch(q.data(), radius * radius, found, params);
  std::vector<std::uint32_t> out;
  for (const auto& item : found)
    if (item.second < radius * radius) out.push_back(item.first);
  return out;
}

// Points in a small box, stretched by two far outliers: grids for these radii would need far too
// many cells, so the tree answers radius queries and their unsorted order exposes the tree's
// structure. Below 2^19 points the build runs unchecked, above it the adaptor checks the token.
class NeverStoppedBuild : public ::testing::TestWithParam<int> {};

TEST_P(NeverStoppedBuild, BuildsNanoflannsTree) {
  PointCloud cloud = test::random_box(GetParam(), 1.0f, 11);
  cloud.xyz[0] = Vec3f::Constant(100.0f);
  cloud.xyz[1] = Vec3f::Constant(-100.0f);
  Points points{cloud.xyz};
  const ReferenceTree reference(3, points, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  std::stop_source never;
  const NeighborSearch search(cloud.xyz, never.get_token());
  const NeighborSearch plain(cloud.xyz);
  NeighborList got, expected;
  std::size_t found = 0;
  for (std::size_t i = 0; i < cloud.size(); i += 997) {
    const Vec3f& q = cloud.xyz[i];
    for (float radius : {0.05f, 0.1f}) {
      search.find(q, Neighborhood::Radius(radius), got, /*sorted=*/false);
      EXPECT_EQ(got.indices, tree_order(reference, q, radius)) << i;
      found += got.size();
    }
    for (const Neighborhood& hood : {Neighborhood::Knn(10), Neighborhood::Hybrid(3.0f, 5)}) {
      search.find(q, hood, got);
      plain.find(q, hood, expected);
      EXPECT_EQ(got.indices, expected.indices) << i;
      EXPECT_EQ(got.sq_dists, expected.sq_dists) << i;
    }
  }
  EXPECT_GT(found, cloud.size() / 997 * 10);  // the radius lists are long enough to have an order
}

INSTANTIATE_TEST_SUITE_P(NeighborSearchCancellation, NeverStoppedBuild,
                         ::testing::Values(150000, 600000));

TEST(NeighborSearchCancellation, AStopAfterTheBuildStillAnswersRadiusQueries) {
  // The grid for a new radius is not built once stopped; the tree answers with the same set.
  PointCloud cloud = test::random_box(3000, 1.0f, 5);
  std::stop_source source;
  const NeighborSearch search(cloud.xyz, source.get_token());
  source.request_stop();
  NeighborList got;
  for (std::size_t i = 0; i < cloud.size(); i += 101) {
    search.find(cloud.xyz[i], Neighborhood::Radius(0.1f), got);
    std::vector<std::uint32_t> expected;
    for (const auto& [d, j] : brute_force(cloud.xyz, cloud.xyz[i]))
      if (d < 0.01f) expected.push_back(j);
    EXPECT_EQ(got.indices, expected) << i;
  }
}

// Sorted (distance, index) pairs strictly within r of q, by brute force.
std::vector<std::pair<float, std::uint32_t>> brute_within(const std::vector<Vec3f>& pts,
                                                          const Vec3f& q, float r) {
  std::vector<std::pair<float, std::uint32_t>> out;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    const float dx = q.x() - pts[i].x(), dy = q.y() - pts[i].y(), dz = q.z() - pts[i].z();
    const float sq = (dx * dx + dy * dy) + dz * dz;
    if (sq < r * r) out.emplace_back(sq, i);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A point near +-FLT_MAX makes the grid's cell count overflow int64 (it threw length_error out
// of an OpenMP region): the k-d tree answers instead, with the same neighbours.
TEST(NeighborSearch, FarPointsFallBackToTheTreeWithTheSameAnswers) {
  for (const float far : {1e18f, 1e30f, std::numeric_limits<float>::max()}) {
    std::vector<Vec3f> pts;
    for (int i = 0; i < 40; ++i)
      for (int j = 0; j < 40; ++j) pts.emplace_back(i * 0.01f, j * 0.01f, 0.0f);
    pts.emplace_back(far, far, far);
    pts.emplace_back(-far, 0.0f, -far);
    NeighborSearch search(pts);
    NeighborList found;
    for (const Vec3f& q : {pts[0], pts[820], pts.back(), Vec3f(far, -far, far)}) {
      search.find(q, Neighborhood::Radius(0.025f), found);
      const auto expected = brute_within(pts, q, 0.025f);
      ASSERT_EQ(found.size(), expected.size()) << far;
      for (std::size_t k = 0; k < found.size(); ++k)
        EXPECT_EQ(found.indices[k], expected[k].second);
      search.find(q, Neighborhood::Hybrid(0.025f, 5), found, /*sorted=*/false);
      EXPECT_EQ(found.size(), std::min<std::size_t>(5, expected.size()));
    }
  }
}

TEST(NeighborSearch, AnInfiniteRadiusIsNotAValidNeighbourhood) {
  EXPECT_FALSE(Neighborhood::Radius(std::numeric_limits<float>::infinity()).valid());
  EXPECT_FALSE(Neighborhood::Radius(std::numeric_limits<float>::quiet_NaN()).valid());
  EXPECT_TRUE(Neighborhood::Radius(std::numeric_limits<float>::max()).valid());
}

// Capped radius queries return the nearest `cap` (ties by index) whether the radius is read from
// the grid, from the tree, or overflows into the nearest search; unsorted lists hold the same set.
TEST(NeighborSearch, CappedRadiusIsTheNearestWithinTheRadiusOnDenseClusters) {
  std::vector<Vec3f> pts;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) pts.emplace_back(i * 0.01f, j * 0.01f, 0.0f);
  for (int c = 0; c < 3000; ++c)  // a dense clump and exact copies
    pts.emplace_back(0.1f + (c % 10) * 1e-5f, 0.1f + (c / 10 % 10) * 1e-5f, (c / 100) * 1e-5f);
  pts.insert(pts.end(), 500, Vec3f(0.2f, 0.2f, 0.0f));
  NeighborSearch search(pts);
  NeighborList sorted, unsorted;
  for (const Vec3f& q : {pts[0], pts[310], pts[1500], pts.back()}) {
    for (const int cap : {4, 64, 1024}) {
      const auto expected = brute_within(pts, q, 0.03f);
      search.find(q, Neighborhood::Hybrid(0.03f, cap), sorted, /*sorted=*/true);
      search.find(q, Neighborhood::Hybrid(0.03f, cap), unsorted, /*sorted=*/false);
      const std::size_t n = std::min<std::size_t>(cap, expected.size());
      ASSERT_EQ(sorted.size(), n);
      for (std::size_t k = 0; k < n; ++k) EXPECT_EQ(sorted.sq_dists[k], expected[k].first);
      std::vector<std::uint32_t> a = sorted.indices, b = unsorted.indices;
      std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
      EXPECT_EQ(a, b) << "cap " << cap;
    }
  }
}

// The tree indexes the caller's points in place, skipping the non-finite ones: its structure is
// nanoflann's tree over the finite points alone (the unsorted order of radius lists shows it).
TEST(NeighborSearch, ACloudWithNaNsGetsNanoflannsTreeOverItsFinitePoints) {
  PointCloud cloud = test::random_box(120000, 1.0f, 23);
  cloud.xyz[0] = Vec3f::Constant(100.0f);  // no grid: the tree answers radius queries
  cloud.xyz[1] = Vec3f::Constant(-100.0f);
  for (std::size_t i = 5; i < cloud.size(); i += 7) cloud.xyz[i] = Vec3f::Constant(NAN);
  Points finite;
  std::vector<std::uint32_t> to_cloud;
  for (std::uint32_t i = 0; i < cloud.size(); ++i)
    if (is_finite(cloud.xyz[i])) finite.points.push_back(cloud.xyz[i]), to_cloud.push_back(i);
  const ReferenceTree reference(3, finite, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const NeighborSearch search(cloud.xyz);
  EXPECT_EQ(search.indexed_points(), finite.points.size());
  NeighborList got;
  std::size_t found = 0;
  for (std::size_t i = 2; i < cloud.size(); i += 1009) {
    std::vector<std::uint32_t> expected;
    for (std::uint32_t c : tree_order(reference, cloud.xyz[i], 0.08f))
      expected.push_back(to_cloud[c]);
    search.find(cloud.xyz[i], Neighborhood::Radius(0.08f), got, /*sorted=*/false);
    EXPECT_EQ(got.indices, expected) << i;
    found += got.size();
  }
  EXPECT_GT(found, 1000u);
}

// A filtered query answers as a search built on the allowed points alone would (random points:
// no ties), for every kind of neighbourhood, on the grid and on the tree.
TEST(NeighborSearch, FilteredQueriesEqualASearchOnTheAllowedPointsAlone) {
  PointCloud cloud = test::random_box(20000, 1.0f, 29);
  for (std::size_t i = 3; i < cloud.size(); i += 53) cloud.xyz[i] = Vec3f::Constant(NAN);
  std::mt19937 rng(5);
  std::vector<std::uint8_t> allowed(cloud.size());
  std::vector<Vec3f> subset;
  std::vector<std::uint32_t> to_cloud;
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    allowed[i] = rng() % 10 < 7;
    if (allowed[i]) subset.push_back(cloud.xyz[i]), to_cloud.push_back(i);
  }
  const NeighborSearch search(cloud.xyz);
  const NeighborSearch alone(subset);
  NeighborList got, expected;
  for (const Neighborhood& hood :
       {Neighborhood::Knn(10), Neighborhood::Radius(0.1f), Neighborhood::Hybrid(0.1f, 5),
        Neighborhood::Hybrid(0.5f, 40), Neighborhood::Radius(0.5f)}) {
    for (std::size_t i = 0; i < cloud.size(); i += 211) {
      for (const bool sorted : {true, false}) {
        search.find(cloud.xyz[i], hood, allowed, got, sorted);
        alone.find(cloud.xyz[i], hood, expected, sorted);
        for (std::uint32_t& j : expected.indices) j = to_cloud[j];
        if (!sorted) {  // the same set; the order is each tree's own
          std::sort(got.indices.begin(), got.indices.end());
          std::sort(expected.indices.begin(), expected.indices.end());
        } else {
          EXPECT_EQ(got.sq_dists, expected.sq_dists) << hood.describe() << " " << i;
        }
        ASSERT_EQ(got.indices, expected.indices) << hood.describe() << " " << i;
        for (std::uint32_t j : got.indices) EXPECT_TRUE(allowed[j]);
      }
    }
  }
  std::vector<std::uint8_t> short_mask(cloud.size() - 1, 1);
  EXPECT_THROW(search.find(cloud.xyz[0], Neighborhood::Knn(3), short_mask, got),
               std::invalid_argument);
}

// nanoflann's build has no stop check of its own; the search checks the token from inside it
// (the dataset adaptor), so a stop in the middle of a large build ends it within a few
// milliseconds instead of at its end.
TEST(NeighborSearchCancellation, AStopDuringTheBuildEndsItEarly) {
  const PointCloud cloud = test::random_box(2000000, 1.0f, 31);
  const auto start = std::chrono::steady_clock::now();
  { const NeighborSearch full(cloud.xyz); }
  const auto build = std::chrono::steady_clock::now() - start;
  std::stop_source source;
  std::chrono::steady_clock::time_point requested;
  std::jthread stopper([&] {
    std::this_thread::sleep_for(build / 4);
    requested = std::chrono::steady_clock::now();
    source.request_stop();
  });
  EXPECT_THROW(NeighborSearch(cloud.xyz, source.get_token()), Cancelled);
  const auto returned = std::chrono::steady_clock::now();
  stopper.join();
  // Without checks inside the build the rest of it (about 3/4 of `build`) would run first.
  EXPECT_LT(returned - requested, build / 4)
      << std::chrono::duration<double, std::milli>(build).count() << " ms build";
}

}  // namespace
}  // namespace primlabel
