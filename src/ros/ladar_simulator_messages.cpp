#include "ladar_perception/ros/ladar_simulator_messages.h"

#include <algorithm>
#include <cmath>

#include <boost/make_shared.hpp>
#include <rosbag/bag.h>
#include <sensor_msgs/PointField.h>

#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

sensor_msgs::PointCloud2Ptr simCloudMessage(const PackedCloud& cloud, const std::string& frame_id,
                                            const ros::Time& stamp) {
  sensor_msgs::PointCloud2Ptr msg = toMessage(cloud);
  msg->header.frame_id = frame_id;
  msg->header.stamp = stamp;
  msg->is_dense = true;  // returns only: every point is finite
  return msg;
}

sensor_msgs::PointCloud2Ptr simTruthMessage(const std::vector<uint8_t>& truth,
                                            const std::string& frame_id, const ros::Time& stamp) {
  sensor_msgs::PointCloud2Ptr msg(new sensor_msgs::PointCloud2);
  msg->header.frame_id = frame_id;
  msg->header.stamp = stamp;
  sensor_msgs::PointField f;
  f.name = "class";
  f.offset = 0;
  f.datatype = sensor_msgs::PointField::UINT8;
  f.count = 1;
  msg->fields.push_back(f);
  msg->height = 1;
  msg->width = static_cast<uint32_t>(truth.size());
  msg->point_step = 1;
  msg->row_step = msg->width;
  msg->is_bigendian = false;
  msg->is_dense = true;
  msg->data = truth;
  return msg;
}

sensor_msgs::LaserScanPtr simLaserScanMessage(const sim::SimulatedLaserScan& scan,
                                              const std::string& frame_id, const ros::Time& stamp) {
  sensor_msgs::LaserScanPtr msg(new sensor_msgs::LaserScan);
  msg->header.frame_id = frame_id;
  msg->header.stamp = stamp;
  msg->angle_min = scan.angle_min;
  msg->angle_max = scan.angle_max;
  msg->angle_increment = scan.angle_increment;
  msg->time_increment = scan.time_increment;
  msg->scan_time = scan.scan_time;
  msg->range_min = scan.range_min;
  msg->range_max = scan.range_max;
  msg->ranges = scan.ranges;
  msg->intensities = scan.intensities;
  return msg;
}

