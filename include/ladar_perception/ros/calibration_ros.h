// ROS adapter of the calibration (nodelet ladar_perception/Calibration): buffers the reference
// and target sensors' scans with the vehicle pose (odom -> base_link from tf2) at each stamp, and
// serves ~calibrate (srv/Calibrate.srv: the first target against the reference),
// ~calibrate_network (srv/CalibrateNetwork.srv: every target, jointly; calibration/network.h),
// ~reset and ~save (std_srvs/Trigger). One target is subscribed on `target`; several on the
// topics of ~target_topics. The calibration
// itself is one core call (calibration::calibrate) on a worker thread; the services are served
// from the adapter's own callback queue and spinner, so the nodelet's queue never waits on it.
// Progress is published on ~progress (std_msgs/String, one line per iteration) and
// ~progress_estimate (geometry_msgs/TransformStamped, the current estimate).
//
// The vehicle pose is looked up with canTransform/lookupTransform (no waiting) and scans whose
// pose is not yet in the tf buffer wait in the scan buffer (calibration::ScanRing) until a timer
// finds it; a
// tf2_ros::MessageFilter cannot be used because the target sensor's frame is, by definition, not
// (correctly) connected to the tree. Bad input is counted and logged per kind through
// InputHealth and shown on /diagnostics with the buffer fill.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/Calibrate.h"
#include "ladar_perception/CalibrateNetwork.h"
#include "ladar_perception/calibration/calibrator.h"
#include "ladar_perception/calibration/network.h"
#include "ladar_perception/calibration/scan_ring.h"
#include "ladar_perception/ros/adapter_support.h"
#include "ladar_perception/ros/input_health.h"

namespace ladar_perception {

// Message -> points in the sensor frame (no algorithm: the core's readers). False with a reason.
bool calibrationPoints(const sensor_msgs::PointCloud2& msg, double min_range, double max_range,
                       calibration::PointVector* points, std::string* error,
                       CloudError* code = nullptr);
bool calibrationPoints(const sensor_msgs::LaserScan& msg, calibration::PointVector* points,
                       std::string* error);

// A parameter holding x y z roll pitch yaw (numbers, int or double): *out = fallback when unset;
// false when set but not a list of 6 numbers.
bool readPose6(const ros::NodeHandle& nh, const std::string& name,
               const calibration::Pose6& fallback, calibration::Pose6* out);

class CalibrationRos {
 public:
  // nh: topics `reference` and `target` (remap them) or ~target_topics; private_nh: parameters,
  // services, progress topics.
  CalibrationRos(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~CalibrationRos();

  // Scans with a vehicle pose buffered for the reference (false) or the first target (true).
  std::size_t bufferedScans(bool target) const;
  const InputHealth& health() const { return health_; }

 private:
  struct Sensor {
    std::string role;   // "reference", "target" or "target <topic>" (in messages)
    std::string topic;
    std::string type;   // PointCloud2 or LaserScan
    double voxel = 0.1; // each scan thinned to this before buffering [m], 0 = not thinned
    double interval = 0;  // at most one scan buffered per this many seconds [s]
    ros::Time last_kept;  // stamp of the last buffered scan (work_mutex_)
    std::string frame;  // from the messages (or the parameter)
    // The latest scans, thinned, with their vehicle poses once tf has them (bounded; point
    // storage reserved once: buffering allocates nothing and its memory stops growing).
    std::unique_ptr<calibration::ScanRing> ring;
    ros::Subscriber subscriber;
  };

  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg, std::size_t sensor);
  void scanCallback(const sensor_msgs::LaserScanConstPtr& msg, std::size_t sensor);
  // Whether a message is to be buffered, checked before it is converted: false (ignored) when it
  // is not in the sensor's frame (a throttled error) or comes within the sensor's buffer interval
  // of the last kept scan. Called with work_mutex_ held.
  bool admits(std::size_t sensor, const std::string& frame, const ros::Time& stamp);
  // Thins work_points_ and buffers the scan to wait for its vehicle pose; false when the scan has
  // more points than the buffer holds. Called with work_mutex_ held, after admits().
  bool enqueue(std::size_t sensor, const ros::Time& stamp);
  void drainPending(const ros::TimerEvent&);
  bool calibrateService(ladar_perception::Calibrate::Request& req,
                        ladar_perception::Calibrate::Response& res);
  bool calibrateNetworkService(ladar_perception::CalibrateNetwork::Request& req,
                               ladar_perception::CalibrateNetwork::Response& res);
  void runNetwork(const ladar_perception::CalibrateNetwork::Request& req,
                  ladar_perception::CalibrateNetwork::Response& res);
  // The pairwise calibration's parameters from ~ and a request's method and spread; false with
  // a reason.
  bool requestParams(const std::string& method, const std::vector<double>& spread,
                     calibration::CalibrationParams* params, std::string* error) const;
  bool resetService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool saveService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  void runCalibration(const ladar_perception::Calibrate::Request& req,
                      ladar_perception::Calibrate::Response& res);
  // child: the frame whose estimate this is ("" = the first target's).
  bool publishProgress(const calibration::SearchProgress& p, const std::string& child = "");
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  std::string outputPath() const;
  std::string networkOutputPath() const;

  ros::NodeHandle nh_, private_nh_, service_nh_;
  ros::CallbackQueue service_queue_;
  std::unique_ptr<ros::AsyncSpinner> service_spinner_;
  ros::Publisher progress_pub_, progress_estimate_pub_;
  ros::ServiceServer calibrate_srv_, network_srv_, reset_srv_, save_srv_;
  ros::Timer drain_timer_;

  InputHealth health_;
  std::unique_ptr<AdapterDiagnostics> diagnostics_;

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  // Parameters.
  std::string odom_frame_, base_frame_, output_file_, network_output_file_;
  std::vector<double> target_surface_voxels_;  // per target of ~target_topics, 0 = ~surface_voxel
  int buffer_size_ = 50;
  int buffer_points_ = 8000000;
  double buffer_voxel_ = 0.1, min_range_ = 0.5, max_range_ = 120.0, tf_wait_ = 2.0;

  // Conversion and thinning workspace, kept from scan to scan (no per-scan allocation).
  std::mutex work_mutex_;
  calibration::PointVector work_points_, thinned_;
  calibration::VoxelThinner thinner_;

  mutable std::mutex mutex_;  // sensors_, last result
  std::vector<Sensor> sensors_;  // 0 reference, then the targets (fixed after construction)
  bool have_result_ = false;
  calibration::CalibrationResult last_result_;
  std::string last_child_frame_;

  std::atomic<bool> busy_{false};
  std::atomic<bool> shutting_down_{false};
  std::atomic<int> progress_iteration_{0};
};

}  // namespace ladar_perception
