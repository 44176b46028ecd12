#include "ladar_perception/ros/calibration_ros.h"

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <future>
#include <sstream>

#include <geometry_msgs/TransformStamped.h>
#include <std_msgs/String.h>
#include <tf2_eigen/tf2_eigen.h>

#include "ladar_perception/calibration/result_yaml.h"
#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

namespace cal = calibration;

bool calibrationPoints(const sensor_msgs::PointCloud2& msg, double min_range, double max_range,
                       cal::PointVector* points, std::string* error, CloudError* code) {
  CloudLayout layout;
  PointCloudView view;
  if (!viewOf(msg, &layout, &view, error, code)) return false;
  cal::pointsFromView(view, min_range, max_range, points);
  return true;
}

bool calibrationPoints(const sensor_msgs::LaserScan& msg, cal::PointVector* points,
                       std::string* error) {
  if (!std::isfinite(msg.angle_min) || !std::isfinite(msg.angle_increment) ||
      msg.angle_increment == 0.f) {
    *error = "LaserScan with an unusable angle_min/angle_increment";
    return false;
  }
  cal::pointsFromLaserScan(msg.ranges.data(), msg.ranges.size(), msg.angle_min,
                           msg.angle_increment, msg.range_min, msg.range_max, points);
  return true;
}

bool readPose6(const ros::NodeHandle& nh, const std::string& name, const cal::Pose6& fallback,
               cal::Pose6* out) {
  *out = fallback;
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return true;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray || v.size() != 6) return false;
  for (int i = 0; i < 6; ++i) {
    if (v[i].getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      (*out)[i] = static_cast<double>(v[i]);
    } else if (v[i].getType() == XmlRpc::XmlRpcValue::TypeInt) {
      (*out)[i] = static_cast<int>(v[i]);
    } else {
      return false;
    }
  }
  return true;
}

namespace {

std::string poseText(const cal::Pose6& p) {
  std::ostringstream s;
  s.precision(4);
  s << std::fixed << "x " << p[0] << " y " << p[1] << " z " << p[2] << " roll " << p[3]
    << " pitch " << p[4] << " yaw " << p[5];
  return s.str();
}

}  // namespace

