// The request's options as the pipeline takes them (service/label_options.hpp): every field
// converted in the one place, and pipeline::refusal told in the request's terms.

#include <gtest/gtest.h>

#include <limits>

#include "primlabel/service/label_options.hpp"
#include "random_label_model.hpp"

namespace primlabel::service {
namespace {

TEST(LabelOptions, EveryFieldOfTheRequestReachesThePipeline) {
  v1::ScanHeader header;
  v1::LabelOptions& options = *header.mutable_options();
  options.set_return_descriptors(true);
  options.set_return_probabilities(true);
  options.set_tabletop_only(true);
  options.set_voxel_size(0.01f);
  options.set_normal_radius(0.02f);
  options.set_feature_radius(0.03f);
  options.set_return_primitives(true);
  options.set_return_objects(true);
  options.set_every_point(true);
  header.mutable_layout()->set_normals(true);
  const pipeline::LabelingOptions labeling = labeling_options(header);
  EXPECT_TRUE(labeling.want_descriptors && labeling.want_probabilities && labeling.tabletop_only);
  EXPECT_TRUE(labeling.want_primitives && labeling.want_objects && labeling.use_cloud_normals);
  EXPECT_EQ(labeling.voxel_size, 0.01f);
  EXPECT_EQ(labeling.normal_radius, 0.02f);
  EXPECT_EQ(labeling.feature_radius, 0.03f);
  EXPECT_FALSE(labeling.plane_cascade);  // every_point
  EXPECT_FALSE(refuse_options(labeling));
  const pipeline::LabelingOptions defaults = labeling_options(v1::ScanHeader{});
  EXPECT_FALSE(defaults.want_objects);
  EXPECT_TRUE(defaults.plane_cascade);  // the service cascades unless every_point is asked
}

TEST(LabelOptions, RefusalsNameTheRequestsFieldsAndTheModel) {
  v1::ScanHeader header;
  header.mutable_options()->set_voxel_size(std::numeric_limits<float>::quiet_NaN());
  auto refused = refuse_options(labeling_options(header));
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(refused->message, "options.voxel_size must be finite and >= 0");

  header = {};
  header.mutable_options()->set_return_objects(true);
  refused = refuse_options(labeling_options(header));
  ASSERT_TRUE(refused);
  EXPECT_NE(refused->message.find("options.return_objects needs options.tabletop_only"),
            std::string::npos);

  header = {};
  header.mutable_options()->set_feature_radius(0.05f);
  const pipeline::LabelingOptions overriding = labeling_options(header);
  EXPECT_FALSE(refuse_options(overriding));  // whatever the model: allowed
  ModelEntry entry;
  entry.name = "m";
  entry.version = "3";
  entry.model = std::make_shared<const LabelModel>(testing::random_label_model("m", "3"));
  refused = refuse_options(overriding, entry, /*chosen=*/false);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->message,
            "model 'm' version '3' does not allow radius overrides (options.normal_radius / "
            "feature_radius); name a model that does");
}

}  // namespace
}  // namespace primlabel::service
