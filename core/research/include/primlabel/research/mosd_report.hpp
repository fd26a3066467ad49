#pragma once
// How a model labels real Kinect table scenes (the mOSD set in ../shared/data/mosd): the share of
// table points labeled plane, and the labeled scene as a picture. mOSD's `label` field marks
// segments, not primitives: 0 invalid, 1-9 (parts of) the table, 20 and up objects.

#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::research {

inline bool is_mosd_table_label(std::uint32_t label) { return label >= 1 && label <= 9; }
inline bool is_mosd_object_label(std::uint32_t label) { return label >= 20; }

struct MosdSceneReport {
  std::string file;
  std::uint64_t points = 0;        // finite points
  std::uint64_t table_points = 0;  // finite points labelled 1-9 in the file
  std::uint64_t table_plane = 0;   // ... that the model labels plane
  std::uint64_t object_points = 0, object_plane = 0;
  std::vector<std::uint64_t> table_predicted;  // table points per predicted taxonomy id
  double feature_seconds = 0, inference_seconds = 0;
  std::string png;  // the labeled picture, when written

  // Table points without a descriptor (unknown) count as not plane.
  double plane_share() const;
  double object_plane_share() const;
};

// Labels the scene at `path` with `model` and counts. When `png_path` is not empty, also renders
// the predicted classes from the sensor's view (class colours, legend) there.
MosdSceneReport report_mosd_scene(const LabelModel& model, const std::string& path,
                                  const std::string& png_path,
                                  const pipeline::LabelingOptions& options = {},
                                  const RunContext& context = {});

struct MosdReport {
  std::vector<MosdSceneReport> scenes;
  std::uint64_t table_points = 0, table_plane = 0;
  double plane_share() const;  // over all scenes' table points
};

MosdReport summarize_mosd(std::vector<MosdSceneReport> scenes);

// Fixed-width text table, one row per scene and the overall share.
std::string mosd_report_text(const MosdReport& report);
// One JSON object: {"scenes":[{...}], "table_points", "table_plane", "plane_share"}.
std::string mosd_report_json(const MosdReport& report);

}  // namespace primlabel::research
