#pragma once
// The CRF node feature basis as primlabel-train and primlabel-research table1 take it on the
// command line.

#include <string>
#include <vector>

namespace primlabel::cli {

// The CRF node feature basis of --node-basis (tent | linear) and --node-knots: the knots given,
// crf::default_node_knots() for tent without them, nothing for linear. Throws
// std::invalid_argument for knots with linear or knots crf::validate_node_knots refuses.
std::vector<float> node_knots(const std::string& basis, const std::vector<float>& knots);
inline constexpr const char* kNodeKnotsHelp =
    "tent basis knots, scaled units (bin % / 100), comma separated and increasing "
    "(default 0,0.025,0.05,0.1,0.15,0.25,0.35,0.5,0.7,1)";

}  // namespace primlabel::cli
