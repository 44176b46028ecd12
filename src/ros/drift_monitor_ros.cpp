#include "ladar_perception/ros/drift_monitor_ros.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cmath>
#include <sstream>

#include <geometry_msgs/TransformStamped.h>
#include <tf2_eigen/tf2_eigen.h>

#include "ladar_perception/ros/calibration_ros.h"  // calibrationPoints, readPose6
#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

namespace cal = calibration;

namespace {
constexpr std::size_t kMaxPending = 40;  // scans waiting for tf (20 per sensor at the defaults)
}  // namespace

DriftMonitorRos::DriftMonitorRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), health_("DriftMonitor") {
  odom_frame_ = private_nh_.param<std::string>("odom_frame", "odom");
  base_frame_ = private_nh_.param<std::string>("base_frame", "base_link");
  frames_[0] = private_nh_.param<std::string>("reference_frame", "");
  frames_[1] = private_nh_.param<std::string>("target_frame", "");
  scan_interval_ = std::max(0.0, private_nh_.param("scan_interval", 2.0));
  check_interval_ = std::max(0.1, private_nh_.param("check_interval", 4.0));
  voxel_ = private_nh_.param("voxel", 0.1);
  min_range_ = private_nh_.param("min_range", 0.5);
  max_range_ = private_nh_.param("max_range", 120.0);
  tf_wait_ = private_nh_.param("tf_wait", 2.0);
  worker_nice_ = std::min(19, std::max(0, private_nh_.param("worker_nice", 10)));
  params_.window = std::max(1.0, private_nh_.param("window", params_.window));
  params_.max_window_scans =
      static_cast<std::size_t>(std::max(2, private_nh_.param("max_window_scans", 8)));
  params_.min_scans = std::max(1, private_nh_.param("min_scans", params_.min_scans));
  params_.warn_translation = private_nh_.param("warn_translation", params_.warn_translation);
  params_.error_translation = private_nh_.param("error_translation", params_.error_translation);
  params_.warn_rotation = private_nh_.param("warn_rotation", params_.warn_rotation);
  params_.error_rotation = private_nh_.param("error_rotation", params_.error_rotation);
  params_.significance = private_nh_.param("significance", params_.significance);
  params_.error_checks = std::max(1, private_nh_.param("error_checks", params_.error_checks));
  params_.calibration.refinement.reference_voxel = std::max(
      0.05, private_nh_.param("surface_voxel", params_.calibration.refinement.reference_voxel));
  if (!readPose6(private_nh_, "spread", params_.spread, &params_.spread)) {
    ROS_ERROR("DriftMonitor: ~spread must be a list of 6 numbers (x y z roll pitch yaw); using "
              "the default");
    params_.spread = cal::DriftMonitorParams().spread;
  }

  tf_listener_.reset(new tf2_ros::TransformListener(tf_buffer_, nh_));
  estimate_pub_ = private_nh_.advertise<geometry_msgs::TransformStamped>("estimate", 10);
  diagnostics_.reset(new AdapterDiagnostics(
      nh_, private_nh_, "DriftMonitor", "drift monitor", 0.0, 0.0,
      [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); }));
  thread_ = std::thread([this] { worker(); });

  const int queue = private_nh_.param("queue_size", 2);
  for (int s = 0; s < 2; ++s) {
    const bool target = s == 1;
    const std::string topic = target ? "target" : "reference";
    const std::string type =
        private_nh_.param<std::string>(topic + "_type", "PointCloud2");
    // One 2D line every scan_interval is far too little to re-estimate a mount: 3D sensors only
    // (a 2D ladar's drift is not measured; calibrate it offline with Calibration).
    if (type != "PointCloud2") {
      std::lock_guard<std::mutex> lock(status_mutex_);
      config_error_ = "~" + topic + "_type '" + type + "' is not supported: the drift monitor " +
                      "watches 3D sensors (PointCloud2) only";
      ROS_ERROR_STREAM("DriftMonitor: " << config_error_);
      continue;
    }
    subscribers_[s] = nh_.subscribe<sensor_msgs::PointCloud2>(
        topic, queue,
        [this, target](const sensor_msgs::PointCloud2ConstPtr& m) { cloudCallback(m, target); });
  }
}

DriftMonitorRos::~DriftMonitorRos() {
  for (ros::Subscriber& s : subscribers_) s.shutdown();
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();  // a running check finishes first (< 1 s)
  diagnostics_.reset();
}

