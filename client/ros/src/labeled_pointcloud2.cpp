#include "primlabel/ros/pointcloud2_message.hpp"

namespace primlabel::rosnode {

std_msgs::Header echoed_header(const std_msgs::Header& input, const v1::LabelSummary& summary) {
  std_msgs::Header header = input;
  if (summary.frame_id().empty() && summary.stamp_ns() == 0) return header;
  header.frame_id = summary.frame_id();
  header.stamp.fromNSec(summary.stamp_ns());
  return header;
}

sensor_msgs::PointCloud2 labeled_pointcloud2(const sensor_msgs::PointCloud2& input,
                                             const client::LabelResult& result,
                                             const roscommon::LabeledFields& fields) {
  return to_message(roscommon::labeled_pointcloud2(view_of(input), result, fields),
                    echoed_header(input.header, result.summary));
}

}  // namespace primlabel::rosnode