CalibrationRos::CalibrationRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      service_nh_(private_nh),
      health_("Calibration") {
  odom_frame_ = private_nh_.param<std::string>("odom_frame", "odom");
  base_frame_ = private_nh_.param<std::string>("base_frame", "base_link");
  output_file_ = private_nh_.param<std::string>("output_file", "");
  buffer_size_ = std::max(1, private_nh_.param("buffer_size", 50));
  buffer_points_ = std::max(1, private_nh_.param("buffer_points", 8000000));
  buffer_voxel_ = private_nh_.param("buffer_voxel", 0.1);
  min_range_ = private_nh_.param("min_range", 0.5);
  max_range_ = private_nh_.param("max_range", 120.0);
  tf_wait_ = private_nh_.param("tf_wait", 2.0);
  network_output_file_ = private_nh_.param<std::string>("network_output_file", "");
  sensors_.resize(1);
  sensors_[0].role = "reference";
  sensors_[0].topic = "reference";
  sensors_[0].type = private_nh_.param<std::string>("reference_type", "PointCloud2");
  sensors_[0].frame = private_nh_.param<std::string>("reference_frame", "");
  sensors_[0].voxel = buffer_voxel_;
  // Several targets: ~target_topics (and ~target_types, one per topic or one for all); else the
  // one on `target`.
  std::vector<std::string> topics, types;
  private_nh_.getParam("target_topics", topics);
  private_nh_.getParam("target_types", types);
  private_nh_.getParam("target_surface_voxels", target_surface_voxels_);
  // Per-target thinning of each buffered scan (~target_buffer_voxels, else ~buffer_voxel): a
  // stereo camera's frames want a fine one (their dense, accurate near returns are otherwise
  // merged while the noisy far ones stay; 0.1 m left the camera 12 cm off).
  std::vector<double> target_voxels, target_intervals;
  private_nh_.getParam("target_buffer_voxels", target_voxels);
  // At most one scan per interval is buffered (~buffer_interval, ~target_buffer_intervals): a
  // Velodyne's buffer then spans the drive instead of its last seconds.
  private_nh_.getParam("target_buffer_intervals", target_intervals);
  const double interval = private_nh_.param("buffer_interval", 0.0);
  sensors_[0].interval = interval;
  const std::string target_type = private_nh_.param<std::string>("target_type", "PointCloud2");
  if (topics.empty()) {
    Sensor t;
    t.role = "target";
    t.topic = "target";
    t.type = target_type;
    t.frame = private_nh_.param<std::string>("target_frame", "");
    t.voxel = target_voxels.empty() ? buffer_voxel_ : target_voxels[0];
    t.interval = target_intervals.empty() ? interval : target_intervals[0];
    sensors_.push_back(std::move(t));
  }
  for (std::size_t k = 0; k < topics.size(); ++k) {
    Sensor t;
    t.role = "target " + topics[k];
    t.topic = topics[k];
    t.type = types.size() == topics.size() ? types[k] : (types.size() == 1 ? types[0] : target_type);
    t.voxel = k < target_voxels.size() ? target_voxels[k] : buffer_voxel_;
    t.interval = k < target_intervals.size() ? target_intervals[k] : interval;
    sensors_.push_back(std::move(t));
  }
  if (!types.empty() && types.size() != 1 && types.size() != topics.size()) {
    ROS_ERROR_STREAM("Calibration: ~target_types has " << types.size() << " entries for "
                     << topics.size() << " ~target_topics (one per topic, or one for all); using ~target_type");
  }
  for (Sensor& s : sensors_) {
    s.ring.reset(new cal::ScanRing(static_cast<std::size_t>(buffer_size_),
                                   static_cast<std::size_t>(4 * buffer_size_),
                                   static_cast<std::size_t>(buffer_points_)));
  }
  const std::string method = private_nh_.param<std::string>("method", cal::defaultMethod());
  if (!cal::isMethod(method)) {
    ROS_ERROR_STREAM("Calibration: unknown method '" << method << "' in ~method; requests that "
                     "name no method will be refused");
  }

  tf_listener_.reset(new tf2_ros::TransformListener(tf_buffer_, nh_));

  // Publishers first, services and subscribers last.
  progress_pub_ = private_nh_.advertise<std_msgs::String>("progress", 20);
  progress_estimate_pub_ =
      private_nh_.advertise<geometry_msgs::TransformStamped>("progress_estimate", 20);

  service_nh_.setCallbackQueue(&service_queue_);
  calibrate_srv_ = service_nh_.advertiseService("calibrate", &CalibrationRos::calibrateService, this);
  network_srv_ = service_nh_.advertiseService("calibrate_network",
                                              &CalibrationRos::calibrateNetworkService, this);
  reset_srv_ = service_nh_.advertiseService("reset", &CalibrationRos::resetService, this);
  save_srv_ = service_nh_.advertiseService("save", &CalibrationRos::saveService, this);
  // Two threads: one may wait on a running calibration while the other answers "busy".
  service_spinner_.reset(new ros::AsyncSpinner(2, &service_queue_));
  service_spinner_->start();

  diagnostics_.reset(new AdapterDiagnostics(
      nh_, private_nh_, "Calibration", "calibration", 0.0, 0.0,  // no rate check: any pair of rates
      [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); }));

  drain_timer_ = nh_.createTimer(ros::Duration(0.05), &CalibrationRos::drainPending, this);
  const int queue = private_nh_.param("queue_size", 20);
  for (std::size_t s = 0; s < sensors_.size(); ++s) {
    const std::string& topic = sensors_[s].topic;
    if (sensors_[s].type == "LaserScan") {
      sensors_[s].subscriber = nh_.subscribe<sensor_msgs::LaserScan>(
          topic, queue, [this, s](const sensor_msgs::LaserScanConstPtr& m) { scanCallback(m, s); });
    } else {
      if (sensors_[s].type != "PointCloud2") {
        ROS_ERROR_STREAM("Calibration: the " << sensors_[s].role << "'s type must be PointCloud2 or "
                         "LaserScan, not '" << sensors_[s].type << "'; using PointCloud2");
        sensors_[s].type = "PointCloud2";
      }
      sensors_[s].subscriber = nh_.subscribe<sensor_msgs::PointCloud2>(
          topic, queue, [this, s](const sensor_msgs::PointCloud2ConstPtr& m) { cloudCallback(m, s); });
    }
  }
}

