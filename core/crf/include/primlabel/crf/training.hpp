#pragma once
// Training a CrfModel by maximising the L2-regularised conditional log-likelihood with L-BFGS
// (LBFGSpp). Three objectives:
//   kPseudoLikelihood  sum_i log p(y_i | y_N(i), x): exact gradient, convex, fast (default)
//   kBetheBp           log p(y | x) with log Z from the Bethe free energy of loopy sum-product
//                      BP; gradients from the BP node and pairwise marginals (approximate)
//   kNodeOnly          multinomial logistic regression on the node features (edge weights 0)
//   kPiecewise         piecewise training: the node factors alone, as kNodeOnly; the caller then
//                      sets the associative coupling (pipeline::train_label_model picks one
//                      Potts coupling on validation scenes). The fast default: on dense scan
//                      graphs pseudo-likelihood overestimates the couplings (it conditions on the
//                      true neighbour labels, which nearly always agree) and Bethe is slow.
// The minimised function is  -(1 / P) * objective + (l2 / 2) * |weights without biases|^2, with
// P the number of labelled points, so l2 means the same for any amount of data.
// Class weights (TrainingOptions::class_weights, not for kBetheBp) weight every point's term by
// the weight w_y of its label, and P becomes the weighted count sum_i w_{y_i}: only the ratios of
// the weights matter. Rare classes (corners are ~0.5% of a table scene) then cost what their
// errors are worth instead of what their point count is; class_balance_weights gives the usual
// choice.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/crf/model.hpp"

namespace primlabel::crf {

inline constexpr int kIgnoreLabel = -1;

// One training scene. Labels are class indices 0..K-1 (into the class_ids given to train_crf),
// or kIgnoreLabel. Ignored points are left out of every objective: they are no target, and for
// pseudo-likelihood no neighbour either; kBetheBp removes them (and their edges) from the graph.
struct LabeledGraph {
  Descriptors descriptors;  // one row per node
  Graph graph;
  std::vector<int> labels;  // one per node
};

enum class TrainingObjective { kPseudoLikelihood, kBetheBp, kNodeOnly, kPiecewise };

// One point of the training curve (Rusu et al. 2009, Fig. 9).
struct TrainingIteration {
  int iteration = 0;
  double objective = 0.0;  // the minimised function (negated, normalised, regularised)
  double train_accuracy = 0.0;
  double validation_accuracy = 0.0;  // NaN without a validation set
  double seconds = 0.0;              // since training started
};

struct TrainingOptions {
  TrainingObjective objective = TrainingObjective::kPiecewise;
  double l2 = 1e-3;
  int max_iterations = 100;
  double epsilon = 1e-5;  // stop when |gradient| <= epsilon * max(1, |weights|)
  float feature_scale = 0.01f;
  // The node feature basis (crf/model.hpp): tent knots, or empty for the paper's identity.
  std::vector<float> node_knots = default_node_knots();
  // One positive, finite weight per class index, or empty for the unweighted objective (see the
  // top of this file). Not for kBetheBp, whose log Z does not split into per-point terms.
  std::vector<double> class_weights;
  // BP used by kBetheBp (sum-product) and to measure accuracies for on_iteration.
  InferenceSettings inference;
  // Called after every L-BFGS iteration with accuracies measured by inference; when empty, no
  // accuracy is computed (training is faster).
  std::function<void(const TrainingIteration&)> on_iteration;
};

struct TrainingResult {
  CrfModel model;
  int iterations = 0;
  double objective = 0.0;
  bool converged = false;           // the gradient criterion was met
  bool line_search_failed = false;  // stopped early; model holds the best weights found
  std::string message;              // why training stopped
  std::vector<TrainingIteration> curve;
};

// class_ids[k] names class index k in the model. Throws std::invalid_argument for inconsistent
// data (shapes, labels out of range, descriptor dimensions that differ), and Cancelled when
// context.stop is requested (checked inside every evaluation). The model does not depend on
// context.threads.
TrainingResult train_crf(std::span<const LabeledGraph> training,
                         std::span<const LabeledGraph> validation,
                         const std::vector<std::uint32_t>& class_ids,
                         const TrainingOptions& options = {}, const RunContext& context = {});

// Class weights balancing the labelled point counts n_c (N in all, K classes with points):
// w_c = (N / (K * n_c))^alpha, alpha in [0, 1]. alpha = 0 gives all ones (the unweighted
// objective, exactly), alpha = 1 makes every class count as much as any other in total. A class
// without points gets 1 (it has no terms to weight). Throws std::invalid_argument for alpha
// outside [0, 1] or no point at all.
std::vector<double> class_balance_weights(std::span<const std::uint64_t> class_points,
                                          double alpha);

// Fraction of labelled points (label >= 0) whose predicted class index equals the label.
double labeled_accuracy(const CrfModel& model, std::span<const LabeledGraph> scenes,
                        const InferenceSettings& inference, const RunContext& context = {});

// The training curve as CSV: header
// "iteration,objective,train_accuracy,validation_accuracy,seconds".
void write_training_curve_csv(std::ostream& out, std::span<const TrainingIteration> curve);
std::string training_curve_csv_header();
std::string training_curve_csv_row(const TrainingIteration& it);

}  // namespace primlabel::crf
