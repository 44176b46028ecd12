// ROS adapter of the vertical scan ground extractor: subscribes to a PointCloud2, waits for the
// sensor's tf through a tf2_ros::MessageFilter, runs one core call per scan and publishes
// `ground`, `obstacles` and `classified` as fresh ConstPtr messages (zero-copy to nodelets in
// the same manager). Owns parameters, dynamic_reconfigure and diagnostics; no algorithm here.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/VerticalScanGroundConfig.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/ros/adapter_support.h"
#include "ladar_perception/ros/input_health.h"

namespace ladar_perception {

// Maps the dynamic_reconfigure config to the core's params (one place for the names).
VerticalScanParams toVerticalScanParams(const VerticalScanGroundConfig& config);
// Writes a named method's settings into the config's thresholds.
void loadMethodSettings(const std::string& method, VerticalScanGroundConfig* config);

class VerticalScanGroundRos {
 public:
  // nh: topics (input `points`, outputs `ground`, `obstacles`, `classified`);
  // private_nh: parameters, dynamic_reconfigure, services.
  VerticalScanGroundRos(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~VerticalScanGroundRos();

  // For in-process inspection (tests proving zero-copy): the last messages handled.
  const void* lastInputAddress() const { return last_input_.load(); }
  sensor_msgs::PointCloud2ConstPtr lastClassified() const;
  const InputHealth& health() const { return health_; }

 private:
  void process(const sensor_msgs::PointCloud2ConstPtr& msg);
  bool sensorPose(const sensor_msgs::PointCloud2& msg, SensorPose* pose);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  std::unique_ptr<GroundModel> makeModel(const VerticalScanGroundConfig& config);

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;

  // Publishers first, subscribers last (Noetic's nodelet does not hold callbacks during onInit).
  ros::Publisher ground_pub_;
  ros::Publisher obstacles_pub_;
  ros::Publisher classified_pub_;

  std::unique_ptr<MethodReconfigure<VerticalScanGroundConfig>> reconfigure_;

  // Touched only by the processing callback (serialised by process_mutex_).
  std::mutex process_mutex_;
  std::unique_ptr<GroundModel> model_;
  GroundClassification result_;
  std::string ground_frame_;
  bool use_tf_ = true;
  float sensor_height_ = 1.73f;
  // The sensor (~sensor_model or ~laser_elevations_deg) and, with ~use_tf false, its mount's
  // roll and pitch (~mount_roll_deg, ~mount_pitch_deg).
  LidarModel lidar_;
  float mount_roll_deg_ = 0.f, mount_pitch_deg_ = 0.f;
  std::atomic<const char*> rows_from_{"elevation table"};  // where the last scan's rows came from

  InputHealth health_;
  std::unique_ptr<AdapterDiagnostics> diagnostics_;
  std::unique_ptr<SensorInput<sensor_msgs::PointCloud2>> input_;  // last: built after the rest

  std::atomic<const void*> last_input_{nullptr};
  mutable std::mutex last_mutex_;
  boost::weak_ptr<const sensor_msgs::PointCloud2> last_classified_;
};

}  // namespace ladar_perception
