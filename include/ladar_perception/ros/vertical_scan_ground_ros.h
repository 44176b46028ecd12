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

#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <dynamic_reconfigure/server.h>
#include <message_filters/subscriber.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/VerticalScanGroundConfig.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/vertical_scan.h"
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
  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void tfFailure(const sensor_msgs::PointCloud2ConstPtr& msg,
                 tf2_ros::filter_failure_reasons::FilterFailureReason reason);
  void process(const sensor_msgs::PointCloud2ConstPtr& msg);
  bool sensorPose(const sensor_msgs::PointCloud2& msg, SensorPose* pose);
  void reconfigure(VerticalScanGroundConfig& config, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  std::unique_ptr<GroundModel> makeModel(const VerticalScanGroundConfig& config);

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;

  // Publishers first, subscribers last (Noetic's nodelet does not hold callbacks during onInit).
  ros::Publisher ground_pub_;
  ros::Publisher obstacles_pub_;
  ros::Publisher classified_pub_;

  std::mutex config_mutex_;
  VerticalScanGroundConfig config_;
  bool config_changed_ = true;
  std::unique_ptr<dynamic_reconfigure::Server<VerticalScanGroundConfig>> reconfigure_server_;
  std::string last_method_;
  std::vector<std::string> explicit_params_;

  // Touched only by the processing callback (serialised by process_mutex_).
  std::mutex process_mutex_;
  std::unique_ptr<GroundModel> model_;
  GroundClassification result_;
  std::string ground_frame_;
  bool use_tf_ = true;
  float sensor_height_ = 1.73f;

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> cloud_sub_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;
  ros::Subscriber direct_sub_;  // used when use_tf is false

  InputHealth health_;
  diagnostic_updater::Updater diagnostics_;
  double expected_rate_min_ = 5.0;
  double expected_rate_max_ = 20.0;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> rate_status_;
  ros::Timer diagnostics_timer_;

  std::atomic<const void*> last_input_{nullptr};
  mutable std::mutex last_mutex_;
  boost::weak_ptr<const sensor_msgs::PointCloud2> last_classified_;
};

}  // namespace ladar_perception
