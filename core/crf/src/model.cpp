#include "primlabel/crf/model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace primlabel::crf {

std::optional<int> CrfModel::class_index(std::uint32_t id) const {
  const auto it = std::find(class_ids.begin(), class_ids.end(), id);
  if (it == class_ids.end()) return std::nullopt;
  return static_cast<int>(it - class_ids.begin());
}

CrfModel CrfModel::zeros(std::vector<std::uint32_t> class_ids, int descriptor_dim,
                         float feature_scale, std::vector<float> node_knots) {
  CrfModel m;
  m.class_ids = std::move(class_ids);
  m.descriptor_dim = descriptor_dim;
  m.feature_scale = feature_scale;
  m.node_knots = std::move(node_knots);
  m.node_weights = Eigen::MatrixXf::Zero(m.num_classes(), m.node_feature_dim());
  m.edge_weights = Eigen::MatrixXf::Zero(m.num_classes(), m.edge_feature_dim());
  m.validate();
  return m;
}

void validate_node_knots(const std::vector<float>& knots) {
  if (knots.empty()) return;
  if (knots.size() < 2 || knots.size() > std::size_t(kMaxNodeKnots))
    throw std::invalid_argument("node knots: " + std::to_string(knots.size()) + " (2.." +
                                std::to_string(kMaxNodeKnots) + " or none)");
  for (std::size_t a = 0; a < knots.size(); ++a)
    if (!std::isfinite(knots[a]) || (a > 0 && !(knots[a] > knots[a - 1])))
      throw std::invalid_argument("node knots are not finite and increasing (knot " +
                                  std::to_string(a) + ": " + std::to_string(knots[a]) + ")");
}

void CrfModel::validate() const {
  if (class_ids.empty()) throw std::invalid_argument("CRF model: no classes");
  if (descriptor_dim <= 0) throw std::invalid_argument("CRF model: descriptor_dim <= 0");
  std::vector<std::uint32_t> sorted = class_ids;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw std::invalid_argument("CRF model: repeated class id");
  try {
    validate_node_knots(node_knots);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("CRF model: ") + e.what());
  }
  const auto check = [&](const Eigen::MatrixXf& w, const char* what, int cols) {
    if (w.rows() != num_classes() || w.cols() != cols)
      throw std::invalid_argument(std::string("CRF model: ") + what + " is " +
                                  std::to_string(w.rows()) + " x " + std::to_string(w.cols()) +
                                  ", not " + std::to_string(num_classes()) + " x " +
                                  std::to_string(cols));
    if (!w.allFinite())
      throw std::invalid_argument(std::string("CRF model: ") + what + " has a non-finite weight");
  };
  check(node_weights, "node_weights", node_feature_dim());
  check(edge_weights, "edge_weights", edge_feature_dim());
  if (!(feature_scale > 0.0f) || !std::isfinite(feature_scale))
    throw std::invalid_argument("CRF model: feature_scale must be positive");
}

}  // namespace primlabel::crf
