#pragma once
// Exact marginals, MAP and log-partition of a tiny CRF by enumerating every labelling.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"

namespace primlabel::crf::testing {

struct Exact {
  std::vector<std::vector<double>> marginals;  // node x class
  std::vector<int> map;                        // class indices of the most probable labelling
  double log_z = 0.0;
  // log p(y) of a labelling given as class indices.
  std::vector<double> node_theta;  // node x K, row-major
  std::vector<double> edge_theta;  // slot x K
  int k = 0;
  const Graph* graph = nullptr;
  double score(const std::vector<int>& y) const {
    double s = 0.0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      s += node_theta[i * k + y[i]];
      for (std::uint32_t p = graph->offsets[i]; p < graph->offsets[i + 1]; ++p) {
        const std::uint32_t j = graph->neighbors[p];
        if (j > i && y[j] == y[i]) s += edge_theta[std::size_t(p) * k + y[i]];
      }
    }
    return s;
  }
};

// phi(u) of crf/model.hpp written as hat functions (independently of the library's code): knot
// a's hat rises from t_{a-1} to 1 at t_a and falls to 0 at t_{a+1}; u is clamped to the knots.
inline double tent(const std::vector<float>& knots, std::size_t a, double u) {
  u = std::clamp(u, double(knots.front()), double(knots.back()));
  if (a > 0 && u >= knots[a - 1] && u <= knots[a])
    return (u - knots[a - 1]) / (double(knots[a]) - knots[a - 1]);
  if (a + 1 < knots.size() && u >= knots[a] && u <= knots[a + 1])
    return (double(knots[a + 1]) - u) / (double(knots[a + 1]) - knots[a]);
  return 0.0;
}

inline double node_score(const CrfModel& model, const float* descriptor, int c) {
  const int d = model.descriptor_dim;
  const double s = model.feature_scale;
  const auto& knots = model.node_knots;
  double t = model.node_weights(c, model.node_feature_dim() - 1);
  for (int f = 0; f < d; ++f) {
    if (knots.empty()) {
      t += model.node_weights(c, f) * s * descriptor[f];
      continue;
    }
    for (std::size_t a = 0; a < knots.size(); ++a)
      t +=
          model.node_weights(c, f * int(knots.size()) + int(a)) * tent(knots, a, s * descriptor[f]);
  }
  return t;
}

inline Exact brute_force(const CrfModel& model, std::span<const float> descriptors,
                         const Graph& graph) {
  const int k = model.num_classes();
  const int d = model.descriptor_dim;
  const std::size_t n = graph.num_nodes();
  const double s = model.feature_scale;
  Exact e;
  e.k = k;
  e.graph = &graph;
  e.node_theta.assign(n * k, 0.0);
  e.edge_theta.assign(graph.num_slots() * k, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < k; ++c) e.node_theta[i * k + c] = node_score(model, &descriptors[i * d], c);
    for (std::uint32_t p = graph.offsets[i]; p < graph.offsets[i + 1]; ++p) {
      const std::uint32_t j = graph.neighbors[p];
      for (int c = 0; c < k; ++c) {
        double t = model.edge_weights(c, d);
        for (int f = 0; f < d; ++f)
          t += model.edge_weights(c, f) * s * s * descriptors[i * d + f] * descriptors[j * d + f];
        e.edge_theta[std::size_t(p) * k + c] = t;
      }
    }
  }
  e.marginals.assign(n, std::vector<double>(k, 0.0));
  std::vector<int> y(n, 0);
  double best = -1e300, z = 0.0;
  std::vector<double> weights;
  std::vector<std::vector<int>> all;
  for (;;) {
    const double sc = e.score(y);
    weights.push_back(sc);
    all.push_back(y);
    if (sc > best) {
      best = sc;
      e.map = y;
    }
    std::size_t pos = 0;
    while (pos < n && ++y[pos] == k) y[pos++] = 0;
    if (pos == n) break;
  }
  for (double w : weights) z += std::exp(w - best);
  e.log_z = best + std::log(z);
  for (std::size_t a = 0; a < all.size(); ++a) {
    const double p = std::exp(weights[a] - e.log_z);
    for (std::size_t i = 0; i < n; ++i) e.marginals[i][all[a][i]] += p;
  }
  return e;
}

}  // namespace primlabel::crf::testing
