#include "ladar_perception/ros/hough_ground_ros.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>

#include <visualization_msgs/Marker.h>

#include "ladar_perception/cloud/laser_scan.h"
#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

// Both directions are produced from the parameter table (hough_params.def).
HoughGroundParams toHoughGroundParams(const HoughGroundConfig& c) {
  HoughGroundParams p = c.method == "thesis" ? houghGroundThesisParams() : houghGroundDefaultParams();
#define LADAR_PARAM(type, member, name, def, lo, hi, unit, meaning) p.member = static_cast<type>(c.name);
#include "ladar_perception/ground/hough_params.def"
  return p;
}

void loadHoughMethodSettings(const std::string& method, HoughGroundConfig* c) {
  const HoughGroundParams p = method == "thesis" ? houghGroundThesisParams() : houghGroundDefaultParams();
#define LADAR_PARAM(type, member, name, def, lo, hi, unit, meaning) c->name = p.member;
#include "ladar_perception/ground/hough_params.def"
}

HoughGroundRos::HoughGroundRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), health_("HoughGround") {
  ground_frame_ = private_nh_.param<std::string>("ground_frame", "base_footprint");
  use_tf_ = private_nh_.param("use_tf", true);
  mount_roll_ = private_nh_.param("mount_roll", mount_roll_);
  mount_pitch_ = private_nh_.param("mount_pitch", mount_pitch_);
  const int queue_size = private_nh_.param("queue_size", 15);
  const double tf_tolerance = private_nh_.param("tf_tolerance", 0.0);

  ground_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("ground", 5);
  obstacles_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("obstacles", 5);
  classified_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("classified", 5);
  line_pub_ = nh_.advertise<visualization_msgs::Marker>("ground_line", 5);
  fit_pub_ = nh_.advertise<HoughGroundFit>("ground_fit", 5);

  diagnostics_.reset(new AdapterDiagnostics(
      nh_, private_nh_, "HoughGround", "hough ground", private_nh_.param("expected_rate_min", 50.0),
      private_nh_.param("expected_rate_max", 100.0),
      [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); }));

  reconfigure_.reset(new MethodReconfigure<HoughGroundConfig>(private_nh_, loadHoughMethodSettings));

  // Subscribe last.
  input_.reset(new SensorInput<sensor_msgs::LaserScan>(
      nh_, "scan", use_tf_, ground_frame_, queue_size, tf_tolerance, &health_,
      [this](const sensor_msgs::LaserScanConstPtr& m) { process(m); }));
  ROS_INFO("HoughGround: listening on %s, ground frame %s%s", nh_.resolveName("scan").c_str(),
           ground_frame_.c_str(), use_tf_ ? "" : " (tf off: fixed mount)");
}

HoughGroundRos::~HoughGroundRos() {
  input_.reset();  // no callback after this
}

sensor_msgs::PointCloud2ConstPtr HoughGroundRos::lastClassified() const {
  std::lock_guard<std::mutex> lock(last_mutex_);
  return last_classified_.lock();
}

bool HoughGroundRos::sensorPose(const sensor_msgs::LaserScan& msg, SensorPose* pose) {
  if (!use_tf_) {
    // A fixed mount: roll (pi/2 = the scan plane vertical, sensor y up) and pitch about the
    // ground frame's axes, sensor_height above the ground.
    Eigen::Isometry3f t = Eigen::Isometry3f::Identity();
    t.linear() = (Eigen::AngleAxisf(static_cast<float>(mount_pitch_), Eigen::Vector3f::UnitY()) *
                  Eigen::AngleAxisf(static_cast<float>(mount_roll_), Eigen::Vector3f::UnitX()))
                     .toRotationMatrix();
    t.translation() = Eigen::Vector3f(0.f, 0.f, sensor_height_);
    pose->sensor_to_ground = t;
    return true;
  }
  return sensorPoseFromTf(input_->buffer(), ground_frame_, msg.header, &health_, pose);
}

