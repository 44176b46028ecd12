// ROS adapter of the Hough ground fit for a vertically mounted 2D ladar (thesis 3.3.4):
// subscribes to a sensor_msgs/LaserScan, waits for the scan frame's tf through a
// tf2_ros::MessageFilter, runs one core call per scan and publishes `ground`, `obstacles` and
// `classified` (PointCloud2 of the scan's returns, scan frame), `ground_line`
// (visualization_msgs/Marker, ground frame) and `ground_fit` (ladar_perception/HoughGroundFit).
// Owns parameters, dynamic_reconfigure and diagnostics; no algorithm here.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/HoughGroundConfig.h"
#include "ladar_perception/HoughGroundFit.h"
#include "ladar_perception/ground/hough_ground.h"
#include "ladar_perception/ros/adapter_support.h"
#include "ladar_perception/ros/input_health.h"

namespace ladar_perception {

// Maps the dynamic_reconfigure config to the core's params (one place for the names).
HoughGroundParams toHoughGroundParams(const HoughGroundConfig& config);
// Writes a named method's settings ("default" or "thesis") into the config's thresholds.
void loadHoughMethodSettings(const std::string& method, HoughGroundConfig* config);

class HoughGroundRos {
 public:
  // nh: topics (input `scan`; outputs `ground`, `obstacles`, `classified`, `ground_line`,
  // `ground_fit`); private_nh: parameters, dynamic_reconfigure.
  HoughGroundRos(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~HoughGroundRos();

  // For in-process inspection (tests): the last messages handled.
  const void* lastInputAddress() const { return last_input_.load(); }
  sensor_msgs::PointCloud2ConstPtr lastClassified() const;
  const InputHealth& health() const { return health_; }

 private:
  void process(const sensor_msgs::LaserScanConstPtr& msg);
  bool sensorPose(const sensor_msgs::LaserScan& msg, SensorPose* pose);
  void publishLine(const sensor_msgs::LaserScan& msg, const ScanGroundResult& result);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;

  // Publishers first, subscribers last (Noetic's nodelet does not hold callbacks during onInit).
  ros::Publisher ground_pub_;
  ros::Publisher obstacles_pub_;
  ros::Publisher classified_pub_;
  ros::Publisher line_pub_;
  ros::Publisher fit_pub_;

  std::unique_ptr<MethodReconfigure<HoughGroundConfig>> reconfigure_;

  // Touched only by the processing callback (serialised by process_mutex_).
  std::mutex process_mutex_;
  HoughGround hough_;
  ScanGroundResult result_;
  LaserScanProjector cloud_projector_;  // the output clouds' points (cached cos/sin table)
  std::string ground_frame_;
  bool use_tf_ = true;
  float sensor_height_ = 1.0f;
  double mount_roll_ = 1.5707963267948966;
  double mount_pitch_ = 0.0;

  InputHealth health_;
  std::unique_ptr<AdapterDiagnostics> diagnostics_;
  std::unique_ptr<SensorInput<sensor_msgs::LaserScan>> input_;  // built after the rest

  // Last fit, for diagnostics.
  mutable std::mutex fit_mutex_;
  GroundLineFit last_fit_;
  uint64_t scans_without_line_ = 0;

  std::atomic<const void*> last_input_{nullptr};
  mutable std::mutex last_mutex_;
  boost::weak_ptr<const sensor_msgs::PointCloud2> last_classified_;
};

}  // namespace ladar_perception
