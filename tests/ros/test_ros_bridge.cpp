// The node's message handling without a ROS master: x y z read from PointCloud2 layouts
// (FLOAT32/FLOAT64, padding, row_step, byte order, NaN pixels), bad layouts rejected with their
// reason, the labeled cloud keeping the input's fields and bytes, the echoed header, the JSON.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "pointcloud2_test_util.hpp"
#include "primlabel/ros/pointcloud2_message.hpp"
#include "primlabel/ros_common/node_parameters.hpp"
#include "primlabel/ros_common/summary_json.hpp"

namespace primlabel::rostest {
namespace {

using rosnode::labeled_pointcloud2;
using rosnode::xyz_from_pointcloud2;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// 3 columns x 2 rows, one invalid pixel, an rgba and an intensity field.
PointCloud organised_cloud() {
  PointCloud cloud;
  cloud.xyz = {{0.1f, 0.2f, 1.0f}, {0.2f, 0.2f, 1.1f}, {kNaN, kNaN, kNaN},
               {0.1f, 0.3f, 1.2f}, {0.2f, 0.3f, 1.3f}, {-0.3f, 0.4f, 1.25f}};
  cloud.width = 3;
  cloud.height = 2;
  cloud.rgba = {0xFF102030u, 0xFF405060u, 0u, 0xFF708090u, 0xFFA0B0C0u, 0xFFD0E0F0u};
  FloatField intensity{"intensity", 1, {10, 20, 30, 40, 50, 60}};
  cloud.fields.push_back(intensity);
  return cloud;
}

void expect_same_points(const PointCloud& read, const PointCloud& sent) {
  ASSERT_EQ(read.size(), sent.size());
  EXPECT_EQ(read.width, sent.width);
  EXPECT_EQ(read.height, sent.height);
  for (std::size_t i = 0; i < sent.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (std::isnan(sent.xyz[i][k]))
        EXPECT_TRUE(std::isnan(read.xyz[i][k])) << i;
      else
        EXPECT_EQ(read.xyz[i][k], sent.xyz[i][k]) << i << " " << k;
    }
}

TEST(PointCloud2Xyz, ReadsFloat32WithPointAndRowPadding) {
  const PointCloud cloud = organised_cloud();
  const PointCloud2 m = to_pointcloud2(cloud, layout_of(false, false, 12));
  ASSERT_GT(m.row_step, m.width * m.point_step);
  expect_same_points(xyz_from_pointcloud2(m), cloud);
}

TEST(PointCloud2Xyz, ReadsFloat64AndBigEndian) {
  const PointCloud cloud = organised_cloud();
  expect_same_points(xyz_from_pointcloud2(to_pointcloud2(cloud, layout_of(true, false, 0))), cloud);
  expect_same_points(xyz_from_pointcloud2(to_pointcloud2(cloud, layout_of(false, true, 0))), cloud);
  expect_same_points(xyz_from_pointcloud2(to_pointcloud2(cloud, layout_of(true, true, 3))), cloud);
}

TEST(PointCloud2Xyz, ReadsFieldsInAnyOrderAndOffset) {
  PointCloud2 m = to_pointcloud2(organised_cloud());
  std::reverse(m.fields.begin(), m.fields.end());  // z y x order in the list, offsets unchanged
  expect_same_points(xyz_from_pointcloud2(m), organised_cloud());
}

void expect_rejected(const PointCloud2& m, const std::string& reason) {
  try {
    xyz_from_pointcloud2(m);
    ADD_FAILURE() << "accepted; expected: " << reason;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

TEST(PointCloud2Xyz, RejectsBadLayoutsNamingTheProblem) {
  const PointCloud2 good = to_pointcloud2(organised_cloud());
  PointCloud2 m = good;
  m.fields.erase(m.fields.begin() + 2);
  expect_rejected(m, "no field 'z'");
  m = good;
  m.fields[0].datatype = PointField::INT16;
  expect_rejected(m, "field 'x' has datatype 3");
  m = good;
  m.fields[1].offset = m.point_step - 2;
  expect_rejected(m, "field 'y' at offset");
  m = good;
  m.fields[2].offset = 0xFFFFFFFFu;  // no overflow past point_step
  expect_rejected(m, "does not fit in point_step");
  m = good;
  m.row_step = m.width * m.point_step - 1;
  expect_rejected(m, "row_step");
  m = good;
  m.data.pop_back();
  expect_rejected(m, "fewer than 2 rows");
  m = good;
  m.height = 0x40000000u;  // claims far more rows than the data holds
  expect_rejected(m, "fewer than");
  m = good;
  m.width = 0;
  expect_rejected(m, "no points");
  m = good;
  m.data.clear();
  expect_rejected(m, "data holds 0 bytes");
}

client::LabelResult result_for(std::size_t points) {
  client::LabelResult r;
  r.class_ids = {1, 4};
  r.class_names = {"plane", "edge/corner"};
  for (std::size_t i = 0; i < points; ++i) {
    r.labels.push_back(i % 3 == 2 ? 0 : (i % 2 ? 4 : 1));
    const float p = i == 2 ? kNaN : 0.1f * float(i);  // point 2 has no descriptor
    r.probabilities.insert(r.probabilities.end(), {p, 1.0f - p});
  }
  r.summary.set_frame_id("camera_depth_optical_frame");
  r.summary.set_stamp_ns(1'700'000'000'123'456'789ull);
  return r;
}

// Every input field other than the replaced `label` keeps its name, offset, type and bytes.
void expect_layout_kept(const PointCloud2& in, const PointCloud2& out) {
  EXPECT_EQ(out.width, in.width);
  EXPECT_EQ(out.height, in.height);
  EXPECT_EQ(out.is_bigendian, in.is_bigendian);
  EXPECT_EQ(out.is_dense, in.is_dense);
  EXPECT_EQ(out.row_step, out.width * out.point_step);
  EXPECT_EQ(out.data.size(), std::size_t(out.row_step) * out.height);
  for (const PointField& f : in.fields) {
    if (f.name == "label") continue;
    const PointField& o = field_named(out, f.name);
    EXPECT_EQ(o.offset, f.offset);
    EXPECT_EQ(o.datatype, f.datatype);
    EXPECT_EQ(o.count, f.count);
  }
  for (std::size_t i = 0; i < std::size_t(in.width) * in.height; ++i)
    EXPECT_EQ(std::memcmp(point_bytes(out, i), point_bytes(in, i), in.point_step), 0) << i;
}

TEST(LabeledPointCloud2, KeepsTheInputLayoutAndAppendsLabelConfidenceAndProbabilities) {
  for (const MessageLayout& layout :
       {MessageLayout{}, layout_of(false, true, 0), layout_of(true, false, 7)}) {
    const PointCloud2 in = to_pointcloud2(organised_cloud(), layout);
    const client::LabelResult r = result_for(6);
    const PointCloud2 out = labeled_pointcloud2(in, r, roscommon::LabeledFields{true, true});
    expect_layout_kept(in, out);
    const PointField& label = field_named(out, "label");
    EXPECT_EQ(label.datatype, PointField::UINT32);
    EXPECT_EQ(label.offset % 4, 0u);
    EXPECT_GE(label.offset, in.point_step);
    EXPECT_EQ(field_named(out, "confidence").datatype, PointField::FLOAT32);
    ASSERT_TRUE(has_field(out, "prob_plane"));
    ASSERT_TRUE(has_field(out, "prob_edge_corner"));
    for (std::size_t i = 0; i < 6; ++i) {
      EXPECT_EQ(value_of<std::uint32_t>(out, i, "label"), r.labels[i]);
      if (i == 2) {  // no probabilities: NaN, and NaN confidence
        EXPECT_TRUE(std::isnan(value_of<float>(out, i, "prob_plane")));
        EXPECT_TRUE(std::isnan(value_of<float>(out, i, "confidence")));
        continue;
      }
      EXPECT_EQ(value_of<float>(out, i, "prob_plane"), r.probabilities[2 * i]);
      EXPECT_EQ(value_of<float>(out, i, "prob_edge_corner"), r.probabilities[2 * i + 1]);
      EXPECT_EQ(value_of<float>(out, i, "confidence"),
                std::max(r.probabilities[2 * i], r.probabilities[2 * i + 1]));
      EXPECT_EQ(value_of<std::uint32_t>(out, i, "rgba"), organised_cloud().rgba[i]);
    }
  }
}

TEST(LabeledPointCloud2, ReplacesAnInputLabelFieldAndAddsOnlyWhatIsAsked) {
  PointCloud cloud = organised_cloud();
  cloud.labels = {7, 7, 7, 7, 7, 7};  // e.g. ground truth
  const PointCloud2 in = to_pointcloud2(cloud);
  const PointCloud2 out = labeled_pointcloud2(in, result_for(6), {});
  EXPECT_EQ(std::count_if(out.fields.begin(), out.fields.end(),
                          [](const PointField& f) { return f.name == "label"; }),
            1);
  EXPECT_FALSE(has_field(out, "confidence"));
  EXPECT_FALSE(has_field(out, "prob_plane"));
  EXPECT_EQ(out.fields.size(), in.fields.size());  // label replaced, nothing else added
  EXPECT_EQ(out.point_step, in.point_step + 4);
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_EQ(value_of<std::uint32_t>(out, i, "label"), result_for(6).labels[i]);
  expect_layout_kept(in, out);
}

TEST(LabeledPointCloud2, RefusesAResultOfAnotherSize) {
  const PointCloud2 in = to_pointcloud2(organised_cloud());
  EXPECT_THROW(labeled_pointcloud2(in, result_for(5), {}), std::invalid_argument);
  client::LabelResult no_probabilities = result_for(6);
  no_probabilities.probabilities.clear();
  EXPECT_THROW(labeled_pointcloud2(in, no_probabilities, roscommon::LabeledFields{true, false}),
               std::invalid_argument);
}

TEST(LabeledPointCloud2, AppendsObjectAndSegmentIdsAfterTheLabel) {
  PointCloud cloud = organised_cloud();
  cloud.labels = {7, 7, 7, 7, 7, 7};
  const PointCloud2 in = to_pointcloud2(cloud);
  client::LabelResult r = result_for(6);
  r.object_ids = {0, 0, 1, 2, 0xFFFFFFFFu, 1};
  r.segments = {3, 0xFFFFFFFFu, 1, 1, 0, 2};
  roscommon::LabeledFields fields;
  fields.object = fields.segment = fields.confidence = true;
  for (const PointField& f : in.fields)  // an input field of a name the node writes is replaced
    ASSERT_NE(f.name, "object");
  PointCloud2 with_old_object = in;
  with_old_object.fields.push_back(with_old_object.fields.front());
  with_old_object.fields.back().name = "object";
  for (const PointCloud2& input : {in, with_old_object}) {
    const PointCloud2 out = labeled_pointcloud2(input, r, fields);
    expect_layout_kept(in, out);
    const std::uint32_t label = field_named(out, "label").offset;
    EXPECT_EQ(field_named(out, "object").offset, label + 4);
    EXPECT_EQ(field_named(out, "object").datatype, PointField::UINT32);
    EXPECT_EQ(field_named(out, "segment").offset, label + 8);
    EXPECT_EQ(field_named(out, "segment").datatype, PointField::UINT32);
    EXPECT_EQ(field_named(out, "confidence").offset, label + 12);
    EXPECT_EQ(std::count_if(out.fields.begin(), out.fields.end(),
                            [](const PointField& f) { return f.name == "object"; }),
              1);
    for (std::size_t i = 0; i < 6; ++i) {
      EXPECT_EQ(value_of<std::uint32_t>(out, i, "label"), r.labels[i]);
      EXPECT_EQ(value_of<std::uint32_t>(out, i, "object"), r.object_ids[i]);
      EXPECT_EQ(value_of<std::uint32_t>(out, i, "segment"), r.segments[i]);
    }
  }
  client::LabelResult no_ids = result_for(6);
  EXPECT_THROW(labeled_pointcloud2(in, no_ids, roscommon::LabeledFields{false, false, true, false}),
               std::invalid_argument);
  EXPECT_THROW(labeled_pointcloud2(in, no_ids, roscommon::LabeledFields{false, false, false, true}),
               std::invalid_argument);
}

TEST(LabeledPointCloud2, TheHeaderIsTheEchoedFrameAndStampElseTheInputs) {
  PointCloud2 in = to_pointcloud2(organised_cloud());
  in.header.frame_id = "sent_frame";
  in.header.stamp = ros::Time(12, 34);
  in.header.seq = 9;
  const PointCloud2 out = labeled_pointcloud2(in, result_for(6), {});
  EXPECT_EQ(out.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(out.header.stamp.toNSec(), 1'700'000'000'123'456'789ull);
  EXPECT_EQ(out.header.seq, 9u);
  const std_msgs::Header old_server = rosnode::echoed_header(in.header, v1::LabelSummary());
  EXPECT_EQ(old_server.frame_id, "sent_frame");
  EXPECT_EQ(old_server.stamp, ros::Time(12, 34));
}

TEST(LabeledPointCloud2, ProbabilityFieldNames) {
  EXPECT_EQ(roscommon::probability_field_name("plane", 1), "prob_plane");
  EXPECT_EQ(roscommon::probability_field_name("edge/corner 2", 4), "prob_edge_corner_2");
  EXPECT_EQ(roscommon::probability_field_name("", 9), "prob_9");
}

TEST(SummaryJson, CarriesTheProtoFieldNamesFrameAndStamp) {
  v1::LabelSummary summary = result_for(1).summary;
  summary.set_model("tabletop-kinect");
  summary.add_class_counts()->set_name("plane");
  const auto json = nlohmann::json::parse(roscommon::summary_json(summary));
  EXPECT_EQ(json.at("frame_id"), "camera_depth_optical_frame");
  EXPECT_EQ(json.at("stamp_ns"), "1700000000123456789");  // 64-bit integers as strings
  EXPECT_EQ(json.at("model"), "tabletop-kinect");
  EXPECT_EQ(json.at("class_counts").at(0).at("name"), "plane");
  EXPECT_EQ(json.at("scan_id"), "");  // every field present
}

TEST(NodeParameters, ObjectsAndPrimitivesGoIntoTheLabelOptions) {
  roscommon::NodeParameters parameters;
  EXPECT_FALSE(roscommon::label_options(parameters).objects);
  EXPECT_FALSE(roscommon::label_options(parameters).primitives);
  parameters.tabletop_only = parameters.objects = parameters.primitives = true;
  const auto options = roscommon::label_options(parameters);
  EXPECT_TRUE(options.tabletop_only);
  EXPECT_TRUE(options.objects);
  EXPECT_TRUE(options.primitives);
}

TEST(NodeParameters, EveryPointGoesIntoTheLabelOptions) {
  roscommon::NodeParameters parameters;
  EXPECT_FALSE(roscommon::label_options(parameters).every_point);  // the service's cascade
  parameters.every_point = true;
  EXPECT_TRUE(roscommon::label_options(parameters).every_point);
}

// The start-up line names every labeling setting with its value, so a ~tabletop_only the
// parameter server kept from an earlier run is seen at once.
TEST(NodeParameters, TheStartUpLineNamesEverySetting) {
  roscommon::NodeParameters parameters;
  std::string text = roscommon::settings_text(parameters);
  for (const char* part :
       {"tabletop_only false", "every_point false", "voxel_size the model's",
        "viewpoint the frame's origin", "objects false", "primitives false", "confidence false",
        "probabilities false", "model (the one whose domain fits each cloud)"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " in: " << text;
  parameters.model = "tabletop-kinect";
  parameters.tabletop_only = true;
  parameters.voxel_size = 0.007;
  parameters.viewpoint = std::array<double, 3>{0.0, 0.0, 1.5};
  text = roscommon::settings_text(parameters);
  for (const char* part :
       {"model tabletop-kinect", "tabletop_only true", "voxel_size 0.007 m", "viewpoint 0,0,1.5"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " in: " << text;
}

// A driver publishing millimetres: units scales what the service gets; anything but m, cm and
// mm is refused at start-up, naming the parameter.
TEST(NodeParameters, UnitsScaleTheRequestAndOnlyMCmMmAreAccepted) {
  roscommon::NodeParameters parameters;
  EXPECT_EQ(roscommon::label_options(parameters).metres_per_unit, 1.0f);
  EXPECT_NE(roscommon::settings_text(parameters).find("units m"), std::string::npos);
  parameters.units = "mm";
  roscommon::check_parameters(parameters, "~");
  EXPECT_EQ(roscommon::label_options(parameters).metres_per_unit, 0.001f);
  parameters.units = "cm";
  EXPECT_EQ(roscommon::label_options(parameters).metres_per_unit, 0.01f);
  parameters.units = "inch";
  try {
    roscommon::check_parameters(parameters, "~");
    ADD_FAILURE() << "units inch accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("~units"), std::string::npos) << e.what();
  }
}

TEST(NodeParameters, TheViewpointGoesIntoTheLabelOptionsOnlyWhenSet) {
  roscommon::NodeParameters parameters;
  EXPECT_FALSE(roscommon::label_options(parameters).viewpoint.has_value());  // the frame's origin
  parameters.viewpoint = std::array<double, 3>{0.5, -1.25, 2.0};
  const auto options = roscommon::label_options(parameters);
  ASSERT_TRUE(options.viewpoint.has_value());
  EXPECT_EQ(*options.viewpoint, Vec3f(0.5f, -1.25f, 2.0f));
}

}  // namespace
}  // namespace primlabel::rostest
