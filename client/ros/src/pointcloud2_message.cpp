#include "primlabel/ros/pointcloud2_message.hpp"

#include <utility>

#include "primlabel/ros_common/pointcloud2_body.hpp"

namespace primlabel::rosnode {

roscommon::PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud) {
  roscommon::PointCloud2View view = roscommon::view_of_body(cloud);
  view.frame_id = cloud.header.frame_id;
  view.stamp_ns = cloud.header.stamp.toNSec();
  return view;
}

sensor_msgs::PointCloud2 to_message(roscommon::PointCloud2Data&& cloud,
                                    const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 m = roscommon::message_body<sensor_msgs::PointCloud2>(std::move(cloud));
  m.header = header;
  return m;
}

}  // namespace primlabel::rosnode
