#pragma once
// Scoring against the fitted ground truth (synth/fitted_truth.hpp), and that truth's own error: the same
// fitting and labeling run on held-out synthetic Kinect table scenes, whose true labels are
// known, compared with them per class.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/synth/fitted_truth.hpp"

namespace primlabel::research {

// The fitted truth lives beside the shapes it fits (primlabel/synth/fitted_truth.hpp).
using synth::fit_object_truth;
using synth::fitted_kind_name;
using synth::FittedKind;
using synth::FittedObject;
using synth::is_mosd_object_label;
using synth::is_mosd_table_label;
using synth::mosd_segments;
using synth::ObjectTruth;
using synth::ObjectTruthOptions;
using synth::synthetic_segments;

// The taxonomy's classes without unknown (what the truth labels score).
std::vector<std::uint32_t> scored_class_ids();

// Adds (truth, predicted) for every object point (segments > 0) the fitted truth labels.
void add_object_points(crf::ConfusionMatrix& confusion, const std::vector<int>& segments,
                       const std::vector<std::uint32_t>& truth,
                       const std::vector<std::uint32_t>& predicted);

struct TruthCheckOptions {
  int scenes = 4;  // synthetic Kinect table scenes of the test set (seeds 3000 + first + i)
  int first = 0;
  ObjectTruthOptions truth;
};

struct TruthCheck {
  // Rows: the synthetic true label; columns: the fitted truth. For points of objects whose true
  // shape is a box or a can (what the models describe), and for all objects.
  crf::ConfusionMatrix box_can{scored_class_ids()}, all{scored_class_ids()};
  std::uint64_t box_can_points = 0, all_points = 0;  // object points, labeled or not
  // Objects by true shape kind ("box", "can", "mug", ...) and fitted kind name.
  std::map<std::string, std::map<std::string, int>> kinds;
};

TruthCheck check_truth_on_synthetic(const TruthCheckOptions& options,
                                    const RunContext& context = {});

std::string truth_check_text(const TruthCheck& check);
std::string truth_check_json(const TruthCheck& check);

// JSON of the per-class precision / recall / support, the accuracy and the counts themselves
// ("confusion": columns, then rows of counts, truth by predicted) of a confusion matrix.
json::Json confusion_classes_json(const crf::ConfusionMatrix& confusion);

}  // namespace primlabel::research
