#include "ladar_perception/calibration/drift_monitor.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>

namespace ladar_perception {
namespace calibration {

const char* driftLevelName(DriftLevel level) {
  switch (level) {
    case DriftLevel::kOk: return "OK";
    case DriftLevel::kWarn: return "WARN";
    case DriftLevel::kError: return "ERROR";
    case DriftLevel::kUnknown: return "UNKNOWN";
  }
  return "?";
}

CalibrationParams DriftMonitorParams::defaultCalibration() {
  CalibrationParams p;
  p.method = "refine";
  p.refinement.max_target_points = 20000;
  p.refinement.max_correspondence_start = 0.5;  // a drift is small: no wide capture needed
  p.refinement.max_iterations = 15;
  p.symmetric_refinement = false;  // one direction suffices to see centimetres
  return p;
}

DriftMonitor::DriftMonitor(const DriftMonitorParams& params,
                           const Eigen::Isometry3d& reference_extrinsic,
                           const Pose6& configured_target)
    : params_(params), reference_extrinsic_(reference_extrinsic), configured_(configured_target) {}

void DriftMonitor::setConfigured(const Pose6& configured_target) {
  configured_ = configured_target;
  level_ = DriftLevel::kUnknown;
  over_error_ = under_error_ = 0;
}

void DriftMonitor::add(std::deque<Scan>* scans, double stamp, const Eigen::Isometry3d& vehicle_pose,
                       const PointVector& points) {
  if (!std::isfinite(stamp) || points.empty()) return;
  newest_ = std::max(newest_, stamp);
  // Keep the deque ordered by stamp (scans arrive nearly in order).
  auto it = scans->end();
  while (it != scans->begin() && std::prev(it)->stamp > stamp) --it;
  scans->insert(it, Scan{stamp, vehicle_pose, points});
  const double oldest = newest_ - params_.window;
  for (std::deque<Scan>* s : {&reference_, &target_}) {
    while (!s->empty() && s->front().stamp < oldest) s->pop_front();
  }
}

void DriftMonitor::addReferenceScan(double stamp, const Eigen::Isometry3d& vehicle_pose,
                                    const PointVector& points) {
  add(&reference_, stamp, vehicle_pose, points);
}

void DriftMonitor::addTargetScan(double stamp, const Eigen::Isometry3d& vehicle_pose,
                                 const PointVector& points) {
  add(&target_, stamp, vehicle_pose, points);
}

ScanSet DriftMonitor::window(const std::deque<Scan>& scans) const {
  ScanSet out;
  const std::size_t n = scans.size();
  const std::size_t keep = std::max<std::size_t>(1, std::min(n, params_.max_window_scans));
  for (std::size_t k = 0; k < keep; ++k) {
    // Evenly over the window, the newest always in.
    const std::size_t i = n - 1 - (keep > 1 ? k * (n - 1) / (keep - 1) : 0);
    out.addScan(scans[i].stamp, scans[i].vehicle_pose, scans[i].points);
  }
  return out;
}

DriftEstimate DriftMonitor::check() {
  DriftEstimate out;
  out.stamp = newest_;
  out.level = level_;
  if (reference_.size() < static_cast<std::size_t>(params_.min_scans) ||
      target_.size() < static_cast<std::size_t>(params_.min_scans)) {
    std::ostringstream m;
    m << "waiting for scans: " << reference_.size() << " reference and " << target_.size()
      << " target scans in the window (" << params_.min_scans << " each needed)";
    out.message = m.str();
    return out;
  }
  CalibrationResult r;
  try {
    CalibrationInput input;
    input.reference = window(reference_);
    input.reference_extrinsic = reference_extrinsic_;
    input.target = window(target_);
    CalibrationParams p = params_.calibration;
    p.initial = configured_;
    p.spread = params_.spread;
    r = calibrate(input, p);
  } catch (const std::exception& e) {
    out.message = std::string("re-estimate failed: ") + e.what();
    return out;
  }
  out.cpu_time = r.cpu_time;
  out.extrinsic = r.extrinsic;
  out.stddev = r.stddev;
  out.offset = poseDifference(r.extrinsic, configured_);
  // A window that fixes no DOF, or whose refinement left the spread, says nothing about drift
  // (the level is kept); an unobservable DOF is only left out.
  if (r.unobservable.size() == 6 || r.message.find("search region") != std::string::npos ||
      r.message.find("too few correspondences") != std::string::npos) {
    out.message = "window not informative: " + r.message;
    return out;
  }
  out.estimated = true;
  bool over_warn = false, over_error = false;
  std::ostringstream which;
  for (int i = 0; i < 6; ++i) {
    const double a = std::abs(out.offset[i]);
    const double sd = out.stddev[i];
    if (!std::isfinite(sd) || a <= params_.significance * sd) continue;  // not significant
    const bool rot = i >= 3;
    const double warn = rot ? params_.warn_rotation : params_.warn_translation;
    const double err = rot ? params_.error_rotation : params_.error_translation;
    if (a > warn) {
      over_warn = true;
      which << (which.tellp() > 0 ? ", " : "") << dofName(i) << " " << out.offset[i]
            << (rot ? " rad" : " m") << " (sd " << sd << ")";
    }
    if (a >= err) over_error = true;
  }
  if (over_error) {
    ++over_error_;
    under_error_ = 0;
  } else {
    over_error_ = 0;
    ++under_error_;
  }
  if (over_error_ >= params_.error_checks) {
    level_ = DriftLevel::kError;
  } else if (level_ == DriftLevel::kError && under_error_ < params_.error_checks) {
    // stays at ERROR until as many checks in a row are below the error thresholds
  } else {
    level_ = over_warn ? DriftLevel::kWarn : DriftLevel::kOk;
  }
  out.level = level_;
  std::ostringstream m;
  if (which.tellp() > 0) {
    m << "offset from the configured extrinsic: " << which.str();
  } else {
    m << "within tolerance of the configured extrinsic";
  }
  if (!r.unobservable.empty()) {
    m << "; not fixed by this window:";
    for (const std::string& n : r.unobservable) m << " " << n;
  }
  out.message = m.str();
  return out;
}

}  // namespace calibration
}  // namespace ladar_perception