bool DriftMonitorRos::due(bool target, const ros::Time& stamp) {
  const double t = stamp.toSec();
  double& last = last_taken_[target ? 1 : 0];
  // A stamp far behind the last one taken: a bag that looped back in time; start over.
  if (t < last - 10.0 * std::max(1.0, scan_interval_)) last = -1e300;
  return t - last >= scan_interval_;
}

void DriftMonitorRos::cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg, bool target) {
  try {
    std::lock_guard<std::mutex> lock(callback_mutex_);
    if (!due(target, msg->header.stamp)) return;
    const ros::WallTime start = ros::WallTime::now();
    std::string error;
    CloudError code = CloudError::kNone;
    if (!calibrationPoints(*msg, min_range_, max_range_, &work_points_, &error, &code)) {
      health_.error(std::string("unreadable cloud (") + cloudErrorName(code) + ")",
                    std::string(target ? "target" : "reference") + " cloud in frame '" +
                        msg->header.frame_id + "': " + error);
      return;
    }
    handOver(target, msg->header.frame_id, msg->header.stamp);
    health_.processed((ros::WallTime::now() - start).toSec());
  } catch (const std::exception& e) {
    health_.error("callback failure", std::string("cloud callback: ") + e.what());
  }
}

void DriftMonitorRos::handOver(bool target, const std::string& frame, const ros::Time& stamp) {
  thinned_.clear();
  if (voxel_ > 0) {
    thinner_.thin(work_points_.data(), work_points_.size(), voxel_, &thinned_);
  } else {
    thinned_.assign(work_points_.begin(), work_points_.end());
  }
  if (thinned_.empty()) return;
  last_taken_[target ? 1 : 0] = stamp.toSec();
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    if (pending_.size() >= kMaxPending) {
      pending_.pop_front();
      uint64_t suppressed = 0;
      if (health_.dropped("pending queue full", &suppressed)) {
        ROS_WARN_STREAM("DriftMonitor: scans wait for tf beyond " << kMaxPending
                        << "; oldest dropped (" << suppressed << " more since the last message)");
      }
    }
    pending_.push_back(Pending{target, frame, stamp, thinned_});
  }
  wake_.notify_one();
}

void DriftMonitorRos::worker() {
  // A lower scheduling priority for this thread alone: on a loaded CPU the ground nodelets'
  // callbacks go first, and a check waits.
  if (worker_nice_ != 0 &&
      setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), worker_nice_) != 0) {
    ROS_WARN("DriftMonitor: could not lower the worker thread's priority (nice %d)", worker_nice_);
  }
  while (true) {
    {
      std::unique_lock<std::mutex> lock(pending_mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(100));
      if (stop_) return;
    }
    try {
      feed();
      check();
    } catch (const std::exception& e) {
      health_.error("internal error", std::string("drift check: ") + e.what());
    }
  }
}

void DriftMonitorRos::feed() {
  std::deque<Pending> work;
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    work.swap(pending_);
  }
  std::deque<Pending> keep;  // still waiting for tf
  const ros::Time now = ros::Time::now();
  for (Pending& p : work) {
    const int k = p.target ? 1 : 0;
    const std::string frame = frames_[k].empty() ? p.frame : frames_[k];
    std::string why;
    const bool pose_ready = tf_buffer_.canTransform(odom_frame_, base_frame_, p.stamp, &why);
    const bool extrinsic_ready =
        tf_buffer_.canTransform(base_frame_, frame, ros::Time(0), &why);
    if (!pose_ready || !extrinsic_ready) {
      if ((now - p.stamp).toSec() > tf_wait_ || (p.stamp - now).toSec() > tf_wait_) {
        health_.tfLookupFailed(std::string(pose_ready ? "no extrinsic " + base_frame_ + " -> " + frame
                                                      : "no vehicle pose " + odom_frame_ + " -> " + base_frame_) +
                               " for a " + (p.target ? "target" : "reference") + " scan within " +
                               std::to_string(tf_wait_) + " s; scan dropped (" + why + ")");
      } else {
        keep.push_back(std::move(p));
      }
      continue;
    }
    if (frames_[k].empty()) frames_[k] = p.frame;
    if (!monitor_) {
      const std::string other = frames_[1 - k];
      if (other.empty() || !tf_buffer_.canTransform(base_frame_, other, ros::Time(0))) {
        keep.push_back(std::move(p));  // the monitor needs both extrinsics
        continue;
      }
      const Eigen::Isometry3d ref = tf2::transformToEigen(
          tf_buffer_.lookupTransform(base_frame_, frames_[0], ros::Time(0)));
      const Eigen::Isometry3d tgt = tf2::transformToEigen(
          tf_buffer_.lookupTransform(base_frame_, frames_[1], ros::Time(0)));
      monitor_.reset(new cal::DriftMonitor(params_, ref, cal::fromIsometry(tgt)));
    }
    const Eigen::Isometry3d vehicle =
        tf2::transformToEigen(tf_buffer_.lookupTransform(odom_frame_, base_frame_, p.stamp));
    if (p.target) {
      monitor_->addTargetScan(p.stamp.toSec(), vehicle, p.points);
    } else {
      monitor_->addReferenceScan(p.stamp.toSec(), vehicle, p.points);
    }
    const double t = p.stamp.toSec();
    // The first scan, or a bag that looped back in time: the next check one interval on.
    if (next_check_ < 0 || t < next_check_ - 10.0 * check_interval_) {
      next_check_ = t + check_interval_;
    } else if (t >= next_check_) {
      check_due_ = true;
      due_stamp_ = std::max(due_stamp_, t);
    }
  }
  if (!keep.empty()) {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    for (auto it = keep.rbegin(); it != keep.rend(); ++it) pending_.push_front(std::move(*it));
  }
}