void HoughGroundRos::process(const sensor_msgs::LaserScanConstPtr& msg) {
  last_input_.store(msg.get());
  diagnostics_->tick();
  std::lock_guard<std::mutex> process_lock(process_mutex_);
  HoughGroundConfig config;
  if (reconfigure_->takeChanged(&config)) {
    hough_.setParams(toHoughGroundParams(config));
    sensor_height_ = static_cast<float>(config.sensor_height);
  }
  LaserScanView scan;
  scan.angle_min = msg->angle_min;
  scan.angle_increment = msg->angle_increment;
  scan.range_min = msg->range_min;
  scan.range_max = msg->range_max;
  scan.ranges = msg->ranges.data();
  scan.size = msg->ranges.size();
  // Intensities are optional; a mismatched array is ignored rather than trusted.
  scan.intensities = msg->intensities.size() == msg->ranges.size() ? msg->intensities.data() : nullptr;
  std::string error;
  if (!validateLaserScan(scan, &error)) {
    health_.error("unreadable scan", "frame '" + msg->header.frame_id + "': " + error);
    return;
  }
  SensorPose pose;
  if (!sensorPose(*msg, &pose)) return;

  const ros::WallTime start = ros::WallTime::now();
  if (!hough_.classify(scan, pose, &result_, &error)) {
    health_.error("unreadable scan", error);
    return;
  }
  health_.processed((ros::WallTime::now() - start).toSec());
  {
    std::lock_guard<std::mutex> lock(fit_mutex_);
    last_fit_ = result_.fit;
    if (!result_.fit.valid) ++scans_without_line_;
  }

  // The scan's returns as a cloud (scan frame, one point per return, NaN for no return), built
  // fresh: the input of the output builders.
  const bool want_cloud = ground_pub_.getNumSubscribers() > 0 ||
                          obstacles_pub_.getNumSubscribers() > 0 ||
                          classified_pub_.getNumSubscribers() > 0;
  if (want_cloud) {
    sensor_msgs::PointCloud2 points;
    points.header = msg->header;
    const CloudLayout layout = laserScanLayout(static_cast<uint32_t>(scan.size));
    applyLayout(layout, &points);
    points.is_dense = false;
    points.data.resize(static_cast<std::size_t>(layout.row_step));
    cloud_projector_.projectPacked(scan, points.data.data());
    CloudLayout view_layout;
    PointCloudView view;
    if (!viewOf(points, &view_layout, &view, &error)) {
      health_.error("internal error", "projected scan: " + error);
      return;
    }
    // Fresh messages, published as ConstPtr and never touched again.
    if (ground_pub_.getNumSubscribers() > 0) {
      ground_pub_.publish(sensor_msgs::PointCloud2ConstPtr(
          subsetCloud(points, view, result_.classification, kLabelGround)));
    }
    if (obstacles_pub_.getNumSubscribers() > 0) {
      obstacles_pub_.publish(sensor_msgs::PointCloud2ConstPtr(
          subsetCloud(points, view, result_.classification, kLabelObstacle)));
    }
    if (classified_pub_.getNumSubscribers() > 0) {
      sensor_msgs::PointCloud2ConstPtr classified = classifiedCloud(points, view, result_.classification);
      {
        std::lock_guard<std::mutex> lock(last_mutex_);
        last_classified_ = classified;
      }
      classified_pub_.publish(classified);
    }
  }
  publishLine(*msg, result_);
}

void HoughGroundRos::publishLine(const sensor_msgs::LaserScan& msg, const ScanGroundResult& result) {
  const GroundLineFit& f = result.fit;
  const std::string& frame = ground_frame_;
  if (fit_pub_.getNumSubscribers() > 0) {
    HoughGroundFitPtr out(new HoughGroundFit);
    out->header.stamp = msg.header.stamp;
    out->header.frame_id = frame;
    out->scan_frame = msg.header.frame_id;
    out->valid = f.valid;
    out->ground = f.ground;
    out->slope = f.slope;
    out->direction.x = result.direction.x();
    out->direction.y = result.direction.y();
    out->direction.z = 0.0;
    out->signed_r = result.signed_r;
    out->votes = f.votes;
    out->inliers = f.inliers;
    out->runner_up = f.runner_up;
    out->margin = f.margin;
    out->rms = f.rms;
    out->r_min = f.r_min;
    out->r_max = f.r_max;
    out->ground_returns = static_cast<int32_t>(result.classification.count(kLabelGround));
    out->obstacle_returns = static_cast<int32_t>(result.classification.count(kLabelObstacle));
    out->unknown_returns = static_cast<int32_t>(result.classification.count(kLabelUnknown));
    fit_pub_.publish(HoughGroundFitConstPtr(out));
  }
  if (line_pub_.getNumSubscribers() > 0) {
    visualization_msgs::MarkerPtr m(new visualization_msgs::Marker);
    m->header.stamp = msg.header.stamp;
    m->header.frame_id = frame;
    m->ns = "hough_ground/" + msg.header.frame_id;
    m->id = 0;
    m->type = visualization_msgs::Marker::LINE_STRIP;
    m->pose.orientation.w = 1.0;
    if (!f.valid) {
      m->action = visualization_msgs::Marker::DELETE;
    } else {
      m->action = visualization_msgs::Marker::ADD;
      m->scale.x = 0.05;
      m->color.r = 0.1f;
      m->color.g = 0.9f;
      m->color.b = 0.2f;
      m->color.a = 1.0f;
      m->lifetime = ros::Duration(0.5);
      // The fitted line over the extent of its inliers, at the ground frame's origin under the
      // sensor (the adapter zeroes the sensor's x, y offset).
      for (float r : {f.r_min, f.r_max}) {
        geometry_msgs::Point p;
        p.x = r * result.direction.x();
        p.y = r * result.direction.y();
        p.z = f.ground + f.slope * r;
        m->points.push_back(p);
      }
    }
    line_pub_.publish(visualization_msgs::MarkerConstPtr(m));
  }
}

void HoughGroundRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  health_.fillDiagnostics(status);
  status.add("method", reconfigure_->current().method);
  status.add("ground frame", use_tf_ ? ground_frame_ : std::string("(tf off)"));
  std::lock_guard<std::mutex> lock(fit_mutex_);
  status.add("last fit valid", last_fit_.valid);
  status.add("last Ground [m]", last_fit_.ground);
  status.add("last Slope", last_fit_.slope);
  status.add("last inliers", last_fit_.inliers);
  status.add("last margin", last_fit_.margin);
  status.add("scans without a ground line", scans_without_line_);
  if (health_.processedCount() > 0 && !last_fit_.valid &&
      status.level == diagnostic_msgs::DiagnosticStatus::OK) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no ground line in the last scan");
  }
}

}  // namespace ladar_perception
