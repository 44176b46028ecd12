#include "ladar_perception/ros/vertical_scan_ground_ros.h"

#include <algorithm>
#include <exception>

#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

namespace {

// A table row's value between dynamic_reconfigure's field and the params' field (the ROS types
// double, int, bool and, for curb_policy, the string obstacle | ground).
void fromConfig(double c, float* p) { *p = static_cast<float>(c); }
void fromConfig(int c, int* p) { *p = c; }
void fromConfig(bool c, bool* p) { *p = c; }
void fromConfig(const std::string& c, int* p) { *p = c == "ground" ? kCurbGround : kCurbObstacle; }
void toConfig(float p, double* c) { *c = p; }
void toConfig(int p, int* c) { *c = p; }
void toConfig(bool p, bool* c) { *c = p; }
void toConfig(int p, std::string* c) { *c = p == kCurbGround ? "ground" : "obstacle"; }

}  // namespace

// Both directions are produced from the parameter table (vertical_scan_params.def).
VerticalScanParams toVerticalScanParams(const VerticalScanGroundConfig& c) {
  VerticalScanParams p =
      c.method == "thesis" ? verticalScanThesisParams() : verticalScanDefaultParams();
#define LADAR_PARAM(type, member, name, def, lo, hi, unit, meaning) fromConfig(c.name, &p.member);
#include "ladar_perception/ground/vertical_scan_params.def"
  return p;
}

void loadMethodSettings(const std::string& method, VerticalScanGroundConfig* c) {
  const VerticalScanParams p =
      method == "thesis" ? verticalScanThesisParams() : verticalScanDefaultParams();
#define LADAR_PARAM(type, member, name, def, lo, hi, unit, meaning) toConfig(p.member, &c->name);
#include "ladar_perception/ground/vertical_scan_params.def"
}

VerticalScanGroundRos::VerticalScanGroundRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), health_("VerticalScanGround") {
  ground_frame_ = private_nh_.param<std::string>("ground_frame", "base_footprint");
  use_tf_ = private_nh_.param("use_tf", true);
  mount_roll_deg_ = static_cast<float>(private_nh_.param("mount_roll_deg", 0.0));
  mount_pitch_deg_ = static_cast<float>(private_nh_.param("mount_pitch_deg", 0.0));
  // The sensor: ~laser_elevations_deg (a user's own table) over ~sensor_model (a name of the
  // lidar table); an unusable value is reported and the HDL-64E used.
  lidar_ = *findLidarModel("hdl64e");
  std::vector<double> elevations;
  const std::string sensor_model = private_nh_.param<std::string>("sensor_model", "hdl64e");
  if (private_nh_.getParam("laser_elevations_deg", elevations)) {
    std::string error;
    LidarModel custom;
    if (lidarModelFromElevations(std::vector<float>(elevations.begin(), elevations.end()), &custom, &error)) {
      lidar_ = custom;
    } else {
      health_.error("bad parameter", error + "; using sensor_model hdl64e");
    }
  } else if (const LidarModel* m = findLidarModel(sensor_model)) {
    lidar_ = *m;
  } else {
    health_.error("bad parameter", "sensor_model '" + sensor_model + "' is none of " + lidarModelNames() +
                                       "; using hdl64e");
  }
  const int queue_size = private_nh_.param("queue_size", 3);
  const double tf_tolerance = private_nh_.param("tf_tolerance", 0.0);

  ground_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("ground", 2);
  obstacles_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("obstacles", 2);
  classified_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("classified", 2);

  diagnostics_.reset(new AdapterDiagnostics(
      nh_, private_nh_, "VerticalScanGround", "vertical scan ground",
      private_nh_.param("expected_rate_min", 5.0), private_nh_.param("expected_rate_max", 20.0),
      [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); }));

  reconfigure_.reset(new MethodReconfigure<VerticalScanGroundConfig>(private_nh_, loadMethodSettings));

  // Subscribe last.
  input_.reset(new SensorInput<sensor_msgs::PointCloud2>(
      nh_, "points", use_tf_, ground_frame_, queue_size, tf_tolerance, &health_,
      [this](const sensor_msgs::PointCloud2ConstPtr& m) { process(m); }));
  ROS_INFO("VerticalScanGround: listening on %s, ground frame %s%s, sensor %s (%d beams)",
           nh_.resolveName("points").c_str(), ground_frame_.c_str(),
           use_tf_ ? "" : " (tf off: fixed sensor_height and mount)", lidar_.name.c_str(), lidar_.beams());
}

