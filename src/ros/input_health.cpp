#include "ladar_perception/ros/input_health.h"

#include <algorithm>
#include <sstream>

#include <ros/console.h>
#include <tf2_eigen/tf2_eigen.h>

namespace ladar_perception {

bool InputHealth::report(const std::string& kind, uint64_t* suppressed) {
  std::lock_guard<std::mutex> lock(mutex_);
  Kind& k = kinds_[kind];
  const ros::WallTime now = ros::WallTime::now();
  ++k.count;
  k.last_seen = now;
  const bool log = k.count == 1 || (now - k.last_logged).toSec() >= throttle_period_;
  if (log) {
    if (suppressed) *suppressed = k.suppressed;
    k.suppressed = 0;
    k.last_logged = now;
  } else {
    ++k.suppressed;
  }
  return log;
}

void InputHealth::error(const std::string& kind, const std::string& detail) {
  uint64_t suppressed = 0;
  if (!report(kind, &suppressed)) return;
  if (suppressed > 0) {
    ROS_ERROR("%s: %s: %s (%lu more of this kind since the last message)", name_.c_str(),
              kind.c_str(), detail.c_str(), static_cast<unsigned long>(suppressed));
  } else {
    ROS_ERROR("%s: %s: %s", name_.c_str(), kind.c_str(), detail.c_str());
  }
}

void InputHealth::tfFilterDropped(const std::string& target_frame, const std_msgs::Header& header,
                                  tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  uint64_t suppressed = 0;
  if (!dropped("missing tf", &suppressed)) return;
  const char* why = "transform not available in time";
  if (reason == tf2_ros::filter_failure_reasons::OutTheBack) why = "message older than the tf buffer";
  if (reason == tf2_ros::filter_failure_reasons::EmptyFrameID) why = "empty frame_id";
  std::ostringstream s;
  s << name_ << ": message at " << header.stamp << " dropped: no transform " << target_frame
    << " <- '" << header.frame_id << "' (" << why << ")";
  if (suppressed > 0) s << " (" << suppressed << " more since the last message)";
  ROS_WARN("%s", s.str().c_str());
}

void InputHealth::tfLookupFailed(const std::string& what) {
  uint64_t suppressed = 0;
  if (dropped("missing tf", &suppressed)) ROS_WARN("%s: %s", name_.c_str(), what.c_str());
}

void InputHealth::dropped_count() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++dropped_;
}

void InputHealth::processed(double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++processed_;
  last_seconds_ = seconds;
  max_seconds_ = std::max(max_seconds_, seconds);
  sum_seconds_ += seconds;
}

uint64_t InputHealth::processedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return processed_;
}

uint64_t InputHealth::errorCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  uint64_t n = 0;
  for (const auto& k : kinds_) n += k.second.count;
  return n;
}

uint64_t InputHealth::errorCount(const std::string& kind) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string sub_kind_prefix = kind + " (";
  uint64_t n = 0;
  for (auto it = kinds_.lower_bound(kind); it != kinds_.end(); ++it) {
    if (it->first == kind) {
      n += it->second.count;
    } else if (it->first.compare(0, sub_kind_prefix.size(), sub_kind_prefix) == 0) {
      n += it->second.count;
    } else if (it->first.compare(0, kind.size(), kind) != 0) {
      break;  // sorted: past every key that starts with `kind`
    }
  }
  return n;
}

void InputHealth::fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  uint64_t errors = 0;
  std::string recent;
  for (const auto& k : kinds_) {
    errors += k.second.count;
    status.add("errors: " + k.first, k.second.count);
    if ((now - k.second.last_seen).toSec() < throttle_period_) {
      recent += (recent.empty() ? "" : "; ") + k.first;
    }
  }
  status.add("scans processed", processed_);
  status.add("scans dropped", dropped_);
  status.add("errors total", errors);
  status.add("processing time last [ms]", last_seconds_ * 1e3);
  status.add("processing time max [ms]", max_seconds_ * 1e3);
  status.add("processing time mean [ms]", processed_ ? sum_seconds_ / processed_ * 1e3 : 0.0);
  if (!recent.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "recent input problems: " + recent);
  } else if (processed_ == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no scan processed yet");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "processing");
  }
}

bool sensorPoseFromTf(const tf2_ros::Buffer& buffer, const std::string& ground_frame,
                      const std_msgs::Header& header, InputHealth* health, SensorPose* pose) {
  geometry_msgs::TransformStamped t;
  try {
    t = buffer.lookupTransform(ground_frame, header.frame_id, header.stamp);
  } catch (const tf2::TransformException& e) {
    health->tfLookupFailed(e.what());
    return false;
  }
  Eigen::Isometry3d sensor_to_ground = tf2::transformToEigen(t);
  sensor_to_ground.translation().x() = 0.0;
  sensor_to_ground.translation().y() = 0.0;
  pose->sensor_to_ground = sensor_to_ground.cast<float>();
  return true;
}

}  // namespace ladar_perception
