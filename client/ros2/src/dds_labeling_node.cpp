#include "primlabel/ros2/dds_labeling_node.hpp"

#include <exception>

#include "primlabel/ros2/node_log.hpp"
#include "primlabel/ros2/pointcloud2_dds.hpp"
#include "primlabel/ros2/ros2_qos.hpp"
#include "primlabel/ros2/type_hash.hpp"
#include "std_msgs/msg/String.h"

namespace primlabel::ros2node {

namespace {

dds_entity_t topic(dds_entity_t participant, const dds_topic_descriptor_t* type,
                   const std::string& name) {
  return checked(dds_create_topic(participant, type, name.c_str(), nullptr, nullptr),
                 "DDS topic " + name);
}

}  // namespace

DdsLabelingNode::DdsLabelingNode(const Ros2Settings& settings)
    : settings_(settings), labeler_(settings.parameters) {
  const roscommon::NodeParameters& p = settings.parameters;
  const std::string domain = "DDS domain " + std::to_string(settings.domain_id);
  if (!settings.dds_config.empty())
    domain_ = DdsEntity(checked(dds_create_domain(settings.domain_id, settings.dds_config.c_str()),
                                domain + " (configuration from the ROS 2 discovery variables and "
                                         "CYCLONEDDS_URI)"));
  // rmw_cyclonedds names the participant's security enclave in its USER_DATA.
  const Qos participant_qos(dds_create_qos());
  const std::string enclave = "enclave=/;";
  dds_qset_userdata(participant_qos.get(), enclave.data(), enclave.size());
  participant_ =
      DdsEntity(checked(dds_create_participant(settings.domain_id, participant_qos.get(), nullptr),
                        "DDS participant on domain " + std::to_string(settings.domain_id)));
  const std::string input = dds_topic(settings, p.input_topic);
  const std::string output = dds_topic(settings, p.output_topic);
  const std::string summary = dds_topic(settings, p.summary_topic);
  const dds_entity_t input_topic =
      topic(participant_.get(), &sensor_msgs_msg_dds__PointCloud2__desc, input);
  const dds_entity_t output_topic =
      output == input ? input_topic
                      : topic(participant_.get(), &sensor_msgs_msg_dds__PointCloud2__desc, output);
  const dds_entity_t summary_topic =
      topic(participant_.get(), &std_msgs_msg_dds__String__desc, summary);

  const Qos reader_qos = input_reader_qos(settings.input_qos);
  const Qos cloud_qos = output_writer_qos(settings.output_qos);
  const Qos summary_qos = output_writer_qos(settings.summary_qos);
  if (!settings.humble_graph) {  // Iron and later: each endpoint names its type's hash
    set_type_hash(reader_qos.get(), point_cloud2_type_hash());
    set_type_hash(cloud_qos.get(), point_cloud2_type_hash());
    set_type_hash(summary_qos.get(), string_type_hash());
  }
  reader_ = DdsEntity(
      checked(dds_create_reader(participant_.get(), input_topic, reader_qos.get(), nullptr),
              "DDS reader on " + input));
  cloud_writer_ = DdsEntity(
      checked(dds_create_writer(participant_.get(), output_topic, cloud_qos.get(), nullptr),
              "DDS writer on " + output));
  summary_writer_ = DdsEntity(
      checked(dds_create_writer(participant_.get(), summary_topic, summary_qos.get(), nullptr),
              "DDS writer on " + summary));
  waitset_ = DdsEntity(checked(dds_create_waitset(participant_.get()), "DDS waitset"));
  data_available_ = DdsEntity(
      checked(dds_create_readcondition(reader_.get(), DDS_ANY_STATE), "DDS read condition"));
  checked(dds_waitset_attach(waitset_.get(), data_available_.get(), 0), "DDS waitset attach");
  discovery_info_ = std::make_unique<RosDiscoveryInfo>(participant_.get(), settings.humble_graph);
  discovery_info_->announce(settings.node_namespace, settings.node_name, {reader_.get()},
                            {cloud_writer_.get(), summary_writer_.get()});

  // The ROS 2 names, and the DDS topics they are (what a plain DDS tool subscribes to).
  log(Severity::kInfo, settings.node_name,
      "labeling " + input.substr(2) + " (" + qos_text(reader_qos.get()) + ") -> " +
          output.substr(2) + " (summary " + summary.substr(2) + "; DDS topics " + input + ", " +
          output + ", " + summary + ", domain " + std::to_string(settings.domain_id) +
          ") through " + p.server + ": " + roscommon::settings_text(p));
  if (settings.use_sim_time)
    log(Severity::kInfo, settings.node_name,
        "use_sim_time true: the outputs carry their input's stamp, so the node reads no /clock");
}

DdsLabelingNode::~DdsLabelingNode() {
  try {
    if (discovery_info_) discovery_info_->withdraw();
  } catch (const std::exception& e) {
    log(Severity::kWarn, settings_.node_name, e.what());
  }
}

void DdsLabelingNode::run(const std::atomic<bool>& stop, std::chrono::milliseconds poll) {
  while (!stop.load()) {
    const dds_return_t triggered = dds_waitset_wait(
        waitset_.get(), nullptr, 0, DDS_MSECS(static_cast<long long>(poll.count())));
    if (triggered < 0) {
      log(Severity::kError, settings_.node_name,
          std::string("waiting for clouds: ") + dds_strretcode(triggered));
      return;
    }
    if (triggered > 0) take_and_label();
  }
}

void DdsLabelingNode::take_and_label() {
  void* sample = nullptr;
  dds_sample_info_t info;
  const dds_return_t taken = dds_take(reader_.get(), &sample, &info, 1, 1);
  if (taken <= 0) return;
  const LoanedSample loan(reader_.get(), sample);
  if (!info.valid_data) return;  // a writer went away: nothing to label
  label(view_of(loan.as<sensor_msgs_msg_dds__PointCloud2_>()));
}

void DdsLabelingNode::label(const roscommon::PointCloud2View& cloud) {
  const std::string& node = settings_.node_name;
  try {
    roscommon::LabeledCloud labeled = labeler_.label(cloud);
    const auto now = std::chrono::steady_clock::now();
    if (!labeled.domain_warning.empty() &&
        (!warned_domain_ || now - last_domain_warning_ > std::chrono::minutes(1))) {
      warned_domain_ = true;
      last_domain_warning_ = now;
      log(Severity::kWarn, node, labeled.domain_warning);
    }
    if (labeled.model_change) log(Severity::kInfo, node, *labeled.model_change);
    const OutgoingPointCloud2 message(labeled.cloud);
    const dds_return_t cloud_written = dds_write(cloud_writer_.get(), message.message());
    std_msgs_msg_dds__String_ summary{};
    summary.data = labeled.summary_json.data();
    const dds_return_t summary_written = dds_write(summary_writer_.get(), &summary);
    if (cloud_written < 0 || summary_written < 0)
      throw std::runtime_error(std::string("publishing: ") +
                               dds_strretcode(cloud_written < 0 ? cloud_written : summary_written));
    ++labeled_;
  } catch (const std::exception& e) {  // a ClientError's text starts with the status code
    ++failed_;
    const std::uint64_t ns = cloud.stamp_ns;
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%llu.%09llu",
                  static_cast<unsigned long long>(ns / 1'000'000'000),
                  static_cast<unsigned long long>(ns % 1'000'000'000));
    log(Severity::kError, node,
        "cloud of frame '" + cloud.frame_id + "' (stamp " + stamp + ") not labeled: " + e.what());
  }
}

}  // namespace primlabel::ros2node
