// ROS adapter of the drift monitor (nodelet ladar_perception/DriftMonitor), for 3D sensors
// (PointCloud2: a lidar, a stereo camera): keeps a sliding window of the reference and target scans (one every ~scan_interval seconds of their stamps,
// thinned, with the vehicle pose odom -> base_link from tf2), and every ~check_interval seconds
// of scan time re-estimates the target's extrinsic against the reference
// (calibration::DriftMonitor) and compares it with the configured one, base_frame -> target frame
// in tf (the URDF's or the static transform the vehicle runs with).
//
// Publishes ~estimate (geometry_msgs/TransformStamped, the re-estimate) after each check and a
// /diagnostics status "drift monitor": OK, WARN or ERROR with the offset per DOF and its
// standard deviation. Checks are driven by the scans' stamps, so a bag played at any rate gives
// the same checks. They run on the adapter's own thread: the subscriber callbacks only convert,
// thin and hand over a scan (a few milliseconds, one scan in scan_interval), so the nodelet
// manager's threads, which the ground nodelets share, never wait on a re-estimate.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/calibration/drift_monitor.h"
#include "ladar_perception/ros/adapter_support.h"
#include "ladar_perception/ros/input_health.h"

namespace ladar_perception {

class DriftMonitorRos {
 public:
  // nh: topics `reference` and `target` (remap them); private_nh: parameters, ~estimate.
  DriftMonitorRos(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~DriftMonitorRos();

 private:
  struct Pending {
    bool target;
    std::string frame;
    ros::Time stamp;
    calibration::PointVector points;  // thinned, sensor frame
  };

  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg, bool target);
  // True when a scan at `stamp` is due (one per scan_interval per sensor).
  bool due(bool target, const ros::Time& stamp);
  void handOver(bool target, const std::string& frame, const ros::Time& stamp);
  void worker();
  // Moves the pending scans whose vehicle pose tf has into the monitor (creating it once both
  // extrinsics are in tf). Called on the worker thread.
  void feed();
  void check();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_, private_nh_;
  ros::Subscriber subscribers_[2];
  ros::Publisher estimate_pub_;
  InputHealth health_;
  std::unique_ptr<AdapterDiagnostics> diagnostics_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  // Parameters.
  std::string odom_frame_, base_frame_, frames_[2];
  double scan_interval_ = 2.0, check_interval_ = 4.0, voxel_ = 0.1;
  double min_range_ = 0.5, max_range_ = 120.0, tf_wait_ = 2.0;
  int worker_nice_ = 10;  // the check thread's nice value (0-19)
  calibration::DriftMonitorParams params_;

  // Callback side (short-held).
  std::mutex callback_mutex_;
  calibration::PointVector work_points_, thinned_;
  calibration::VoxelThinner thinner_;
  double last_taken_[2] = {-1e300, -1e300};

  // Hand-over between the callbacks and the worker.
  std::mutex pending_mutex_;
  std::condition_variable wake_;
  std::deque<Pending> pending_;
  bool stop_ = false;
  std::thread thread_;

  // Worker side; the status is read by the diagnostics under status_mutex_.
  std::unique_ptr<calibration::DriftMonitor> monitor_;
  double next_check_ = -1;  // the scan time of the next check [s]; < 0 before the first scan
  bool check_due_ = false;
  double due_stamp_ = 0;
  mutable std::mutex status_mutex_;
  calibration::DriftEstimate last_;
  bool have_estimate_ = false;
  int checks_ = 0, warn_checks_ = 0, error_checks_ = 0;
  std::string state_ = "waiting for scans and the extrinsics in tf";
  std::string config_error_;  // an unsupported input type: the status is ERROR
};

}  // namespace ladar_perception
