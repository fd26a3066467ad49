#pragma once
// The CRF model: per-class weights of a log-linear, associative pairwise CRF over point
// descriptors (Rusu et al. 2009, eqs. 7 and 8). Plain data, laid out so a file format can store
// it field by field; node-only (logistic regression) models are the same struct with zero edge
// weights.
//
// ---- Parameterisation (copy for the README) ------------------------------------------------
// K classes (class_ids[k] is the taxonomy id of class index k), descriptors of d values,
// s = feature_scale, u_i = s * descriptor_i (FPFH bins are percentages, so u is in [0, 1]).
//   node feature   x_i  = [ phi(u_i), 1 ]                                   (node_feature_dim)
//   edge feature   e_ij = [ u_i (.) u_j (d values), 1 ]                    (d + 1)
//                  ((.) is the element-wise product: products of neighbouring features)
//   node score     theta_i(k)    = w_k . x_i                  w_k = node_weights.row(k)
//   edge score     theta_ij(k,l) = [k == l] * v_k . e_ij      v_k = edge_weights.row(k)
//                  (associative: neighbours only gain or lose score by sharing a label)
//   p(y | x) = exp( sum_i theta_i(y_i) + sum_{(i,j) in E} theta_ij(y_i, y_j) ) / Z(x)
// phi is the node feature basis. Without node_knots it is the identity (d values), the paper's
// eq. 7. With knots t_0 < ... < t_{B-1} every value u (clamped to [t_0, t_{B-1}]) is spread over
// B "tent" functions: between t_a and t_{a+1} it gives (t_{a+1} - u) / (t_{a+1} - t_a) to knot a
// and the rest to knot a + 1 (d * B values, at most 2 non-zero per bin). w_k . phi(u) is then any
// piecewise-linear function of each bin, summed over bins: still log-linear in the features, but
// a bin's evidence may rise and fall (the explicit feature map of additive kernels such as
// histogram intersection, Maji & Berg 2009), which a single weight per bin cannot express.
// E is the symmetric neighbourhood graph (crf/graph.hpp), each undirected edge counted once.
// The last column of each weight matrix is the bias. A node-only model has edge_weights == 0.
// ------------------------------------------------------------------------------------------

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace primlabel::crf {

inline constexpr int kMaxNodeKnots = 64;

// Throws std::invalid_argument unless `knots` is empty (the identity basis) or 2..kMaxNodeKnots
// finite, strictly increasing values; the message starts "node knots".
void validate_node_knots(const std::vector<float>& knots);

// The default tent knots, in scaled units (u = s * bin value; FPFH bins are percentages): dense
// where most bin values lie, so the learnt per-bin curves bend where the classes differ. Fewer
// knots lose accuracy, more gain little (docs/development.md, "Figures behind the code").
inline const std::vector<float>& default_node_knots() {
  static const std::vector<float> knots = {0.0f,  0.025f, 0.05f, 0.1f, 0.15f,
                                           0.25f, 0.35f,  0.5f,  0.7f, 1.0f};
  return knots;
}

struct CrfModel {
  std::vector<std::uint32_t> class_ids;  // class index k -> taxonomy id
  int descriptor_dim = 0;                // d
  Eigen::MatrixXf node_weights;          // K x node_feature_dim, row k = w_k, last column = bias
  Eigen::MatrixXf edge_weights;          // K x (d + 1), row k = v_k, last column = bias
  float feature_scale = 0.01f;           // s: FPFH bins are percentages, so x is O(1)
  std::vector<float> node_knots;         // the tent basis of phi; empty = identity

  int num_classes() const { return static_cast<int>(class_ids.size()); }
  int node_feature_dim() const {
    return descriptor_dim * (node_knots.empty() ? 1 : static_cast<int>(node_knots.size())) + 1;
  }
  int edge_feature_dim() const { return descriptor_dim + 1; }
  bool has_edge_terms() const { return edge_weights.size() > 0 && !edge_weights.isZero(0.0f); }
  // Class index of a taxonomy id, or nothing when the model does not know it.
  std::optional<int> class_index(std::uint32_t id) const;

  // All-zero weights of the right shape.
  static CrfModel zeros(std::vector<std::uint32_t> class_ids, int descriptor_dim,
                        float feature_scale = 0.01f, std::vector<float> node_knots = {});

  // Throws std::invalid_argument when shapes disagree, an id repeats, a weight is not finite or
  // the knots are not 2..kMaxNodeKnots finite, strictly increasing values.
  void validate() const;
};

}  // namespace primlabel::crf
