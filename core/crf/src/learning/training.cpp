#include "primlabel/crf/training.hpp"

#include <LBFGS.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "learning/objectives.hpp"
#include "node_features.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf {
namespace detail {

namespace {
constexpr long long kBlockNodes = 512;
}

CrfModel model_from_parameters(const Eigen::VectorXd& x, const ParameterShape& shape,
                               const CrfModel& like) {
  CrfModel model = like;
  model.node_weights =
      Eigen::Map<const RowMatrixXd>(x.data(), shape.classes, shape.node_row()).cast<float>();
  model.edge_weights.setZero(shape.classes, shape.edge_row());
  if (shape.edges)
    model.edge_weights =
        Eigen::Map<const RowMatrixXd>(x.data() + shape.node_size(), shape.classes, shape.edge_row())
            .cast<float>();
  return model;
}

std::vector<PreparedScene> prepare_scenes(std::span<const LabeledGraph> scenes,
                                          const CrfModel& like, bool edge_features) {
  std::vector<PreparedScene> prepared(scenes.size());
  const int d = like.descriptor_dim;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const LabeledGraph& in = scenes[s];
    PreparedScene& out = prepared[s];
    const long long n = static_cast<long long>(in.graph.num_nodes());
    const bool compact = !edge_features && !like.node_knots.empty();
    out.graph = &in.graph;
    if (compact)
      out.tents.assign(std::size_t(n) * d, TentPair{0, 0.0f, 0.0f});
    else
      out.features.setZero(n, like.node_feature_dim());
    if (edge_features) out.edge_features.setZero(n, like.edge_feature_dim());
    out.labels.assign(n, kIgnoreLabel);
    for (long long i = 0; i < n; ++i) {
      if (!in.graph.active[i]) continue;
      const float* descriptor = in.descriptors.row(std::size_t(i)).data();
      if (compact)
        tent_pairs(descriptor, d, like.feature_scale, like.node_knots,
                   &out.tents[std::size_t(i) * d]);
      else
        node_features(like, descriptor, out.features.row(i).data());
      if (edge_features)
        node_features(descriptor, d, like.feature_scale, {}, out.edge_features.row(i).data());
      out.labels[i] = in.labels[i];
    }
  }
  return prepared;
}

std::vector<NodeBlock> node_blocks(const std::vector<PreparedScene>& scenes) {
  std::vector<NodeBlock> blocks;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const long long n = static_cast<long long>(scenes[s].labels.size());
    for (long long first = 0; first < n; first += kBlockNodes)
      blocks.push_back({static_cast<int>(s), first, std::min(kBlockNodes, n - first)});
  }
  return blocks;
}

double sum_blocks(const Eigen::MatrixXd& partial_grad, const Eigen::VectorXd& partial_loss,
                  double labelled, Eigen::VectorXd& gradient) {
  gradient.setZero(partial_grad.rows());
  double loss = 0.0;
  for (Eigen::Index b = 0; b < partial_grad.cols(); ++b) {
    gradient += partial_grad.col(b);
    loss += partial_loss(b);
  }
  const double scale = labelled > 0 ? 1.0 / labelled : 0.0;
  gradient *= scale;
  return loss * scale;
}

}  // namespace detail

namespace {

using Vector = Eigen::VectorXd;

void check_scenes(std::span<const LabeledGraph> scenes, int dim, int classes, const char* what) {
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const LabeledGraph& g = scenes[s];
    const std::string where = std::string(what) + " scene " + std::to_string(s) + ": ";
    if (g.descriptors.dim != dim)
      throw std::invalid_argument(where + "descriptor dimension differs from the first scene");
    if (g.descriptors.size() != g.graph.num_nodes())
      throw std::invalid_argument(where + "descriptors are not one row per node");
    if (g.labels.size() != g.graph.num_nodes())
      throw std::invalid_argument(where + "labels are not one per node");
    for (int y : g.labels)
      if (y < kIgnoreLabel || y >= classes)
        throw std::invalid_argument(where + "label " + std::to_string(y) + " out of range");
  }
}

// The function LBFGSpp minimises: objective / P + (l2 / 2) |non-bias weights|^2. It also records
// every accepted iterate (see ReportingLineSearch) for the curve and the early-stop fallback.
class Problem {
 public:
  Problem(detail::Objective& objective, const detail::ParameterShape& shape, double l2,
          std::stop_token stop)
      : objective_(objective), shape_(shape), l2_(l2), stop_(std::move(stop)) {
    regularised_ = Vector::Ones(shape.size());
    // Biases (the last column of W and of V) are free.
    for (int k = 0; k < shape.classes; ++k) {
      regularised_((k + 1) * Eigen::Index(shape.node_row()) - 1) = 0.0;
      if (shape.edges)
        regularised_(shape.node_size() + (k + 1) * Eigen::Index(shape.edge_row()) - 1) = 0.0;
    }
  }