VerticalScanGroundRos::~VerticalScanGroundRos() {
  input_.reset();  // no callback after this
}

sensor_msgs::PointCloud2ConstPtr VerticalScanGroundRos::lastClassified() const {
  std::lock_guard<std::mutex> lock(last_mutex_);
  return last_classified_.lock();
}

std::unique_ptr<GroundModel> VerticalScanGroundRos::makeModel(const VerticalScanGroundConfig& config) {
  std::unique_ptr<GroundModel> model;
  if (config.method == "default" || config.method == "thesis") {
    if (config.curb_policy != "obstacle" && config.curb_policy != "ground") {
      health_.error("bad parameter", "curb_policy '" + config.curb_policy +
                                         "' is neither obstacle nor ground; curbs are obstacles");
    }
    model = makeVerticalScanModel(toVerticalScanParams(config));
  } else {
    // The thesis's baselines and the per-column Hough fit, with their own settings.
    std::string error;
    model = makeGroundModel(config.method, &error);
    if (!model) {
      health_.error("bad parameter", error + "; using the default method");
      model = makeVerticalScanModel(verticalScanDefaultParams());
    }
  }
  model->setLidarModel(lidar_);
  return model;
}

bool VerticalScanGroundRos::sensorPose(const sensor_msgs::PointCloud2& msg, SensorPose* pose) {
  if (!use_tf_) {
    *pose = SensorPose::fromMount(sensor_height_, mount_roll_deg_, mount_pitch_deg_);
    return true;
  }
  return sensorPoseFromTf(input_->buffer(), ground_frame_, msg.header, &health_, pose);
}

void VerticalScanGroundRos::process(const sensor_msgs::PointCloud2ConstPtr& msg) {
  last_input_.store(msg.get());
  diagnostics_->tick();
  std::lock_guard<std::mutex> process_lock(process_mutex_);
  VerticalScanGroundConfig config;
  const bool changed = reconfigure_->takeChanged(&config);
  if (changed || !model_) {
    if (!changed) config = reconfigure_->current();
    model_ = makeModel(config);
    sensor_height_ = static_cast<float>(config.sensor_height);
  }
  CloudLayout layout;
  PointCloudView view;
  std::string error;
  CloudError code = CloudError::kNone;
  if (!viewOf(*msg, &layout, &view, &error, &code)) {
    health_.error(std::string("unreadable cloud (") + cloudErrorName(code) + ")",
                  "frame '" + msg->header.frame_id + "': " + error);
    return;
  }
  // A cloud that cannot come from the configured sensor is still classified (rows from its
  // ring field or the nearest beam), and the mismatch reported.
  const std::string mismatch = checkCloudAgainstLidarModel(view, lidar_);
  if (!mismatch.empty()) health_.error("sensor model mismatch", mismatch);
  rows_from_.store(view.hasRing() ? ringSourceName(view.ringSource()) : "elevation table");
  SensorPose pose;
  if (!sensorPose(*msg, &pose)) return;

  const ros::WallTime start = ros::WallTime::now();
  model_->classify(view, pose, &result_);
  health_.processed((ros::WallTime::now() - start).toSec());

  // Fresh messages, published as ConstPtr and never touched again.
  if (ground_pub_.getNumSubscribers() > 0) {
    ground_pub_.publish(sensor_msgs::PointCloud2ConstPtr(subsetCloud(*msg, view, result_, kLabelGround)));
  }
  if (obstacles_pub_.getNumSubscribers() > 0) {
    obstacles_pub_.publish(
        sensor_msgs::PointCloud2ConstPtr(subsetCloud(*msg, view, result_, kLabelObstacle)));
  }
  if (classified_pub_.getNumSubscribers() > 0) {
    sensor_msgs::PointCloud2ConstPtr classified = classifiedCloud(*msg, view, result_);
    {
      std::lock_guard<std::mutex> lock(last_mutex_);
      last_classified_ = classified;
    }
    classified_pub_.publish(classified);
  }
}

void VerticalScanGroundRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  health_.fillDiagnostics(status);
  status.add("method", reconfigure_->current().method);
  status.add("sensor model", lidar_.name + " (" + std::to_string(lidar_.beams()) + " beams)");
  status.add("rows from", std::string(rows_from_.load()));
  status.add("ground frame", use_tf_ ? ground_frame_ : std::string("(tf off)"));
}

}  // namespace ladar_perception
