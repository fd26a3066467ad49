#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stop_token>

#include "primlabel/crf/graph.hpp"
#include "primlabel/geometry/cancellation.hpp"

namespace primlabel::crf {
namespace {

std::vector<Vec3f> line_points(int n) {
  std::vector<Vec3f> points(n);
  for (int i = 0; i < n; ++i) points[i] = Vec3f(float(i), 0.1f * float(i % 3), 0.0f);
  return points;
}

void expect_well_formed(const Graph& g) {
  ASSERT_EQ(g.offsets.size(), g.num_nodes() + 1);
  ASSERT_EQ(g.reverse.size(), g.num_slots());
  for (std::size_t i = 0; i < g.num_nodes(); ++i) {
    const auto row = g.neighbors_of(i);
    EXPECT_TRUE(std::is_sorted(row.begin(), row.end()));
    EXPECT_EQ(std::adjacent_find(row.begin(), row.end()), row.end());
    if (!g.active[i]) {
      EXPECT_EQ(row.size(), 0u);
    }
    for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
      const std::uint32_t j = g.neighbors[p];
      EXPECT_NE(j, i);
      EXPECT_TRUE(g.active[j]);
      const std::uint32_t r = g.reverse[p];
      EXPECT_EQ(g.neighbors[r], i);  // the opposite slot lives in row j and points back at i
      EXPECT_GE(r, g.offsets[j]);
      EXPECT_LT(r, g.offsets[j + 1]);
      EXPECT_EQ(g.reverse[r], p);
    }
  }
}

TEST(CrfGraph, KnnIsSymmetricWithoutSelfLoops) {
  const auto points = line_points(50);
  const std::vector<float> descriptors(50 * 2, 1.0f);
  GraphSettings options;
  options.neighborhood = Neighborhood::Knn(4);
  const Graph g = build_graph(points, Descriptors(2, descriptors), options);
  expect_well_formed(g);
  EXPECT_EQ(g.num_active(), 50u);
  for (std::size_t i = 0; i < 50; ++i) EXPECT_GE(g.degree(i), 4u);
  // On a line the 4 nearest are the two on either side (union adds no more in the interior).
  EXPECT_EQ(std::vector<std::uint32_t>(g.neighbors_of(10).begin(), g.neighbors_of(10).end()),
            (std::vector<std::uint32_t>{8, 9, 11, 12}));
}

TEST(CrfGraph, RadiusAndHybrid) {
  const auto points = line_points(30);
  const std::vector<float> descriptors(30, 0.0f);  // all-zero descriptors are valid
  GraphSettings options;
  options.neighborhood = Neighborhood::Radius(1.5f);
  const Graph g = build_graph(points, Descriptors(1, descriptors), options);
  expect_well_formed(g);
  EXPECT_EQ(g.degree(0), 1u);
  EXPECT_EQ(g.degree(15), 2u);
  options.neighborhood = Neighborhood::Hybrid(10.0f, 2);
  const Graph h = build_graph(points, Descriptors(1, descriptors), options);
  expect_well_formed(h);
  for (std::size_t i = 0; i < 30; ++i) EXPECT_GE(h.degree(i), 2u);
}

TEST(CrfGraph, InvalidPointsAreInactiveAndIsolated) {
  auto points = line_points(20);
  std::vector<float> descriptors(20 * 3, 5.0f);
  descriptors[4 * 3 + 1] = std::nanf("");
  points[9] = Vec3f::Constant(std::nanf(""));
  GraphSettings options;
  options.neighborhood = Neighborhood::Knn(2);
  const Graph g = build_graph(points, Descriptors(3, descriptors), options);
  expect_well_formed(g);
  EXPECT_FALSE(g.active[4]);
  EXPECT_FALSE(g.active[9]);
  EXPECT_EQ(g.num_active(), 18u);
  // The nearest valid neighbours skip the invalid point 4.
  for (std::uint32_t j : g.neighbors_of(3)) EXPECT_NE(j, 4u);
}

TEST(CrfGraph, DeterministicForAnyThreadsAndWithOrWithoutSearch) {
  std::vector<Vec3f> points;
  for (int i = 0; i < 2000; ++i)
    points.emplace_back(std::sin(0.37f * i) * 3.0f, std::cos(0.11f * i) * 2.0f, 0.001f * i);
  const std::vector<float> descriptors(points.size() * 2, 1.0f);
  const GraphSettings options;
  const Graph one = build_graph(points, Descriptors(2, descriptors), options, RunContext{1});
  const Graph two = build_graph(points, Descriptors(2, descriptors), options, RunContext{2});
  const NeighborSearch search(points);
  const Graph reused =
      build_graph(points, Descriptors(2, descriptors), options, RunContext{2}, &search);
  expect_well_formed(one);
  EXPECT_EQ(one.offsets, two.offsets);
  EXPECT_EQ(one.neighbors, two.neighbors);
  EXPECT_EQ(one.neighbors, reused.neighbors);
  EXPECT_EQ(one.reverse, reused.reverse);
}

TEST(CrfGraph, FromEdgesAndRestrict) {
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> edges = {{0, 1}, {1, 0}, {1, 2},
                                                                      {2, 2}, {2, 3}, {3, 4}};
  const Graph g = graph_from_edges(5, edges);
  expect_well_formed(g);
  EXPECT_EQ(g.num_edges(), 4u);  // duplicate and self loop dropped
  const std::vector<std::uint8_t> keep = {1, 1, 0, 1, 1};
  const Graph r = restrict_graph(g, keep);
  expect_well_formed(r);
  EXPECT_EQ(r.num_edges(), 2u);  // 0-1 and 3-4
  EXPECT_FALSE(r.active[2]);
  EXPECT_THROW(graph_from_edges(2, std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 5}}),
               std::invalid_argument);
}