geometry_msgs::TransformStamped simTransform(const Eigen::Isometry3d& pose,
                                             const std::string& parent, const std::string& child,
                                             const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.header.stamp = stamp;
  t.child_frame_id = child;
  t.transform.translation.x = pose.translation().x();
  t.transform.translation.y = pose.translation().y();
  t.transform.translation.z = pose.translation().z();
  const Eigen::Quaterniond q(pose.linear());
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

tf2_msgs::TFMessage simStaticTransforms(const sim::SensorRig& rig, const ros::Time& stamp) {
  tf2_msgs::TFMessage msg;
  for (const sim::SensorMount& s : rig.sensors) {
    msg.transforms.push_back(simTransform(s.base_to_sensor, rig.base_frame, s.frame_id, stamp));
  }
  return msg;
}

void simFiringMessages(const sim::SensorMount& mount, const sim::SensorOutput& output,
                       const ros::Time& stamp, bool with_truth, FiringMessages* out) {
  out->cloud.reset();
  out->scan.reset();
  out->truth.reset();
  if (mount.kind == sim::SensorKind::kSick) {
    out->scan = simLaserScanMessage(output.laser, mount.frame_id, stamp);
    if (with_truth) out->truth = simTruthMessage(output.laser.beam_truth, mount.frame_id, stamp);
  } else {
    out->cloud = simCloudMessage(output.scan.cloud, mount.frame_id, stamp);
    if (with_truth) out->truth = simTruthMessage(output.scan.truth, mount.frame_id, stamp);
  }
}

namespace {

ros::Time stampAt(const ros::Time& start, double t) { return start + ros::Duration(t); }

}  // namespace

bool writeSimulationBag(const sim::RigSimulator& simulator, const SimulationBagOptions& options,
                        SimulationBagSummary* summary, std::string* error) {
  if (!(options.duration > 0.0) || !std::isfinite(options.duration)) {
    if (error) *error = "simulation duration must be positive";
    return false;
  }
  if (!(options.tf_rate > 0.0)) {
    if (error) *error = "tf rate must be positive";
    return false;
  }
  SimulationBagSummary local;
  SimulationBagSummary& sum = summary ? *summary : local;
  sum = SimulationBagSummary();
  const sim::SensorRig& rig = simulator.rig();
  try {
    rosbag::Bag bag;
    bag.open(options.path, rosbag::bagmode::Write);
    if (options.compression == "lz4") bag.setCompression(rosbag::compression::LZ4);
    else if (options.compression == "bz2") bag.setCompression(rosbag::compression::BZ2);
    else if (options.compression != "none") {
      if (error) *error = "unknown compression '" + options.compression + "' (none, lz4, bz2)";
      return false;
    }
    // /tf_static once, latched as tf2's static broadcaster would publish it.
    auto latched = boost::make_shared<ros::M_string>();
    // A custom connection header replaces rosbag's own, so it carries the type fields too.
    (*latched)["type"] = ros::message_traits::DataType<tf2_msgs::TFMessage>::value();
    (*latched)["md5sum"] = ros::message_traits::MD5Sum<tf2_msgs::TFMessage>::value();
    (*latched)["message_definition"] = ros::message_traits::Definition<tf2_msgs::TFMessage>::value();
    (*latched)["latching"] = "1";
    (*latched)["callerid"] = "/ladar_simulate";
    bag.write("/tf_static", options.start, simStaticTransforms(rig, options.start), latched);
    ++sum.messages["/tf_static"];

    auto topicName = [](const std::string& t) { return t.empty() || t[0] == '/' ? t : "/" + t; };
    std::vector<sim::SensorFiring> firings;
    sim::SensorOutput output;
    FiringMessages msgs;
    uint64_t tf_index = 0;
    // One simulated second at a time: tf ticks and firings merged in time order.
    for (double chunk = 0.0; chunk < options.duration; chunk += 1.0) {
      const double chunk_end = std::min(chunk + 1.0, options.duration);
      firings.clear();
      simulator.firings(chunk, chunk_end, &firings);
      std::size_t next = 0;
      for (;;) {
        const double tf_time = static_cast<double>(tf_index) / options.tf_rate;
        const bool tf_due = tf_time < chunk_end;
        const bool firing_due = next < firings.size();
        if (!tf_due && !firing_due) break;
        if (tf_due && (!firing_due || tf_time <= firings[next].time)) {
          const ros::Time stamp = stampAt(options.start, tf_time);
          tf2_msgs::TFMessage tf;
          tf.transforms.push_back(
              simTransform(simulator.basePose(tf_time), rig.odom_frame, rig.base_frame, stamp));
          bag.write("/tf", stamp, tf);
          ++sum.messages["/tf"];
          ++tf_index;
          continue;
        }
        const sim::SensorFiring& f = firings[next++];
        const sim::SensorMount& mount = rig.sensors[f.sensor];
        const ros::Time stamp = stampAt(options.start, f.time);
        simulator.simulate(f, &output);
        simFiringMessages(mount, output, stamp, options.truth, &msgs);
        const std::string topic = topicName(mount.topic);
        if (msgs.scan) bag.write(topic, stamp, msgs.scan);
        if (msgs.cloud) bag.write(topic, stamp, msgs.cloud);
        ++sum.messages[topic];
        if (msgs.truth) {
          bag.write(topicName(mount.truth_topic), stamp, msgs.truth);
          ++sum.messages[topicName(mount.truth_topic)];
        }
        if (mount.kind == sim::SensorKind::kVelodyne) sum.velodyne_points += output.scan.truth.size();
      }
    }
    bag.close();
  } catch (const std::exception& e) {
    if (error) *error = std::string("writing ") + options.path + ": " + e.what();
    return false;
  }
  return true;
}

}  // namespace ladar_perception
