// PCL reads what primlabel writes: a labeled, organised, binary_compressed PCD with primlabel's
// header tags loads in PCL 1.13's own reader (primlabel-pcl-resave, built where PCL is found)
// with every point's coordinates, label and the organised shape intact.

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"

namespace primlabel {
namespace {

TEST(PclInterop, PclReadsALabeledTaggedOrganisedPcd) {
  test::TempDir dir;
  const std::string ours = dir.file("frame.pcd"), resaved = dir.file("resaved.pcd");
  auto r = test::run_command(test::binary("primlabel-synth") + " --sensor kinect --seed 11 -q -o " +
                             ours);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_FALSE(read_cloud_tags(ours).empty());  // the comment lines PCL must skip
  r = test::run_command(test::binary("primlabel-pcl-resave") + " " + ours + " " + resaved);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud a = read_pcd(ours), b = read_pcd(resaved);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(b.width, a.width);
  EXPECT_EQ(b.height, a.height);
  ASSERT_EQ(b.labels.size(), a.labels.size());
  std::size_t finite = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.labels[i], b.labels[i]) << i;
    if (!is_finite(a.xyz[i])) {
      ASSERT_FALSE(is_finite(b.xyz[i])) << i;
      continue;
    }
    ++finite;
    // PCL's ASCII writer prints 8 significant digits.
    ASSERT_LT((a.xyz[i] - b.xyz[i]).norm(), 1e-6f * (1.0f + a.xyz[i].norm())) << i;
  }
  EXPECT_GT(finite, a.size() / 2);
}

}  // namespace
}  // namespace primlabel