TEST(CrfGraph, Empty) {
  const Graph g = build_graph({}, Descriptors(33, {}));
  EXPECT_EQ(g.num_nodes(), 0u);
  EXPECT_EQ(g.num_slots(), 0u);
  EXPECT_EQ(g.offsets.size(), 1u);
}

// ---- Cancellation ------------------------------------------------------------------------------

// A 3000-point patch with a few invalid descriptors and non-finite points (more than one block
// of every parallel pass).
struct Patch {
  std::vector<Vec3f> points;
  std::vector<float> descriptors;  // dim 2
};

Patch noisy_patch() {
  Patch patch;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 3000; ++i) {
    patch.points.emplace_back(u(rng), u(rng), 0.05f * u(rng));
    patch.descriptors.push_back(u(rng));
    patch.descriptors.push_back(u(rng));
  }
  for (int i = 5; i < 3000; i += 211) patch.descriptors[2 * i + 1] = std::nanf("");
  for (int i = 7; i < 3000; i += 307) patch.points[i] = Vec3f::Constant(std::nanf(""));
  return patch;
}

// The graph build_graph promises, by brute force: each valid point linked to its nearest valid
// others (distance, then index), symmetrised, rows sorted.
std::vector<std::vector<std::uint32_t>> brute_force_rows(const Patch& patch,
                                                         const Neighborhood& hood) {
  const std::size_t n = patch.points.size();
  std::vector<std::uint8_t> valid(n);
  for (std::size_t i = 0; i < n; ++i)
    valid[i] = is_finite(patch.points[i]) &&
               descriptor_is_valid(std::span<const float>(&patch.descriptors[2 * i], 2));
  std::vector<std::vector<std::uint32_t>> rows(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    std::vector<std::pair<float, std::uint32_t>> others;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i || !valid[j]) continue;
      const Vec3f d = patch.points[i] - patch.points[j];
      const float sq = (d.x() * d.x() + d.y() * d.y()) + d.z() * d.z();  // nanoflann's order
      if (hood.radius > 0.0f && !(sq < hood.radius * hood.radius)) continue;
      others.emplace_back(sq, static_cast<std::uint32_t>(j));
    }
    std::sort(others.begin(), others.end());
    const std::size_t cap = hood.radius == 0.0f      ? std::size_t(hood.k)
                            : hood.max_neighbors > 0 ? std::size_t(hood.max_neighbors)
                                                     : others.size();
    for (std::size_t r = 0; r < std::min(cap, others.size()); ++r) {
      rows[i].push_back(others[r].second);
      rows[others[r].second].push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (auto& row : rows) {
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  }
  return rows;
}

