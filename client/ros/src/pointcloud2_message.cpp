#include "primlabel/ros/pointcloud2_message.hpp"

#include <utility>

namespace primlabel::rosnode {

roscommon::PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud) {
  roscommon::PointCloud2View view;
  view.frame_id = cloud.header.frame_id;
  view.stamp_ns = cloud.header.stamp.toNSec();
  view.height = cloud.height;
  view.width = cloud.width;
  for (const sensor_msgs::PointField& f : cloud.fields)
    view.fields.push_back({f.name, f.offset, f.datatype, f.count});
  view.is_bigendian = cloud.is_bigendian;
  view.point_step = cloud.point_step;
  view.row_step = cloud.row_step;
  view.is_dense = cloud.is_dense;
  view.data = cloud.data.data();
  view.data_size = cloud.data.size();
  return view;
}

sensor_msgs::PointCloud2 to_message(roscommon::PointCloud2Data&& cloud,
                                    const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 m;
  m.header = header;
  m.height = cloud.height;
  m.width = cloud.width;
  for (const roscommon::PointFieldInfo& f : cloud.fields) {
    sensor_msgs::PointField field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = f.count;
    m.fields.push_back(field);
  }
  m.is_bigendian = cloud.is_bigendian;
  m.point_step = cloud.point_step;
  m.row_step = cloud.row_step;
  m.is_dense = cloud.is_dense;
  m.data = std::move(cloud.data);
  return m;
}

}  // namespace primlabel::rosnode