CalibrationRos::~CalibrationRos() {
  shutting_down_ = true;  // a running calibration stops at its next progress report
  for (Sensor& s : sensors_) s.subscriber.shutdown();
  drain_timer_.stop();
  diagnostics_.reset();
  if (service_spinner_) service_spinner_->stop();
  calibrate_srv_.shutdown();
  network_srv_.shutdown();
  reset_srv_.shutdown();
  save_srv_.shutdown();
}

std::size_t CalibrationRos::bufferedScans(bool target) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sensors_[target ? 1 : 0].ring->posedScans();
}

void CalibrationRos::cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg, std::size_t sensor) {
  try {
    const ros::WallTime start = ros::WallTime::now();
    std::lock_guard<std::mutex> work(work_mutex_);
    if (!admits(sensor, msg->header.frame_id, msg->header.stamp)) return;
    std::string error;
    CloudError code = CloudError::kNone;
    if (!calibrationPoints(*msg, min_range_, max_range_, &work_points_, &error, &code)) {
      health_.error(std::string("unreadable cloud (") + cloudErrorName(code) + ")",
                    sensors_[sensor].role + " cloud in frame '" + msg->header.frame_id +
                        "': " + error);
      return;
    }
    if (enqueue(sensor, msg->header.stamp)) {
      health_.processed((ros::WallTime::now() - start).toSec());  // conversion + thinning
    }
  } catch (const std::exception& e) {
    health_.error("callback failure", std::string("cloud callback: ") + e.what());
  }
}

void CalibrationRos::scanCallback(const sensor_msgs::LaserScanConstPtr& msg, std::size_t sensor) {
  try {
    const ros::WallTime start = ros::WallTime::now();
    std::lock_guard<std::mutex> work(work_mutex_);
    if (!admits(sensor, msg->header.frame_id, msg->header.stamp)) return;
    std::string error;
    if (!calibrationPoints(*msg, &work_points_, &error)) {
      health_.error("unreadable scan", sensors_[sensor].role + " scan in frame '" +
                                           msg->header.frame_id + "': " + error);
      return;
    }
    if (enqueue(sensor, msg->header.stamp)) {
      health_.processed((ros::WallTime::now() - start).toSec());  // conversion + thinning
    }
  } catch (const std::exception& e) {
    health_.error("callback failure", std::string("scan callback: ") + e.what());
  }
}

namespace {
// Largest scan [points] whose conversion and thinning storage is kept for the next scan; a
// larger one (a 2-million-point cloud) is processed and its storage released.
constexpr std::size_t kRetainedWorkPoints = 1 << 19;
}  // namespace

bool CalibrationRos::admits(std::size_t sensor, const std::string& frame, const ros::Time& stamp) {
  Sensor& s = sensors_[sensor];
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (s.frame.empty()) s.frame = frame;
    if (frame != s.frame) {
      health_.error("unexpected frame", s.role + " message in frame '" + frame +
                                            "', expected '" + s.frame + "'; ignored");
      return false;
    }
  }
  // Within the buffer interval of the last kept scan: not needed, and not converted.
  return !(s.interval > 0 && !s.last_kept.isZero() && stamp >= s.last_kept &&
           (stamp - s.last_kept).toSec() < s.interval);
}

bool CalibrationRos::enqueue(std::size_t sensor, const ros::Time& stamp) {
  Sensor& s = sensors_[sensor];
  const std::string& role = s.role;
  thinned_.clear();
  if (s.voxel > 0) {
    thinner_.thin(work_points_.data(), work_points_.size(), s.voxel, &thinned_);
  } else {
    thinned_.assign(work_points_.begin(), work_points_.end());
  }
  cal::ScanRing::PushOutcome outcome;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    outcome = s.ring->push(static_cast<int64_t>(stamp.toNSec()), thinned_.data(), thinned_.size());
  }
  const std::size_t thinned = thinned_.size();
  if (work_points_.capacity() > kRetainedWorkPoints || thinned_.capacity() > kRetainedWorkPoints) {
    cal::PointVector().swap(work_points_);
    cal::PointVector().swap(thinned_);
    thinner_ = cal::VoxelThinner();
  }
  if (outcome.stored) s.last_kept = stamp;
  if (!outcome.stored) {
    health_.error("scan too large", role + " scan of " + std::to_string(thinned) +
                                        " points after thinning; the buffer holds " +
                                        std::to_string(buffer_points_) + " (~buffer_points)");
    return false;
  }
  if (outcome.dropped_waiting > 0) {
    uint64_t suppressed = 0;
    if (health_.dropped("pending queue full", &suppressed)) {
      ROS_WARN_STREAM("Calibration: " << role << " scans wait for their vehicle pose beyond the "
                      "buffer's room; oldest dropped (" << suppressed << " more since the last "
                      "message)");
    }
  }
  return true;
}

