// Continuous recalibration (thesis 5.2.2): a sensor's extrinsic re-estimated against the
// reference from a sliding window of recent scans, and compared with the configured extrinsic
// (the one the rest of the vehicle uses). A mount knocked by a few centimetres or a fraction of
// a degree then shows as an offset larger than its own uncertainty. ROS-free: the DriftMonitor
// nodelet and the tests feed it scans with their vehicle poses.
#pragma once

#include <deque>
#include <string>

#include "ladar_perception/calibration/calibrator.h"

namespace ladar_perception {
namespace calibration {

enum class DriftLevel { kOk, kWarn, kError, kUnknown };
const char* driftLevelName(DriftLevel level);  // "OK", "WARN", "ERROR", "UNKNOWN"

struct DriftMonitorParams {
  double window = 20.0;            // [s] scans older than this (before the newest) are dropped
  std::size_t max_window_scans = 8;  // per sensor: the newest, evenly spread over the window
  int min_scans = 3;               // per sensor, before a check says anything
  // An offset counts when it exceeds its threshold AND `significance` reported standard
  // deviations: a window that cannot fix a DOF never raises on it.
  // The error thresholds sit below the bumps that must be caught (2 cm, 0.01 rad) so that a
  // bump of exactly that size, measured a little short, still counts.
  double warn_translation = 0.01;    // [m]
  double error_translation = 0.015;  // [m]
  double warn_rotation = 0.005;      // [rad]
  double error_rotation = 0.0075;    // [rad]
  double significance = 3.0;
  // ERROR only after this many consecutive checks over an error threshold (one noisy window
  // does not page anybody); it clears after as many checks below it.
  int error_checks = 2;
  // The re-estimate: a refinement from the configured extrinsic within this spread (no coarse
  // search: a drift is small), on thinned clouds.
  Pose6 spread = (Pose6() << 0.15, 0.15, 0.15, 0.05, 0.05, 0.05).finished();
  CalibrationParams calibration = defaultCalibration();

  static CalibrationParams defaultCalibration();
};

struct DriftEstimate {
  double stamp = 0;                // the newest scan's stamp [s]
  DriftLevel level = DriftLevel::kUnknown;
  bool estimated = false;          // the window gave an estimate
  Pose6 extrinsic = Pose6::Zero(); // the re-estimate, base_link -> target
  Pose6 offset = Pose6::Zero();    // re-estimate - configured (angles wrapped)
  Pose6 stddev = Pose6::Zero();    // of the re-estimate, per DOF (infinity: not fixed)
  double cpu_time = 0;             // of this check [s]
  std::string message;
};

class DriftMonitor {
 public:
  DriftMonitor(const DriftMonitorParams& params, const Eigen::Isometry3d& reference_extrinsic,
               const Pose6& configured_target);

  // Scans in their sensor frames, with the vehicle pose (odom -> base_link) at their stamps.
  // Scans older than the window are dropped; out-of-order stamps are accepted.
  void addReferenceScan(double stamp, const Eigen::Isometry3d& vehicle_pose, const PointVector& points);
  void addTargetScan(double stamp, const Eigen::Isometry3d& vehicle_pose, const PointVector& points);

  // Re-estimates from the current window and updates the level. Never throws.
  DriftEstimate check();

  // A new configured extrinsic (the mount was recalibrated): the level starts over.
  void setConfigured(const Pose6& configured_target);
  const Pose6& configured() const { return configured_; }
  DriftLevel level() const { return level_; }
  std::size_t referenceScans() const { return reference_.size(); }
  std::size_t targetScans() const { return target_.size(); }

 private:
  struct Scan {
    double stamp;
    Eigen::Isometry3d vehicle_pose;
    PointVector points;
  };
  void add(std::deque<Scan>* scans, double stamp, const Eigen::Isometry3d& vehicle_pose,
           const PointVector& points);
  ScanSet window(const std::deque<Scan>& scans) const;

  DriftMonitorParams params_;
  Eigen::Isometry3d reference_extrinsic_;
  Pose6 configured_;
  std::deque<Scan> reference_, target_;
  double newest_ = -1e300;
  DriftLevel level_ = DriftLevel::kUnknown;
  int over_error_ = 0;   // consecutive checks over an error threshold
  int under_error_ = 0;  // consecutive checks below, while at ERROR
};

}  // namespace calibration
}  // namespace ladar_perception
