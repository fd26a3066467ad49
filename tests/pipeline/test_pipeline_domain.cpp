// The point spacing a model was trained for, and the warning for clouds far outside it.
#include <gtest/gtest.h>

#include <cmath>

#include "primlabel/geometry/point_spacing.hpp"
#include "primlabel/pipeline/domain.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "random_label_model.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

TEST(PointSpacing, IsTheMedianNearestDistanceAndSkipsCoincidentCopies) {
  PointCloud grid = test::plane_grid(0.0f, 0.0f, 0.1f, 0.002f);
  const NeighborSearch search(grid.xyz);
  EXPECT_NEAR(median_point_spacing(grid.xyz, search), 0.002f, 1e-5f);

  // Every point twice, and a NaN: the copies are not a spacing of 0.
  PointCloud doubled = grid;
  doubled.xyz.insert(doubled.xyz.end(), grid.xyz.begin(), grid.xyz.end());
  doubled.xyz.push_back(Vec3f::Constant(std::nanf("")));
  const NeighborSearch doubled_search(doubled.xyz);
  EXPECT_NEAR(median_point_spacing(doubled.xyz, doubled_search), 0.002f, 1e-5f);

  // Ten times apart, ten times the spacing (and a tilted plane does not change it).
  PointCloud sparse = test::plane_grid(0.3f, -0.2f, 1.0f, 0.02f);
  const NeighborSearch sparse_search(sparse.xyz);
  EXPECT_NEAR(median_point_spacing(sparse.xyz, sparse_search), 0.02f * std::sqrt(1.0f + 0.09f),
              2e-3f);

  const std::vector<Vec3f> empty, one{Vec3f(1, 2, 3)};
  EXPECT_TRUE(std::isnan(median_point_spacing(empty, NeighborSearch(empty))));
  EXPECT_TRUE(std::isnan(median_point_spacing(one, NeighborSearch(one))));
}

TEST(DomainWarning, OnlyForCloudsMoreThanTwiceOutsideTheTrainedRange) {
  TrainingSummary trained;
  trained.point_spacing_min = 0.001f;
  trained.point_spacing_max = 0.003f;
  EXPECT_EQ(pipeline::spacing_warning(trained, 0.002f), "");
  EXPECT_EQ(pipeline::spacing_warning(trained, 0.0006f), "");  // within 2x below
  EXPECT_EQ(pipeline::spacing_warning(trained, 0.0059f), "");  // within 2x above
  const std::string sparser = pipeline::spacing_warning(trained, 0.008f);
  EXPECT_NE(sparser.find("8.00 mm"), std::string::npos) << sparser;
  EXPECT_NE(sparser.find("sparser"), std::string::npos) << sparser;
  EXPECT_NE(sparser.find("1.00-3.00 mm"), std::string::npos) << sparser;
  // Which spacing: the described one (after the model's voxels), not the acquired one the model
  // choice compares, so the two messages' ranges cannot be read as one.
  EXPECT_NE(sparser.find("as described (after any voxel filter)"), std::string::npos) << sparser;
  EXPECT_NE(pipeline::spacing_warning(trained, 0.0004f).find("denser"), std::string::npos);
  // Nothing to compare: no warning rather than a false one.
  EXPECT_EQ(pipeline::spacing_warning(trained, std::nanf("")), "");
  EXPECT_EQ(pipeline::spacing_warning(TrainingSummary{}, 0.5f), "");
}

TEST(DomainWarning, NoiseOnlyWhenMoreThanTwiceTheNoisiestTrainingScenes) {
  TrainingSummary trained;
  trained.surface_variation_max = 0.002f;
  EXPECT_EQ(pipeline::noise_warning(trained, 0.0001f), "");  // cleaner passes
  EXPECT_EQ(pipeline::noise_warning(trained, 0.0079f), "");  // under twice the noise
  const std::string noisy = pipeline::noise_warning(trained, 0.018f);
  EXPECT_NE(noisy.find("9.0x"), std::string::npos) << noisy;
  EXPECT_NE(noisy.find("3.0x its range noise"), std::string::npos) << noisy;
  EXPECT_EQ(pipeline::noise_warning(TrainingSummary{}, 0.5f), "");
  EXPECT_EQ(pipeline::noise_warning(trained, std::nanf("")), "");

  trained.point_spacing_min = 0.001f, trained.point_spacing_max = 0.002f;
  EXPECT_EQ(pipeline::domain_warning(trained, 0.0015f, 0.001f), "");
  EXPECT_EQ(pipeline::domain_warning(trained, 0.0015f, 0.018f), noisy);
  const std::string both = pipeline::domain_warning(trained, 0.01f, 0.018f);
  EXPECT_EQ(both, pipeline::spacing_warning(trained, 0.01f) + "; " + noisy);
}