void CalibrationRos::drainPending(const ros::TimerEvent&) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time now = ros::Time::now();
    for (Sensor& s : sensors_) {
      int64_t stamp_ns = 0;
      while (s.ring->oldestWaiting(&stamp_ns)) {
        ros::Time stamp;
        stamp.fromNSec(static_cast<uint64_t>(stamp_ns));
        std::string why;
        if (tf_buffer_.canTransform(odom_frame_, base_frame_, stamp, &why)) {
          s.ring->resolvePose(
              tf2::transformToEigen(tf_buffer_.lookupTransform(odom_frame_, base_frame_, stamp)));
          continue;
        }
        // Waited too long, or stamped far ahead of the clock (a bag that looped back in time:
        // tf has cleared its buffer and that pose will not come).
        if ((now - stamp).toSec() > tf_wait_ || (stamp - now).toSec() > tf_wait_) {
          health_.tfLookupFailed("no vehicle pose " + odom_frame_ + " -> " +
                                 base_frame_ + " at a " + s.role +
                                 " scan's stamp within " + std::to_string(tf_wait_) +
                                 " s; scan dropped (" + why + ")");
          s.ring->dropWaiting();
          continue;
        }
        break;  // stamps are ordered: later scans wait too
      }
    }
  } catch (const std::exception& e) {
    health_.error("callback failure", std::string("buffering: ") + e.what());
  }
}

void CalibrationRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  health_.fillDiagnostics(status);
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Sensor& sensor : sensors_) {
    const std::string& role = sensor.role;
    const std::size_t k = &sensor - sensors_.data();
    status.add(role + " frame", sensors_[k].frame.empty() ? std::string("(none yet)") : sensors_[k].frame);
    status.add(role + " scans buffered", sensors_[k].ring->posedScans());
    status.add(role + " scans waiting for a pose", sensors_[k].ring->waitingScans());
    status.add(role + " points buffered", sensors_[k].ring->points());
  }
  status.add("calibration running", busy_.load());
  status.add("last result", have_result_ ? (last_result_.success ? "success" : "no success")
                                          : "none");
  if (have_result_) status.add("last final cost", last_result_.final_cost);
}

bool CalibrationRos::publishProgress(const cal::SearchProgress& p, const std::string& child) {
  const int n = ++progress_iteration_;
  std_msgs::String line;
  std::ostringstream s;
  s << p.stage << " iteration " << n << " (stage " << p.iteration << "), evaluations "
    << p.evaluations << ", best cost " << p.best_cost << ", spread [" << p.spread.transpose()
    << "], estimate " << poseText(p.estimate);
  line.data = s.str();
  progress_pub_.publish(line);
  geometry_msgs::TransformStamped est = tf2::eigenToTransform(cal::toIsometry(p.estimate));
  est.header.stamp = ros::Time::now();
  est.header.frame_id = base_frame_;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    est.child_frame_id = child.empty() ? sensors_[1].frame : child;
  }
  progress_estimate_pub_.publish(est);
  return !shutting_down_ && ros::ok();
}

namespace {
// Where ROS keeps a node's files: $ROS_HOME, else ~/.ros, else /tmp.
std::string rosHomeDir() {
  const char* ros_home = std::getenv("ROS_HOME");
  const char* home = std::getenv("HOME");
  return ros_home ? ros_home : (home ? std::string(home) + "/.ros" : "/tmp");
}
}  // namespace

std::string CalibrationRos::outputPath() const {
  if (!output_file_.empty()) return output_file_;
  const std::string dir = rosHomeDir();
  std::string child = last_child_frame_.empty() ? "target" : last_child_frame_;
  for (char& c : child) {
    if (c == '/') c = '_';
  }
  return dir + "/ladar_calibration_" + child + ".yaml";
}