TEST(CrfGraphCancellation, AStoppedTokenCancelsTheBuild) {
  const Patch patch = noisy_patch();
  std::vector<float> all_valid(patch.descriptors.size(), 1.0f);
  std::vector<Vec3f> finite = patch.points;
  for (Vec3f& p : finite)
    if (!is_finite(p)) p = Vec3f::Zero();
  const NeighborSearch search(finite);
  std::stop_source source;
  source.request_stop();
  GraphSettings options;
  RunContext context;
  context.stop = source.get_token();
  for (const Neighborhood& hood : {Neighborhood::Knn(8), Neighborhood::Radius(0.05f)}) {
    options.neighborhood = hood;
    // Its own index over the valid points, and the shared index.
    EXPECT_THROW(build_graph(patch.points, Descriptors(2, patch.descriptors), options, context),
                 Cancelled);
    EXPECT_THROW(build_graph(finite, Descriptors(2, all_valid), options, context, &search),
                 Cancelled);
  }
}

TEST(CrfGraphCancellation, ANeverStoppedTokenGivesTheSameGraph) {
  const Patch patch = noisy_patch();
  std::stop_source never;
  for (const Neighborhood& hood :
       {Neighborhood::Knn(8), Neighborhood::Radius(0.05f), Neighborhood::Hybrid(0.05f, 6)}) {
    const auto expected = brute_force_rows(patch, hood);
    GraphSettings plain;
    plain.neighborhood = hood;
    const Graph reference =
        build_graph(patch.points, Descriptors(2, patch.descriptors), plain, RunContext{1});
    for (int threads : {1, 3}) {
      const RunContext context{threads, never.get_token()};
      const Graph g = build_graph(patch.points, Descriptors(2, patch.descriptors), plain, context);
      expect_well_formed(g);
      ASSERT_EQ(g.num_nodes(), expected.size());
      for (std::size_t i = 0; i < expected.size(); ++i)
        ASSERT_EQ(std::vector<std::uint32_t>(g.neighbors_of(i).begin(), g.neighbors_of(i).end()),
                  expected[i])
            << hood.describe() << " node " << i;
      EXPECT_EQ(g.offsets, reference.offsets);
      EXPECT_EQ(g.neighbors, reference.neighbors);
      EXPECT_EQ(g.reverse, reference.reverse);
      EXPECT_EQ(g.active, reference.active);
    }
  }
}

// Points without a descriptor are filtered out of the one index's answers: the graph is the one
// a search over the valid points alone gives (how it was built before), with the caller's index
// or without.
TEST(CrfGraph, MissingDescriptorsGiveTheGraphOfTheValidPointsAlone) {
  const Patch patch = noisy_patch();
  std::vector<Vec3f> valid_points;
  std::vector<float> valid_descriptors;
  std::vector<std::uint32_t> to_patch;
  for (std::size_t i = 0; i < patch.points.size(); ++i) {
    if (!is_finite(patch.points[i]) ||
        !descriptor_is_valid(std::span<const float>(&patch.descriptors[2 * i], 2)))
      continue;
    valid_points.push_back(patch.points[i]);
    valid_descriptors.insert(valid_descriptors.end(),
                             {patch.descriptors[2 * i], patch.descriptors[2 * i + 1]});
    to_patch.push_back(static_cast<std::uint32_t>(i));
  }
  ASSERT_LT(to_patch.size(), patch.points.size() - 10);  // some finite points lack a descriptor
  const NeighborSearch search(patch.points);
  for (const Neighborhood& hood :
       {Neighborhood::Knn(8), Neighborhood::Radius(0.05f), Neighborhood::Hybrid(0.05f, 6)}) {
    GraphSettings settings;
    settings.neighborhood = hood;
    const Graph compact = build_graph(valid_points, Descriptors(2, valid_descriptors), settings);
    const Graph own = build_graph(patch.points, Descriptors(2, patch.descriptors), settings);
    const Graph shared =
        build_graph(patch.points, Descriptors(2, patch.descriptors), settings, {}, &search);
    EXPECT_EQ(own.neighbors, shared.neighbors) << hood.describe();
    EXPECT_EQ(own.reverse, shared.reverse) << hood.describe();
    ASSERT_EQ(own.num_slots(), compact.num_slots()) << hood.describe();
    for (std::size_t c = 0; c < to_patch.size(); ++c) {
      std::vector<std::uint32_t> expected;
      for (std::uint32_t j : compact.neighbors_of(c)) expected.push_back(to_patch[j]);
      const auto row = own.neighbors_of(to_patch[c]);
      ASSERT_EQ(std::vector<std::uint32_t>(row.begin(), row.end()), expected)
          << hood.describe() << " node " << to_patch[c];
    }
  }
}

}  // namespace
}  // namespace primlabel::crf
