#include "ladar_perception/ros/vertical_scan_ground_ros.h"

#include <algorithm>
#include <exception>

#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {

VerticalScanParams toVerticalScanParams(const VerticalScanGroundConfig& c) {
  VerticalScanParams p =
      c.method == "thesis" ? verticalScanThesisParams() : verticalScanDefaultParams();
  p.column_width_deg = static_cast<float>(c.column_width_deg);
  p.min_range = static_cast<float>(c.min_range);
  p.max_range = static_cast<float>(c.max_range);
  p.ground_slope_min = static_cast<float>(c.ground_slope_min);
  p.ground_slope_max = static_cast<float>(c.ground_slope_max);
  p.iterations = c.iterations;
  p.weight_bias = static_cast<float>(c.weight_bias);
  p.tolerances.gnd_error_max_base = static_cast<float>(c.gnd_error_max_base);
  p.tolerances.gnd_error_max_per_m = static_cast<float>(c.gnd_error_max_per_m);
  p.tolerances.slope_error_max_base = static_cast<float>(c.slope_error_max_base);
  p.tolerances.slope_error_max_per_m = static_cast<float>(c.slope_error_max_per_m);
  p.tolerances.obstacle_threshold = static_cast<float>(c.obstacle_threshold);
  p.segment_length = static_cast<float>(c.segment_length);
  p.track_max_step = static_cast<float>(c.track_max_step);
  p.track_max_drop = static_cast<float>(c.track_max_drop);
  p.track_tolerance_per_m = static_cast<float>(c.track_tolerance_per_m);
  p.track_drop_per_m = static_cast<float>(c.track_drop_per_m);
  p.track_max_local_slope = static_cast<float>(c.track_max_local_slope);
  p.track_min_local_slope = static_cast<float>(c.track_min_local_slope);
  p.track_anchor_distance = static_cast<float>(c.track_anchor_distance);
  p.track_max_bend = static_cast<float>(c.track_max_bend);
  p.track_first_slope_max = static_cast<float>(c.track_first_slope_max);
  p.track_recover_distance = static_cast<float>(c.track_recover_distance);
  p.negative_gnd_error_max = static_cast<float>(c.negative_gnd_error_max);
  p.negative_support_distance = static_cast<float>(c.negative_support_distance);
  p.vertical_gnd_error_max = static_cast<float>(c.vertical_gnd_error_max);
  p.vertical_slope_max = static_cast<float>(c.vertical_slope_max);
  p.vertical_foot_slope = static_cast<float>(c.vertical_foot_slope);
  p.laser_neighbours = c.laser_neighbours;
  p.neighbour_cells_per_column = c.neighbour_cells_per_column;
  p.neighbour_max_dr = static_cast<float>(c.neighbour_max_dr);
  p.neighbour_spacing_fraction = static_cast<float>(c.neighbour_spacing_fraction);
  p.neighbour_min_step = static_cast<float>(c.neighbour_min_step);
  p.curb_policy = c.curb_policy == "ground" ? kCurbGround : kCurbObstacle;
  p.curb_max_height = static_cast<float>(c.curb_max_height);
  p.curb_max_depth = static_cast<float>(c.curb_max_depth);
  p.local_ground = c.local_ground;
  p.local_ground_cell = static_cast<float>(c.local_ground_cell);
  p.local_ground_columns = c.local_ground_columns;
  p.local_ground_rings = c.local_ground_rings;
  p.local_ground_min_returns = c.local_ground_min_returns;
  p.local_ground_below = static_cast<float>(c.local_ground_below);
  p.local_ground_above = static_cast<float>(c.local_ground_above);
  p.local_ground_face_dr = static_cast<float>(c.local_ground_face_dr);
  p.local_ground_face_height = static_cast<float>(c.local_ground_face_height);
  p.bend_ground_line = c.bend_ground_line;
  p.couple_columns = c.couple_columns;
  p.negative_obstacles = c.negative_obstacles;
  p.vertical_surfaces = c.vertical_surfaces;
  p.coupling_radius = c.coupling_radius;
  p.min_ground_returns = c.min_ground_returns;
  return p;
}

