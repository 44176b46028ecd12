// Messages of the ladar simulator (ROS side only: the scans come from the core's RigSimulator)
// and the rosbag writer behind `ladar_simulate`.
//
// Topics per sensor (names from the rig): `topic` carries the data (PointCloud2 in the velodyne
// driver's XYZIRT layout, sensor_msgs/LaserScan for a SICK, PointCloud2 x,y,z for stereo), and
// `truth_topic` a PointCloud2 with one uint8 field `class` (sim::SurfaceClass) per point of the
// data in the same order (per beam of a LaserScan, 255 = no return). /tf carries odom ->
// base_link, /tf_static base_link -> every sensor.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/sim/sensor_rig.h"

namespace ladar_perception {

// A data cloud of the simulator, stamped and framed (built with toMessage()).
sensor_msgs::PointCloud2Ptr simCloudMessage(const PackedCloud& cloud, const std::string& frame_id,
                                            const ros::Time& stamp);
// The ground truth: one uint8 `class` per point (or beam).
sensor_msgs::PointCloud2Ptr simTruthMessage(const std::vector<uint8_t>& truth,
                                            const std::string& frame_id, const ros::Time& stamp);
sensor_msgs::LaserScanPtr simLaserScanMessage(const sim::SimulatedLaserScan& scan,
                                              const std::string& frame_id, const ros::Time& stamp);
geometry_msgs::TransformStamped simTransform(const Eigen::Isometry3d& pose,
                                             const std::string& parent, const std::string& child,
                                             const ros::Time& stamp);
// base_link -> each sensor of the rig.
tf2_msgs::TFMessage simStaticTransforms(const sim::SensorRig& rig, const ros::Time& stamp);

// What one firing publishes. Exactly one of cloud / scan is set.
struct FiringMessages {
  sensor_msgs::PointCloud2Ptr cloud;
  sensor_msgs::LaserScanPtr scan;
  sensor_msgs::PointCloud2Ptr truth;  // null when truth is off
};
void simFiringMessages(const sim::SensorMount& mount, const sim::SensorOutput& output,
                       const ros::Time& stamp, bool with_truth, FiringMessages* out);

struct SimulationBagOptions {
  std::string path;                   // the bag to write
  double duration = 0.0;              // simulated seconds, > 0
  ros::Time start = ros::Time(1700000000, 0);  // stamp of simulation time 0
  double tf_rate = 50.0;              // odom -> base_link messages per second
  bool truth = true;                  // write the truth topics
  std::string compression = "none";   // none, lz4, bz2
};

struct SimulationBagSummary {
  std::map<std::string, std::size_t> messages;  // per topic
  std::size_t velodyne_points = 0;               // summed over revolutions
};

// Simulates [0, duration) of the rig and writes every message to a bag in time order.
// Returns false with a reason (bag cannot be opened, bad options); never throws.
bool writeSimulationBag(const sim::RigSimulator& simulator, const SimulationBagOptions& options,
                        SimulationBagSummary* summary, std::string* error);

}  // namespace ladar_perception
