#pragma once
// Log-potentials of a CrfModel on one graph (the scores of model.hpp), shared by inference and
// training. Float, row-major, computed in fixed-size blocks so the values never depend on the
// thread count.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"

namespace primlabel::crf::detail {

using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// theta_i(k) for every node: num_nodes x K; rows of inactive nodes are zero.
RowMatrixXf node_scores(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads);

// theta_ij(k, k) for every directed slot: num_slots x K (both directions of an edge hold the same
// row). Zero when the model has no edge terms.
RowMatrixXf edge_scores(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads);

// Threads worth starting for `nodes` nodes: small graphs run on one thread, since a parallel
// region per BP iteration costs more than it saves there (and stalls on a busy machine).
// Results never depend on the thread count, so this only changes speed.
int useful_threads(int requested, std::size_t nodes);

// Checks that descriptors are num_nodes x model.descriptor_dim; throws std::invalid_argument.
void check_shapes(const CrfModel& model, std::span<const float> descriptors, const Graph& graph);

}  // namespace primlabel::crf::detail
