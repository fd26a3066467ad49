#pragma once
// The training objectives behind train_crf. Each returns the negated log-(pseudo-)likelihood of
// the labelled points divided by their number, and its gradient; the L2 term is added by the
// driver. Parameters are one vector: [W row-major (K x (d+1)), V row-major (K x (d+1))], V absent
// for the node-only objective.
//
// Sums run over fixed blocks of nodes whose partial results are added in block order, so the
// value and gradient are the same for any thread count.

#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "loopy_bp.hpp"
#include "primlabel/crf/training.hpp"

namespace primlabel::crf::detail {

struct ParameterShape {
  int classes = 0;    // K
  int dim = 0;        // d (descriptor values)
  bool edges = true;  // V present
  int row() const { return dim + 1; }
  Eigen::Index size() const { return Eigen::Index(classes) * row() * (edges ? 2 : 1); }
};

CrfModel model_from_parameters(const Eigen::VectorXd& x, const ParameterShape& shape,
                               const std::vector<std::uint32_t>& class_ids, float feature_scale);

// A scene prepared for training: node features x_i = [s * descriptor, 1] in double (zero rows
// for inactive or ignored nodes) and the labels (-1 where ignored or inactive).
struct PreparedScene {
  const Graph* graph = nullptr;
  RowMatrixXd features;
  std::vector<int> labels;
};

std::vector<PreparedScene> prepare_scenes(std::span<const LabeledGraph> scenes,
                                          float feature_scale);

class Objective {
 public:
  virtual ~Objective() = default;
  // -(log-likelihood of the labelled points) / (number of labelled points); fills `gradient`.
  virtual double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) = 0;
};

// Pseudo-likelihood; with shape.edges == false, multinomial logistic regression (node-only).
std::unique_ptr<Objective> make_pseudo_likelihood(const std::vector<PreparedScene>& scenes,
                                                  const ParameterShape& shape, int threads);

// Log-likelihood with the Bethe approximation of log Z from loopy sum-product BP, warm-started
// from the previous evaluation's messages.
std::unique_ptr<Objective> make_bethe(const std::vector<PreparedScene>& scenes,
                                      const ParameterShape& shape, const BpSettings& bp);

// Fixed node blocks over all scenes (the unit of deterministic summation).
struct NodeBlock {
  int scene;
  long long first;
  long long count;
};
std::vector<NodeBlock> node_blocks(const std::vector<PreparedScene>& scenes);

}  // namespace primlabel::crf::detail
