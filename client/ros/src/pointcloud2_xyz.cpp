#include "primlabel/ros/pointcloud2_message.hpp"

namespace primlabel::rosnode {

roscommon::XyzLayout xyz_layout(const sensor_msgs::PointCloud2& cloud) {
  return roscommon::xyz_layout(view_of(cloud), cloud.data.size());
}

PointCloud xyz_from_pointcloud2(const sensor_msgs::PointCloud2& cloud) {
  return roscommon::xyz_from_pointcloud2(view_of(cloud));
}

}  // namespace primlabel::rosnode
