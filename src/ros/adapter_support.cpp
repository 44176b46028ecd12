#include "ladar_perception/ros/adapter_support.h"

namespace ladar_perception {

AdapterDiagnostics::AdapterDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh,
                                       const std::string& name, const std::string& task_name,
                                       double expected_rate_min, double expected_rate_max,
                                       Task task)
    : updater_(nh, private_nh),
      rate_min_(expected_rate_min),
      rate_max_(expected_rate_max),
      task_(std::move(task)) {
  updater_.setHardwareID("none");
  if (rate_max_ > 0) {
    rate_.reset(new diagnostic_updater::FrequencyStatus(
        diagnostic_updater::FrequencyStatusParam(&rate_min_, &rate_max_, 0.1, 10)));
    updater_.add(*rate_);
  }
  updater_.add(task_name, [this](diagnostic_updater::DiagnosticStatusWrapper& s) { task_(s); });
  // A wall-clock timer: on a played bag (use_sim_time) a timer on ROS time fires only as
  // bag time passes, so a bag shorter than a second never published a processing time.
  timer_ = private_nh.createWallTimer(ros::WallDuration(1.0), [this, name](const ros::WallTimerEvent&) {
    try {
      updater_.force_update();
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(10.0, "%s: diagnostics update failed: %s", name.c_str(), e.what());
    }
  });
}

}  // namespace ladar_perception