// A depth camera's frame at 1 m (spacing 1.5 mm) written in other units.
PointCloud frame_in_units(float scale) {
  PointCloud cloud = test::plane_grid(0.0f, 0.0f, 0.2f, 0.0015f);
  for (Vec3f& p : cloud.xyz) p *= scale;
  cloud.viewpoint.origin = Vec3f(0.0f, 0.0f, 1.0f) * scale;
  return cloud;
}

TEST(UnitsHint, NamesMillimetresAndCentimetresOnlyWhenScalingFitsTheModel) {
  TrainingSummary kinect;
  kinect.acquired_spacing_min = 0.00135f, kinect.acquired_spacing_max = 0.00203f;
  const std::string mm = pipeline::units_hint(kinect, frame_in_units(1000.0f));
  EXPECT_NE(mm.find("looks like millimetres"), std::string::npos) << mm;
  EXPECT_NE(mm.find("--units mm"), std::string::npos) << mm;
  const std::string cm = pipeline::units_hint(kinect, frame_in_units(100.0f));
  EXPECT_NE(cm.find("looks like centimetres"), std::string::npos) << cm;
  EXPECT_NE(cm.find("scale it by 0.01"), std::string::npos) << cm;
  EXPECT_EQ(pipeline::units_hint(kinect, frame_in_units(1.0f)), "");
  // A sparse scan in metres whose spacing alone would fit at 0.001: 1.5 m apart, 50 m away. Its
  // range in millimetres (5 cm) is no table top's: no hint.
  PointCloud far_scan = test::plane_grid(0.0f, 0.0f, 30.0f, 1.5f);
  far_scan.viewpoint.origin = Vec3f(0.0f, 0.0f, 50.0f);
  EXPECT_EQ(pipeline::units_hint(kinect, far_scan), "");
  // Nothing recorded, nothing to say.
  EXPECT_EQ(pipeline::units_hint(TrainingSummary{}, frame_in_units(1000.0f)), "");
}

// Through label_cloud: a Kinect model given a frame in millimetres labels nothing, counts every
// point isolated, and its warning opens with how to fix it. In metres: neither.
TEST(UnitsHint, LabelCloudSaysWhenEveryPointIsLostToTheUnits) {
  LabelModel model = testing::random_label_model();
  model.features.voxel_size = 0.007f;
  model.training.point_spacing_min = 0.0042f, model.training.point_spacing_max = 0.005f;
  model.training.acquired_spacing_min = 0.00135f, model.training.acquired_spacing_max = 0.00203f;
  PointCloud millimetres = frame_in_units(1000.0f);
  const pipeline::LabelingResult lost = pipeline::label_cloud(model, millimetres);
  EXPECT_EQ(lost.isolated_points, millimetres.size());
  EXPECT_EQ(lost.domain_warning.rfind("the cloud looks like millimetres", 0), 0u)
      << lost.domain_warning;
  PointCloud metres = frame_in_units(1.0f);
  const pipeline::LabelingResult fine = pipeline::label_cloud(model, metres);
  EXPECT_EQ(fine.isolated_points, 0u);
  EXPECT_EQ(fine.domain_warning.find("looks like"), std::string::npos) << fine.domain_warning;
}

TEST(SurfaceVariation, IsTheMedianOfTheFiniteValues) {
  EXPECT_FLOAT_EQ(median_surface_variation({0.1f, std::nanf(""), 0.3f, 0.2f}), 0.2f);
  EXPECT_TRUE(std::isnan(median_surface_variation({})));
  EXPECT_TRUE(std::isnan(median_surface_variation({std::nanf("")})));
}

}  // namespace
}  // namespace primlabel
