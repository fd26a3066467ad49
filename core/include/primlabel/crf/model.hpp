#pragma once
// The CRF model: per-class weights of a log-linear, associative pairwise CRF over point
// descriptors (Rusu et al. 2009, eqs. 7 and 8). Plain data, laid out so a file format can store
// it field by field; node-only (logistic regression) models are the same struct with zero edge
// weights.
//
// ---- Parameterisation (copy for the README) ------------------------------------------------
// K classes (class_ids[k] is the taxonomy id of class index k), descriptors of d values,
// s = feature_scale.
//   node feature   x_i  = [ s * descriptor_i (d values), 1 ]                      (d + 1)
//   edge feature   e_ij = [ s^2 * (descriptor_i (.) descriptor_j) (d values), 1 ] (d + 1)
//                  ((.) is the element-wise product: products of neighbouring features)
//   node score     theta_i(k)    = w_k . x_i                  w_k = node_weights.row(k)
//   edge score     theta_ij(k,l) = [k == l] * v_k . e_ij      v_k = edge_weights.row(k)
//                  (associative: neighbours only gain or lose score by sharing a label)
//   p(y | x) = exp( sum_i theta_i(y_i) + sum_{(i,j) in E} theta_ij(y_i, y_j) ) / Z(x)
// E is the symmetric neighbourhood graph (crf/graph.hpp), each undirected edge counted once.
// The last column of each weight matrix is the bias. A node-only model has edge_weights == 0.
// ------------------------------------------------------------------------------------------

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace primlabel::crf {

struct CrfModel {
  std::vector<std::uint32_t> class_ids;  // class index k -> taxonomy id
  int descriptor_dim = 0;                // d
  Eigen::MatrixXf node_weights;          // K x (d + 1), row k = w_k, last column = bias
  Eigen::MatrixXf edge_weights;          // K x (d + 1), row k = v_k, last column = bias
  float feature_scale = 0.01f;           // s: FPFH bins are percentages, so x is O(1)

  int num_classes() const { return static_cast<int>(class_ids.size()); }
  int feature_dim() const { return descriptor_dim + 1; }
  bool has_edge_terms() const { return edge_weights.size() > 0 && !edge_weights.isZero(0.0f); }
  // Class index of a taxonomy id, or nothing when the model does not know it.
  std::optional<int> class_index(std::uint32_t id) const;

  // All-zero weights of the right shape.
  static CrfModel zeros(std::vector<std::uint32_t> class_ids, int descriptor_dim,
                        float feature_scale = 0.01f);

  // Throws std::invalid_argument when shapes disagree, an id repeats or a weight is not finite.
  void validate() const;
};

}  // namespace primlabel::crf
