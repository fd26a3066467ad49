#include "node_basis.hpp"

#include <stdexcept>

#include "primlabel/crf/model.hpp"

namespace primlabel::cli {

std::vector<float> node_knots(const std::string& basis, const std::vector<float>& knots) {
  if (basis == "linear") {
    if (!knots.empty()) throw std::invalid_argument("--node-knots needs --node-basis tent");
    return {};
  }
  if (knots.empty()) return crf::default_node_knots();
  try {
    crf::validate_node_knots(knots);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--node-knots: ") + e.what());
  }
  return knots;
}

}  // namespace primlabel::cli