  double operator()(const Vector& x, Vector& grad) {
    throw_if_stopped(stop_, "training");  // per evaluation: each one is a pass over the scenes
    const double loss = objective_.evaluate(x, grad);
    const Vector rx = regularised_.cwiseProduct(x);
    grad += l2_ * rx;
    return loss + 0.5 * l2_ * rx.squaredNorm();
  }

  // Called by the line search with each accepted iterate.
  void accepted(const Vector& x, double fx) {
    ++iterations_;
    if (fx <= best_fx_) {
      best_fx_ = fx;
      best_x_ = x;
    }
    if (on_accept_) on_accept_(iterations_, x, fx);
  }

  void start(const Vector& x0, double f0) {
    best_x_ = x0;
    best_fx_ = f0;
  }
  std::function<void(int, const Vector&, double)> on_accept_;
  const Vector& best_x() const { return best_x_; }
  double best_fx() const { return best_fx_; }
  int iterations() const { return iterations_; }

 private:
  detail::Objective& objective_;
  detail::ParameterShape shape_;
  double l2_;
  std::stop_token stop_;
  Vector regularised_;
  Vector best_x_;
  double best_fx_ = std::numeric_limits<double>::infinity();
  int iterations_ = 0;
};

// LBFGSpp's backtracking line search, plus a report of the accepted point: LBFGSpp 0.1 has no
// iteration callback, and one line search is exactly one L-BFGS iteration.
template <typename Scalar>
class ReportingLineSearch {
 public:
  using Vec = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  template <typename Foo>
  static void LineSearch(Foo& f, Scalar& fx, Vec& x, Vec& grad, Scalar& step, const Vec& drt,
                         const Vec& xp, const LBFGSpp::LBFGSParam<Scalar>& param) {
    LBFGSpp::LineSearchBacktracking<Scalar>::LineSearch(f, fx, x, grad, step, drt, xp, param);
    f.accepted(x, fx);
  }
};

}  // namespace

std::vector<double> class_balance_weights(std::span<const std::uint64_t> class_points,
                                          double alpha) {
  if (!(alpha >= 0.0 && alpha <= 1.0))
    throw std::invalid_argument("class balance: alpha must be in [0, 1]");
  double total = 0.0;
  int present = 0;
  for (std::uint64_t n : class_points) {
    total += double(n);
    present += n > 0 ? 1 : 0;
  }
  if (present == 0) throw std::invalid_argument("class balance: no labelled point");
  std::vector<double> weights(class_points.size(), 1.0);
  if (alpha == 0.0) return weights;  // exactly the unweighted objective
  for (std::size_t c = 0; c < class_points.size(); ++c)
    if (class_points[c] > 0)
      weights[c] = std::pow(total / (double(present) * double(class_points[c])), alpha);
  return weights;
}

double labeled_accuracy(const CrfModel& model, std::span<const LabeledGraph> scenes,
                        const InferenceSettings& inference, const RunContext& context) {
  std::size_t labelled = 0, correct = 0;
  for (const LabeledGraph& scene : scenes) {
    const InferenceResult result =
        infer(model, scene.descriptors, scene.graph, inference, {}, context);
    for (std::size_t i = 0; i < scene.labels.size(); ++i) {
      const int y = scene.labels[i];
      if (y < 0) continue;
      ++labelled;
      correct += result.labels[i] == model.class_ids[y] ? 1 : 0;
    }
  }
  return labelled > 0 ? double(correct) / double(labelled)
                      : std::numeric_limits<double>::quiet_NaN();
}

