#pragma once
// The training objectives behind train_crf. Each returns the negated log-(pseudo-)likelihood of
// the labelled points divided by their number (or, with class weights, the weighted sum divided
// by the weighted count), and its gradient; the L2 term is added by the
// driver. Parameters are one vector: [W row-major (K x node_row), V row-major (K x (d+1))], V
// absent for the node-only objective (node_row = node_feature_dim of crf/model.hpp).
//
// Sums run over fixed blocks of nodes whose partial results are added in block order, so the
// value and gradient are the same for any thread count.

#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "inference/belief_propagation.hpp"
#include "node_features.hpp"
#include "primlabel/crf/training.hpp"

namespace primlabel::crf::detail {

struct ParameterShape {
  int classes = 0;    // K
  int node_dim = 0;   // node feature values before the bias: d, or d * knots
  int edge_dim = 0;   // d (descriptor values)
  bool edges = true;  // V present
  int node_row() const { return node_dim + 1; }
  int edge_row() const { return edge_dim + 1; }
  Eigen::Index node_size() const { return Eigen::Index(classes) * node_row(); }
  Eigen::Index size() const {
    return node_size() + (edges ? Eigen::Index(classes) * edge_row() : 0);
  }
};

// The parameters' model: `like` gives the classes, dimension, scale and knots.
CrfModel model_from_parameters(const Eigen::VectorXd& x, const ParameterShape& shape,
                               const CrfModel& like);

// A scene prepared for training, in double: node features x_i (crf/model.hpp), edge features
// u_i = [s * descriptor, 1] whose products make e_ij (left empty when no objective needs them),
// zero rows for inactive nodes, and the labels (-1 where ignored or inactive). Without edges the
// tent basis is kept compactly instead (`tents`, num_nodes x d; `features` empty): a tent row has
// two non-zero values per bin, so this is ~10x less memory to stream per evaluation.
struct PreparedScene {
  const Graph* graph = nullptr;
  RowMatrixXd features;
  RowMatrixXd edge_features;
  std::vector<TentPair> tents;
  std::vector<int> labels;
};

// `like` gives the dimension, scale and knots of the node features.
std::vector<PreparedScene> prepare_scenes(std::span<const LabeledGraph> scenes,
                                          const CrfModel& like, bool edge_features);

class Objective {
 public:
  virtual ~Objective() = default;
  // -(log-likelihood of the labelled points) / (number of labelled points); fills `gradient`.
  virtual double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) = 0;
};

// Pseudo-likelihood; with shape.edges == false, multinomial logistic regression (node-only).
// `class_weights`: one per class (the term of a point labelled y is weighted by class_weights[y])
// or empty (unweighted).
std::unique_ptr<Objective> make_pseudo_likelihood(const std::vector<PreparedScene>& scenes,
                                                  const ParameterShape& shape, int threads,
                                                  std::vector<double> class_weights = {});

// Log-likelihood with the Bethe approximation of log Z from loopy sum-product BP (the kernel
// inference uses), warm-started from the previous evaluation's messages. `context` (threads,
// stop) serves every evaluation; a stopped one throws Cancelled.
std::unique_ptr<Objective> make_bethe(const std::vector<PreparedScene>& scenes,
                                      const ParameterShape& shape, const BpSettings& bp,
                                      const RunContext& context);

// Fixed node blocks over all scenes (the unit of deterministic summation).
struct NodeBlock {
  int scene;
  long long first;
  long long count;
};
std::vector<NodeBlock> node_blocks(const std::vector<PreparedScene>& scenes);

// The objective from per-block partial results (one gradient column and loss per block), added in
// block order, not thread order, so it is identical for any thread count; divided by the
// (weighted) number of labelled points. Writes `gradient`, returns the value.
double sum_blocks(const Eigen::MatrixXd& partial_grad, const Eigen::VectorXd& partial_loss,
                  double labelled, Eigen::VectorXd& gradient);

}  // namespace primlabel::crf::detail
