#pragma once
// Where the mOSD subcommands (mosd-report, write-truth) put what they write: the output folders,
// and each scene's request for its fitted object truth.

#include <string>

#include "primlabel/research/mosd_report.hpp"

namespace primlabel::research_tool {

// Creates DIR and its parents; throws std::runtime_error naming DIR when it cannot.
void make_directory(const std::string& dir);

// The fitted truth of SCENE: fitted when `enabled` or when TRUTH_DIR is given, at label radius
// RADIUS, and written as TRUTH_DIR/<scene stem>_truth.pcd when TRUTH_DIR is not empty.
research::MosdTruthRequest truth_request(bool enabled, double radius, const std::string& truth_dir,
                                         const std::string& scene);

}  // namespace primlabel::research_tool