namespace {

// One calibration at a time: a request while one runs is answered busy at once; an exception
// becomes the answer's message (it must never leave a service callback).
template <typename Response, typename Run>
bool serveOneAtATime(std::atomic<bool>& busy, const std::atomic<int>& iteration,
                     const char* what, Response& res, Run run) {
  if (busy.exchange(true)) {
    res.success = false;
    res.message = "busy: a calibration is running (progress iteration " +
                  std::to_string(iteration.load()) + "); try again when it answers";
    return true;
  }
  try {
    run();
  } catch (const std::exception& e) {
    res.success = false;
    res.message = std::string(what) + " failed: " + e.what();
  }
  busy = false;
  return true;
}

}  // namespace

bool CalibrationRos::calibrateService(ladar_perception::Calibrate::Request& req,
                                      ladar_perception::Calibrate::Response& res) {
  return serveOneAtATime(busy_, progress_iteration_, "calibration", res,
                         [&] { runCalibration(req, res); });
}

bool CalibrationRos::requestParams(const std::string& method, const std::vector<double>& spread,
                                   cal::CalibrationParams* params, std::string* error) const {
  params->method = method.empty() ? private_nh_.param<std::string>("method", cal::defaultMethod())
                                  : method;
  if (!cal::isMethod(params->method)) {
    std::string names;
    for (const std::string& m : cal::methodNames()) names += " " + m;
    *error = "unknown method '" + params->method + "' (methods:" + names + ")";
    return false;
  }
  if (params->method == "particle_filter") {
    const cal::CalibrationParams thesis = cal::thesisParticleFilterParams();
    params->search = thesis.search;
  }
  params->bin_size = private_nh_.param("bin_size", params->bin_size);
  params->trim_fraction = private_nh_.param("trim_fraction", params->trim_fraction);
  params->refinement.reference_voxel =
      std::max(0.05, private_nh_.param("surface_voxel", params->refinement.reference_voxel));
  if (!readPose6(private_nh_, "spread", params->spread, &params->spread) ||
      !readPose6(private_nh_, "initial_guess", params->initial, &params->initial)) {
    *error = "~initial_guess and ~spread must be lists of 6 numbers (x y z roll pitch yaw)";
    return false;
  }
  if (!spread.empty()) {
    if (spread.size() != 6) {
      *error = "spread must have 6 values (x y z roll pitch yaw) or none";
      return false;
    }
    for (int i = 0; i < 6; ++i) params->spread[i] = spread[i];
  }
  return true;
}

void CalibrationRos::runCalibration(const ladar_perception::Calibrate::Request& req,
                                    ladar_perception::Calibrate::Response& res) {
  const auto fail = [&res](const std::string& why) {
    res.success = false;
    res.message = why;
  };
  cal::CalibrationParams params;
  std::string why;
  if (!requestParams(req.method, req.spread, &params, &why)) return fail(why);
  const geometry_msgs::Transform& g = req.initial_guess;
  const bool guess_given = g.translation.x != 0 || g.translation.y != 0 || g.translation.z != 0 ||
                           g.rotation.x != 0 || g.rotation.y != 0 || g.rotation.z != 0 ||
                           g.rotation.w != 0;
  if (guess_given) {
    const Eigen::Quaterniond q(g.rotation.w, g.rotation.x, g.rotation.y, g.rotation.z);
    if (!(q.norm() > 1e-6) || !std::isfinite(q.norm())) return fail("initial_guess has a zero or non-finite rotation");
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = q.normalized().toRotationMatrix();
    t.translation() << g.translation.x, g.translation.y, g.translation.z;
    params.initial = cal::fromIsometry(t);
  }

  // Snapshot of the buffers (the subscribers keep filling them meanwhile).
  cal::CalibrationInput input;
  std::string reference_frame, target_frame;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    reference_frame = sensors_[0].frame;
    target_frame = sensors_[1].frame;
    sensors_[0].ring->appendPosedTo(&input.reference);
    sensors_[1].ring->appendPosedTo(&input.target);
  }
  if (input.reference.empty() || input.target.empty()) {
    return fail("no data: " + std::to_string(input.reference.numScans()) + " reference and " +
                std::to_string(input.target.numScans()) + " target scans with a vehicle pose are "
                "buffered; drive the vehicle with both sensors publishing and tf " + odom_frame_ +
                " -> " + base_frame_ + " available");
  }
  try {
    input.reference_extrinsic = tf2::transformToEigen(
        tf_buffer_.lookupTransform(base_frame_, reference_frame, ros::Time(0)));
  } catch (const tf2::TransformException& e) {
    return fail("the reference's extrinsic " + base_frame_ + " -> " + reference_frame +
                " is not in tf: " + e.what());
  }

  progress_iteration_ = 0;
  // The work runs on its own thread; this service thread (the adapter's queue) only waits.
  auto future = std::async(std::launch::async, [&]() {
    return cal::calibrate(input, params,
                          [this](const cal::SearchProgress& p) { return publishProgress(p); });
  });
  const cal::CalibrationResult result = future.get();

  res.success = result.success;
  res.message = result.message;
  res.transform = tf2::eigenToTransform(cal::toIsometry(result.extrinsic));
  res.transform.header.stamp = ros::Time::now();
  res.transform.header.frame_id = base_frame_;
  res.transform.child_frame_id = target_frame;
  res.stddev.assign(result.stddev.data(), result.stddev.data() + 6);
  res.final_cost = result.final_cost;
  res.unobservable = result.unobservable;
  res.elapsed = result.elapsed;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_result_ = result;
    last_child_frame_ = target_frame;
    have_result_ = true;
  }
  const std::string path = outputPath();
  res.launch_line = cal::staticTransformLaunchLine(path, base_frame_, target_frame);
  if (result.success) {
    std::string error;
    if (cal::writeStaticTransformYaml(path, base_frame_, target_frame, result, &error)) {
      res.message += "; written to " + path;
    } else {
      res.message += "; NOT written: " + error;
    }
  } else {
    res.message += "; not written (call ~save to write it anyway)";
  }
  ROS_INFO_STREAM("Calibration " << (result.success ? "succeeded" : "did not succeed") << " in "
                  << result.elapsed << " s: " << poseText(result.extrinsic) << "; "
                  << res.message);
}

