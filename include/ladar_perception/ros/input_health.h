// Bookkeeping every adapter shares: a per-kind throttled error reporter (each kind of bad
// input is logged once per throttle period, with what was wrong) and processing statistics for
// diagnostics. Thread-safe: callbacks may run on several threads of a nodelet manager.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/time.h>
#include <std_msgs/Header.h>
#include <tf2_ros/message_filter.h>

#include <tf2_ros/buffer.h>

#include "ladar_perception/ground/ground_classification.h"

namespace ladar_perception {

class InputHealth {
 public:
  // `name` prefixes every log line (the nodelet's type, e.g. "VerticalScanGround").
  explicit InputHealth(std::string name = "ladar_perception", double throttle_period = 5.0)
      : name_(std::move(name)), throttle_period_(throttle_period) {}

  // Counts a problem and logs it as an error, throttled per kind, with how many of this kind
  // were not logged since the last line.
  void error(const std::string& kind, const std::string& detail);
  // A message dropped by a tf2_ros::MessageFilter (its transform never came): counted as a
  // dropped scan of kind "missing tf" and logged as a throttled warning.
  void tfFilterDropped(const std::string& target_frame, const std_msgs::Header& header,
                       tf2_ros::filter_failure_reasons::FilterFailureReason reason);
  // A transform lookup that failed after the filter passed the message.
  void tfLookupFailed(const std::string& what);

  // Counts a problem of the given kind ("unreadable cloud", "missing tf", ...). Returns true
  // when the caller should log it now (first time, or the throttle period has passed since
  // this kind was last logged); *suppressed says how many of this kind were not logged since.
  bool report(const std::string& kind, uint64_t* suppressed = nullptr);

  // A scan that went through the core: its processing time in seconds.
  void processed(double seconds);
  // A scan dropped before processing (tf never arrived, queue overflow); counts it under
  // `kind` and returns, like report(), whether to log now.
  bool dropped(const std::string& kind, uint64_t* suppressed = nullptr) {
    dropped_count();
    return report(kind, suppressed);
  }

  // Adds counts, error kinds and processing times to a diagnostic status; warns while errors
  // happened in the last throttle period.
  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) const;

  uint64_t processedCount() const;
  uint64_t errorCount() const;
  // Problems of `kind` and of its sub-kinds: "unreadable cloud" also counts
  // "unreadable cloud (data too short)" and every other "unreadable cloud (...)".
  uint64_t errorCount(const std::string& kind) const;

 private:
  void dropped_count();
  struct Kind {
    uint64_t count = 0;
    uint64_t suppressed = 0;
    ros::WallTime last_logged;
    ros::WallTime last_seen;
  };
  mutable std::mutex mutex_;
  std::string name_;
  double throttle_period_;
  std::map<std::string, Kind> kinds_;
  uint64_t processed_ = 0;
  uint64_t dropped_ = 0;
  double last_seconds_ = 0.0;
  double max_seconds_ = 0.0;
  double sum_seconds_ = 0.0;
};

// The sensor's pose above the local ground from tf (ground_frame <- header.frame_id at the
// stamp), shifted so the origin is the ground point under the sensor (SensorPose's convention).
// A failed lookup is counted and reported through `health`; returns false then.
bool sensorPoseFromTf(const tf2_ros::Buffer& buffer, const std::string& ground_frame,
                      const std_msgs::Header& header, InputHealth* health, SensorPose* pose);

}  // namespace ladar_perception