TrainingResult train_crf(std::span<const LabeledGraph> training,
                         std::span<const LabeledGraph> validation,
                         const std::vector<std::uint32_t>& class_ids,
                         const TrainingOptions& options, const RunContext& context) {
  if (training.empty()) throw std::invalid_argument("train_crf: no training scenes");
  if (class_ids.empty()) throw std::invalid_argument("train_crf: no classes");
  const int dim = training.front().descriptors.dim;
  if (dim <= 0) throw std::invalid_argument("train_crf: descriptor dimension <= 0");
  const int classes = static_cast<int>(class_ids.size());
  check_scenes(training, dim, classes, "training");
  check_scenes(validation, dim, classes, "validation");
  if (!(options.l2 >= 0.0)) throw std::invalid_argument("train_crf: l2 < 0");
  if (options.max_iterations < 1) throw std::invalid_argument("train_crf: max_iterations < 1");
  if (!options.class_weights.empty()) {
    if (options.class_weights.size() != class_ids.size())
      throw std::invalid_argument("train_crf: class_weights are not one per class");
    for (double w : options.class_weights)
      if (!(w > 0.0 && std::isfinite(w)))
        throw std::invalid_argument("train_crf: a class weight is not positive and finite");
    if (options.objective == TrainingObjective::kBetheBp)
      throw std::invalid_argument(
          "train_crf: class weights need a per-point objective (piecewise, node-only, "
          "pseudo-likelihood), not bethe");
  }
  std::size_t total_nodes = 0;
  for (const auto& scene : training) total_nodes += scene.graph.num_nodes();
  const int threads = detail::useful_threads(context.threads, total_nodes);
  const auto started = std::chrono::steady_clock::now();

  // The zero model fixes the shapes (and checks the scale and knots).
  const CrfModel like = CrfModel::zeros(class_ids, dim, options.feature_scale, options.node_knots);
  detail::ParameterShape shape;
  shape.classes = classes;
  shape.node_dim = like.node_feature_dim() - 1;
  shape.edge_dim = dim;
  shape.edges = options.objective != TrainingObjective::kNodeOnly &&
                options.objective != TrainingObjective::kPiecewise;

  std::vector<detail::PreparedScene> scenes = detail::prepare_scenes(training, like, shape.edges);
  std::vector<Graph> restricted;  // Bethe: the graph over the labelled nodes only
  std::unique_ptr<detail::Objective> objective;
  if (options.objective == TrainingObjective::kBetheBp) {
    restricted.reserve(scenes.size());
    for (auto& scene : scenes) {
      std::vector<std::uint8_t> labelled(scene.labels.size());
      for (std::size_t i = 0; i < labelled.size(); ++i) labelled[i] = scene.labels[i] >= 0;
      restricted.push_back(restrict_graph(*scene.graph, labelled));
      scene.graph = &restricted.back();
    }
    detail::BpSettings bp;
    // The Bethe value and gradient are only right at a BP fixed point: converge tighter and
    // longer than for labelling (warm starts make later evaluations cheap).
    bp.max_iterations = std::max(options.inference.max_iterations, 100);
    bp.damping = options.inference.damping;
    bp.tolerance = std::min(options.inference.tolerance, 1e-4f);
    objective = detail::make_bethe(scenes, shape, bp, context.with_threads(threads));
  } else {
    objective = detail::make_pseudo_likelihood(scenes, shape, threads, options.class_weights);
  }

  TrainingResult result;
  Problem problem(*objective, shape, options.l2, context.stop);
  const InferenceSettings& inference = options.inference;
  const auto seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  problem.on_accept_ = [&](int iteration, const Vector& x, double fx) {
    TrainingIteration it;
    it.iteration = iteration;
    it.objective = fx;
    it.validation_accuracy = std::numeric_limits<double>::quiet_NaN();
    if (options.on_iteration) {
      const CrfModel model = detail::model_from_parameters(x, shape, like);
      it.train_accuracy = labeled_accuracy(model, training, inference, context);
      if (!validation.empty())
        it.validation_accuracy = labeled_accuracy(model, validation, inference, context);
    } else {
      it.train_accuracy = std::numeric_limits<double>::quiet_NaN();
    }
    it.seconds = seconds();
    result.curve.push_back(it);
    if (options.on_iteration) options.on_iteration(it);
  };

  LBFGSpp::LBFGSParam<double> param;
  param.epsilon = options.epsilon;
  param.epsilon_rel = options.epsilon;
  param.max_iterations = options.max_iterations;
  // Wolfe's curvature condition asks for longer steps, which on the Bethe objective run into
  // parameters where BP no longer converges (NaN); sufficient decrease is enough there.
  param.linesearch = options.objective == TrainingObjective::kBetheBp
                         ? LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_ARMIJO
                         : LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_WOLFE;
  LBFGSpp::LBFGSSolver<double, ReportingLineSearch> solver(param);

  Vector x = Vector::Zero(shape.size());
  {
    Vector g(shape.size());
    problem.start(x, problem(x, g));
  }
  double fx = problem.best_fx();
  try {
    const int k = solver.minimize(problem, x, fx);
    result.iterations = problem.iterations();
    result.converged = k < options.max_iterations;
    result.message = result.converged ? "converged" : "reached max_iterations";
  } catch (const std::exception& e) {
    // The BP objective is approximate, so its line search may fail; keep the best iterate.
    result.line_search_failed = true;
    result.iterations = problem.iterations();
    result.message = std::string("line search failed: ") + e.what();
  }
  result.objective = problem.best_fx();
  result.model = detail::model_from_parameters(problem.best_x(), shape, like);
  return result;
}

std::string training_curve_csv_header() {
  return "iteration,objective,train_accuracy,validation_accuracy,seconds";
}

std::string training_curve_csv_row(const TrainingIteration& it) {
  std::ostringstream row;
  row << std::setprecision(10) << it.iteration << ',' << it.objective << ',';
  const auto number = [&](double v) {
    if (std::isnan(v))
      row << "";  // empty cell: not measured
    else
      row << v;
  };
  number(it.train_accuracy);
  row << ',';
  number(it.validation_accuracy);
  row << ',' << it.seconds;
  return row.str();
}

void write_training_curve_csv(std::ostream& out, std::span<const TrainingIteration> curve) {
  out << training_curve_csv_header() << '\n';
  for (const auto& it : curve) out << training_curve_csv_row(it) << '\n';
}

}  // namespace primlabel::crf