void loadMethodSettings(const std::string& method, VerticalScanGroundConfig* c) {
  const VerticalScanParams p =
      method == "thesis" ? verticalScanThesisParams() : verticalScanDefaultParams();
  c->column_width_deg = p.column_width_deg;
  c->min_range = p.min_range;
  c->max_range = p.max_range;
  c->ground_slope_min = p.ground_slope_min;
  c->ground_slope_max = p.ground_slope_max;
  c->iterations = p.iterations;
  c->weight_bias = p.weight_bias;
  c->gnd_error_max_base = p.tolerances.gnd_error_max_base;
  c->gnd_error_max_per_m = p.tolerances.gnd_error_max_per_m;
  c->slope_error_max_base = p.tolerances.slope_error_max_base;
  c->slope_error_max_per_m = p.tolerances.slope_error_max_per_m;
  c->obstacle_threshold = p.tolerances.obstacle_threshold;
  c->segment_length = p.segment_length;
  c->track_max_step = p.track_max_step;
  c->track_max_drop = p.track_max_drop;
  c->track_tolerance_per_m = p.track_tolerance_per_m;
  c->track_drop_per_m = p.track_drop_per_m;
  c->track_max_local_slope = p.track_max_local_slope;
  c->track_min_local_slope = p.track_min_local_slope;
  c->track_anchor_distance = p.track_anchor_distance;
  c->track_max_bend = p.track_max_bend;
  c->track_first_slope_max = p.track_first_slope_max;
  c->track_recover_distance = p.track_recover_distance;
  c->negative_gnd_error_max = p.negative_gnd_error_max;
  c->negative_support_distance = p.negative_support_distance;
  c->vertical_gnd_error_max = p.vertical_gnd_error_max;
  c->vertical_slope_max = p.vertical_slope_max;
  c->vertical_foot_slope = p.vertical_foot_slope;
  c->laser_neighbours = p.laser_neighbours;
  c->neighbour_cells_per_column = p.neighbour_cells_per_column;
  c->neighbour_max_dr = p.neighbour_max_dr;
  c->neighbour_spacing_fraction = p.neighbour_spacing_fraction;
  c->neighbour_min_step = p.neighbour_min_step;
  c->curb_policy = p.curb_policy == kCurbGround ? "ground" : "obstacle";
  c->curb_max_height = p.curb_max_height;
  c->curb_max_depth = p.curb_max_depth;
  c->local_ground = p.local_ground;
  c->local_ground_cell = p.local_ground_cell;
  c->local_ground_columns = p.local_ground_columns;
  c->local_ground_rings = p.local_ground_rings;
  c->local_ground_min_returns = p.local_ground_min_returns;
  c->local_ground_below = p.local_ground_below;
  c->local_ground_above = p.local_ground_above;
  c->local_ground_face_dr = p.local_ground_face_dr;
  c->local_ground_face_height = p.local_ground_face_height;
  c->bend_ground_line = p.bend_ground_line;
  c->couple_columns = p.couple_columns;
  c->negative_obstacles = p.negative_obstacles;
  c->vertical_surfaces = p.vertical_surfaces;
  c->coupling_radius = p.coupling_radius;
  c->min_ground_returns = p.min_ground_returns;
}

VerticalScanGroundRos::VerticalScanGroundRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), health_("VerticalScanGround") {
  ground_frame_ = private_nh_.param<std::string>("ground_frame", "base_footprint");
  use_tf_ = private_nh_.param("use_tf", true);
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
  ROS_INFO("VerticalScanGround: listening on %s, ground frame %s%s",
           nh_.resolveName("points").c_str(), ground_frame_.c_str(),
           use_tf_ ? "" : " (tf off: fixed sensor_height)");
}

VerticalScanGroundRos::~VerticalScanGroundRos() {
  input_.reset();  // no callback after this
}

sensor_msgs::PointCloud2ConstPtr VerticalScanGroundRos::lastClassified() const {
  std::lock_guard<std::mutex> lock(last_mutex_);
  return last_classified_.lock();
}

std::unique_ptr<GroundModel> VerticalScanGroundRos::makeModel(const VerticalScanGroundConfig& config) {
  if (config.method == "default" || config.method == "thesis") {
    if (config.curb_policy != "obstacle" && config.curb_policy != "ground") {
      health_.error("bad parameter", "curb_policy '" + config.curb_policy +
                                         "' is neither obstacle nor ground; curbs are obstacles");
    }
    return makeVerticalScanModel(toVerticalScanParams(config));
  }
  // The thesis's baselines and the per-column Hough fit, with their own settings.
  std::string error;
  std::unique_ptr<GroundModel> model = makeGroundModel(config.method, &error);
  if (!model) {
    health_.error("bad parameter", error + "; using the default method");
    model = makeVerticalScanModel(verticalScanDefaultParams());
  }
  return model;
}

bool VerticalScanGroundRos::sensorPose(const sensor_msgs::PointCloud2& msg, SensorPose* pose) {
  if (!use_tf_) {
    *pose = SensorPose::fromHeight(sensor_height_);
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
  status.add("ground frame", use_tf_ ? ground_frame_ : std::string("(tf off)"));
}

}  // namespace ladar_perception
