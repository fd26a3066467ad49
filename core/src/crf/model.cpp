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
                         float feature_scale) {
  CrfModel m;
  m.class_ids = std::move(class_ids);
  m.descriptor_dim = descriptor_dim;
  m.feature_scale = feature_scale;
  m.node_weights = Eigen::MatrixXf::Zero(m.num_classes(), descriptor_dim + 1);
  m.edge_weights = Eigen::MatrixXf::Zero(m.num_classes(), descriptor_dim + 1);
  m.validate();
  return m;
}

void CrfModel::validate() const {
  if (class_ids.empty()) throw std::invalid_argument("CRF model: no classes");
  if (descriptor_dim <= 0) throw std::invalid_argument("CRF model: descriptor_dim <= 0");
  std::vector<std::uint32_t> sorted = class_ids;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw std::invalid_argument("CRF model: repeated class id");
  const auto check = [&](const Eigen::MatrixXf& w, const char* what) {
    if (w.rows() != num_classes() || w.cols() != feature_dim())
      throw std::invalid_argument(std::string("CRF model: ") + what + " is not K x (d + 1)");
    if (!w.allFinite())
      throw std::invalid_argument(std::string("CRF model: ") + what + " has a non-finite weight");
  };
  check(node_weights, "node_weights");
  check(edge_weights, "edge_weights");
  if (!(feature_scale > 0.0f) || !std::isfinite(feature_scale))
    throw std::invalid_argument("CRF model: feature_scale must be positive");
}

}  // namespace primlabel::crf