void DriftMonitorRos::check() {
  if (!monitor_ || !check_due_) return;
  check_due_ = false;
  next_check_ = due_stamp_ + check_interval_;
  // The configured extrinsic may have been replaced (a new calibration loaded).
  const cal::Pose6 configured = cal::fromIsometry(
      tf2::transformToEigen(tf_buffer_.lookupTransform(base_frame_, frames_[1], ros::Time(0))));
  if ((configured - monitor_->configured()).cwiseAbs().maxCoeff() > 1e-6) {
    monitor_->setConfigured(configured);
  }
  const cal::DriftEstimate e = monitor_->check();
  if (e.estimated) {
    geometry_msgs::TransformStamped out = tf2::eigenToTransform(cal::toIsometry(e.extrinsic));
    out.header.stamp.fromSec(e.stamp);
    out.header.frame_id = base_frame_;
    out.child_frame_id = frames_[1];
    estimate_pub_.publish(out);
  }
  if (e.level == cal::DriftLevel::kError) {
    ROS_ERROR_STREAM_THROTTLE(10.0, "DriftMonitor: " << frames_[1] << " has moved on its mount: "
                                                     << e.message);
  } else if (e.level == cal::DriftLevel::kWarn) {
    ROS_WARN_STREAM_THROTTLE(10.0, "DriftMonitor: " << frames_[1] << ": " << e.message);
  }
  std::lock_guard<std::mutex> lock(status_mutex_);
  last_ = e;
  have_estimate_ = true;
  ++checks_;
  warn_checks_ += e.level == cal::DriftLevel::kWarn;
  error_checks_ += e.level == cal::DriftLevel::kError;
  state_ = e.message;
}

void DriftMonitorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  health_.fillDiagnostics(status);
  std::lock_guard<std::mutex> lock(status_mutex_);
  status.add("reference frame", frames_[0].empty() ? std::string("(none yet)") : frames_[0]);
  status.add("target frame", frames_[1].empty() ? std::string("(none yet)") : frames_[1]);
  status.add("checks", checks_);
  status.add("checks at WARN", warn_checks_);
  status.add("checks at ERROR", error_checks_);
  status.add("drift level", have_estimate_ ? cal::driftLevelName(last_.level) : "UNKNOWN");
  status.add("drift", state_);
  if (have_estimate_ && last_.estimated) {
    static const char* names[6] = {"x", "y", "z", "roll", "pitch", "yaw"};
    for (int i = 0; i < 6; ++i) {
      std::ostringstream v;
      v << last_.offset[i] << " +- " << last_.stddev[i] << (i < 3 ? " m" : " rad");
      status.add(std::string("offset ") + names[i], v.str());
    }
    status.add("check CPU [s]", last_.cpu_time);
  }
  if (!config_error_.empty()) {
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::ERROR, config_error_);
  } else if (have_estimate_ && last_.level == cal::DriftLevel::kError) {
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::ERROR, "extrinsic drift: " + state_);
  } else if (have_estimate_ && last_.level == cal::DriftLevel::kWarn) {
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN, "extrinsic drift: " + state_);
  }
}

}  // namespace ladar_perception
