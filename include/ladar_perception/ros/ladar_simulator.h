// ROS adapter of the LadarSimulator nodelet: publishes the simulated vehicle live (the same
// topics as a ladar_simulate bag), so a launch file runs the whole pipeline with no bag.
//
// Private parameters:
//   world (string, "urban")          standard world, or
//   world_image / class_image (string), metres_per_pixel (0.1), height_scale (2.0)
//   seed (int, 1)
//   sensors_file (string, "")        sensor rig YAML; empty: the thesis vehicle (config/sensors.yaml)
//   noise_profile (string, "")       table4.1 | datasheet | none overrides the rig's noise
//   trajectory_file (string, "")     waypoints YAML; empty: the world's standard drive
//   random_poses (int, 0)            > 0: the thesis experiment's random poses instead,
//   pose_hold (double, 1.0)          each held this many seconds
//   loop (bool, true)                restart the drive at its end
//   real_time_factor (double, 1.0)   simulated seconds per wall second
//   publish_clock (bool, false)      publish /clock from simulated time (for use_sim_time
//                                    pipelines); otherwise stamps are ros::Time::now() at start
//                                    plus simulated time
//   publish_truth (bool, true)       the *_truth topics
//   motion_distortion (bool, false)
//   tf_rate (double, 50.0)           odom -> base_link rate
// The true extrinsics are set as the private parameter `true_extrinsics` (YAML text).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {

class LadarSimulatorRos {
 public:
  LadarSimulatorRos(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& name);
  ~LadarSimulatorRos();

  bool ok() const { return ok_; }

 private:
  bool configure(std::string* error);
  void onTimer(const ros::WallTimerEvent& event);
  void step(double now_sim);
  ros::Time stampAt(double t) const;
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  bool ok_ = false;
  std::string error_;

  sim::World world_;
  sim::SensorRig rig_;
  sim::VehicleMotion motion_;
  std::unique_ptr<sim::RigSimulator> simulator_;
  uint32_t seed_ = 1;

  double real_time_factor_ = 1.0;
  double tf_rate_ = 50.0;
  bool publish_clock_ = false;
  bool publish_truth_ = true;

  std::vector<ros::Publisher> data_pubs_, truth_pubs_;
  ros::Publisher clock_pub_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_;
  diagnostic_updater::Updater diagnostics_;

  ros::WallTimer timer_;
  ros::WallTime wall_start_;
  ros::Time stamp_origin_;
  double simulated_ = 0.0;   // simulated time done so far
  uint64_t tf_index_ = 0;
  std::vector<sim::SensorFiring> firings_;
  sim::SensorOutput output_;
  std::size_t published_scans_ = 0;
  double lag_ = 0.0;
  std::size_t skipped_ = 0;
};

}  // namespace ladar_perception
