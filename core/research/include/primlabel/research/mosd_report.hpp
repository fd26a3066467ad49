#pragma once
// How a model labels real Kinect table scenes (the mOSD set in ../shared/data/mosd): the share of
// table points labeled plane, and the labeled scene as a picture. mOSD's `label` field marks
// segments, not primitives: 0 invalid, 1-9 (parts of) the table, 20 and up objects.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/synth/fitted_truth.hpp"
#include "primlabel/research/truth_check.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::research {


// The fitted object truth of one scene (synth/fitted_truth.hpp) and, with a model, its scores on it.
struct MosdObjectTruth {
  std::vector<FittedObject> objects;
  std::uint64_t object_points = 0;  // finite points of object segments
  std::uint64_t truth_points = 0;   // ... that the fitted truth labels (the scored ones)
  crf::ConfusionMatrix scores{scored_class_ids()};  // rows fitted truth, columns the model
  std::string truth_file;                           // the labeled truth PCD, when written
  std::size_t count(FittedKind kind) const;
};

struct MosdTruthRequest {
  bool enabled = false;
  ObjectTruthOptions options;
  std::string write_path;  // when set: the truth as a labeled PCD (taxonomy ids, `segment` field)
};

// Fits the object truth of an mOSD scene (its `label` field holds the segments); `labels`, when
// given, receives the truth label of every point.
MosdObjectTruth fit_mosd_truth(const PointCloud& cloud, const MosdTruthRequest& request,
                               const RunContext& context = {},
                               std::vector<std::uint32_t>* labels = nullptr);

struct MosdSceneReport {
  std::string file;
  std::uint64_t points = 0;        // finite points
  std::uint64_t table_points = 0;  // finite points labelled 1-9 in the file
  std::uint64_t table_plane = 0;   // ... that the model labels plane
  // Table points farther than kContactBand from every object point, and those labeled plane:
  // the table away from the contact band, where the taxonomy's rule at scale r makes the table
  // around an object's foot a concave edge rather than plane.
  std::uint64_t table_away = 0, table_away_plane = 0;
  std::uint64_t object_points = 0, object_plane = 0;
  std::vector<std::uint64_t> table_predicted;  // table points per predicted taxonomy id
  double feature_seconds = 0, inference_seconds = 0;
  std::string png;                              // the labeled picture, when written
  std::optional<MosdObjectTruth> object_truth;  // with MosdTruthRequest::enabled

  // Table points without a descriptor (unknown) count as not plane.
  double plane_share() const;
  double away_plane_share() const;  // table_away_plane / table_away
  double object_plane_share() const;
};

// The contact band: the label radius r of the ground-truth rule.
inline constexpr float kContactBand = static_cast<float>(synth::kDefaultLabelRadius);

// Labels the scene at `path` with `model` and counts. When `png_path` is not empty, also renders
// the predicted classes from the sensor's view (class colours, legend) there. With `truth`
// enabled, also fits the object truth and scores the model's labels of the object points on it.
MosdSceneReport report_mosd_scene(const LabelModel& model, const std::string& path,
                                  const std::string& png_path,
                                  const pipeline::LabelingOptions& options = {},
                                  const RunContext& context = {},
                                  const MosdTruthRequest& truth = {});

struct MosdReport {
  std::vector<MosdSceneReport> scenes;
  std::uint64_t table_points = 0, table_plane = 0;
  std::uint64_t table_away = 0, table_away_plane = 0;
  std::optional<MosdObjectTruth> object_truth;  // over every scene that has one
  double plane_share() const;                   // over all scenes' table points
  double away_plane_share() const;              // ... away from the contact band
  double mean_plane_share() const;              // the scenes' shares, averaged
  double mean_away_plane_share() const;
};

MosdReport summarize_mosd(std::vector<MosdSceneReport> scenes);

// JSON of a fitted object (segment, kind, points, inlier share, rms, size, pose, both costs) and
// of a scene's (or the overall) object truth: model counts, points, scores, per object.
json::Json fitted_object_json(const FittedObject& object);
json::Json object_truth_json(const MosdObjectTruth& truth, bool with_objects);

// Fixed-width text table, one row per scene and the overall share; with object truth, the fitted
// models per scene and the model's per-class recall / precision on the object points.
std::string mosd_report_text(const MosdReport& report);
// One JSON object: {"scenes":[{...}], "table_points", "table_plane", "plane_share",
// "mean_plane_share", "table_away", "away_plane_share", "mean_away_plane_share"}, and
// "object_truth" (per scene and overall) when fitted.
std::string mosd_report_json(const MosdReport& report);

}  // namespace primlabel::research