std::string CalibrationRos::networkOutputPath() const {
  if (!network_output_file_.empty()) return network_output_file_;
  return rosHomeDir() + "/ladar_calibration_network.yaml";
}

bool CalibrationRos::calibrateNetworkService(ladar_perception::CalibrateNetwork::Request& req,
                                             ladar_perception::CalibrateNetwork::Response& res) {
  return serveOneAtATime(busy_, progress_iteration_, "network calibration", res,
                         [&] { runNetwork(req, res); });
}

void CalibrationRos::runNetwork(const ladar_perception::CalibrateNetwork::Request& req,
                                ladar_perception::CalibrateNetwork::Response& res) {
  const auto fail = [&res](const std::string& why) {
    res.success = false;
    res.message = why;
  };
  cal::NetworkParams params;
  std::string why;
  if (!requestParams(req.method, req.spread, &params.calibration, &why)) return fail(why);
  params.cross_pairs = !req.reference_only;

  // Snapshot of the buffers (the subscribers keep filling them meanwhile).
  cal::NetworkInput input;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    input.reference_name = sensors_[0].frame;
    sensors_[0].ring->appendPosedTo(&input.reference);
    for (std::size_t k = 1; k < sensors_.size(); ++k) {
      cal::NetworkTarget t;
      t.name = sensors_[k].frame;
      if (k - 1 < target_surface_voxels_.size()) t.surface_voxel = target_surface_voxels_[k - 1];
      sensors_[k].ring->appendPosedTo(&t.scans);
      input.targets.push_back(std::move(t));
    }
  }
  std::string empty;
  if (input.reference.empty()) empty += " the reference";
  for (const cal::NetworkTarget& t : input.targets) {
    if (t.scans.empty() || t.name.empty()) empty += " " + (t.name.empty() ? std::string("a target") : t.name);
  }
  if (!empty.empty()) {
    return fail("no data from" + empty + ": drive the vehicle with every sensor publishing and tf " +
                odom_frame_ + " -> " + base_frame_ + " available");
  }
  try {
    input.reference_extrinsic = tf2::transformToEigen(
        tf_buffer_.lookupTransform(base_frame_, input.reference_name, ros::Time(0)));
  } catch (const tf2::TransformException& e) {
    return fail("the reference's extrinsic " + base_frame_ + " -> " + input.reference_name +
                " is not in tf: " + e.what());
  }
  // Each target's initial guess: ~initial_guesses/<frame> (6 numbers), else its mount in tf (an
  // existing, uncertain calibration), else ~initial_guess. The spread is the request's or ~spread.
  for (cal::NetworkTarget& t : input.targets) {
    t.spread = params.calibration.spread;
    t.initial = params.calibration.initial;
    const std::string key = "initial_guesses/" + cal::networkKey(t.name);
    if (private_nh_.hasParam(key)) {
      if (!readPose6(private_nh_, key, t.initial, &t.initial)) {
        return fail("~" + key + " must be a list of 6 numbers (x y z roll pitch yaw)");
      }
    } else {
      try {
        t.initial = cal::fromIsometry(
            tf2::transformToEigen(tf_buffer_.lookupTransform(base_frame_, t.name, ros::Time(0))));
      } catch (const tf2::TransformException&) {
      }
    }
  }

  progress_iteration_ = 0;
  auto future = std::async(std::launch::async, [&]() {
    return cal::calibrateNetwork(input, params, [this](const std::string& edge,
                                                       const cal::SearchProgress& p) {
      cal::SearchProgress q = p;
      q.stage = edge + ": " + p.stage;
      return publishProgress(q, edge.substr(0, edge.find(" <- ")));
    });
  });
  const cal::NetworkResult result = future.get();

  res.success = result.success;
  res.message = result.message;
  res.elapsed = result.elapsed;
  const ros::Time now = ros::Time::now();
  const auto stamped = [&](const cal::Pose6& pose, const std::string& child) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(cal::toIsometry(pose));
    t.header.stamp = now;
    t.header.frame_id = base_frame_;
    t.child_frame_id = child;
    return t;
  };
  for (const cal::NetworkSensorResult& s : result.sensors) {
    res.transforms.push_back(stamped(s.joint, s.name));
    res.pairwise.push_back(stamped(s.pairwise, s.name));
    res.stddev.insert(res.stddev.end(), s.stddev.data(), s.stddev.data() + 6);
    for (const std::string& u : s.unobservable) res.unobservable.push_back(s.name + ": " + u);
  }
  for (const cal::NetworkEdge& e : result.edges) {
    res.edges.push_back(result.sensors[e.to].name + " <- " +
                        (e.from < 0 ? std::string("reference") : result.sensors[e.from].name));
    res.edge_used.push_back(e.used);
    res.loop_translation.push_back(e.loop_translation);
    res.loop_rotation.push_back(e.loop_rotation);
    res.residual_translation.push_back(e.residual_translation);
    res.residual_rotation.push_back(e.residual_rotation);
  }
  const std::string path = networkOutputPath();
  std::string launch_path = path;
  const std::size_t dot = launch_path.rfind(".yaml");
  if (dot != std::string::npos && dot + 5 == launch_path.size()) launch_path.erase(dot);
  launch_path += ".launch";
  if (result.success) {
    std::string error;
    if (cal::backupExistingFile(path, nullptr, &error) &&
        cal::writeFileAtomically(path, cal::networkYaml(base_frame_, result), &error) &&
        cal::backupExistingFile(launch_path, nullptr, &error) &&
        cal::writeFileAtomically(launch_path, cal::networkLaunch(path, result), &error)) {
      res.output_file = path;
      res.launch_file = launch_path;
      res.message += "; written to " + path + " and " + launch_path;
    } else {
      res.message += "; NOT written: " + error;
    }
  } else {
    res.message += "; not written";
  }
  ROS_INFO_STREAM("Calibration: network " << (result.success ? "calibrated" : "not calibrated")
                  << " in " << result.elapsed << " s: " << res.message);
}

bool CalibrationRos::resetService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> work(work_mutex_);  // the callbacks' order: work_mutex_, then mutex_
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t n = 0;
  for (Sensor& s : sensors_) {
    n += s.ring->posedScans() + s.ring->waitingScans();
    s.ring->clear();
    s.last_kept = ros::Time();
  }
  have_result_ = false;
  res.success = true;
  res.message = "cleared " + std::to_string(n) + " buffered scans" +
                (busy_ ? " (a running calibration keeps its own copy)" : "");
  return true;
}

bool CalibrationRos::saveService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  cal::CalibrationResult result;
  std::string child;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!have_result_) {
      res.success = false;
      res.message = "nothing to save: no calibration has run since start or reset";
      return true;
    }
    result = last_result_;
    child = last_child_frame_;
  }
  const std::string path = outputPath();
  std::string error;
  res.success = cal::writeStaticTransformYaml(path, base_frame_, child, result, &error);
  res.message = res.success ? "written to " + path + (result.success ? "" : " (the result was not a success: see its comments)")
                            : error;
  return true;
}

}  // namespace ladar_perception
