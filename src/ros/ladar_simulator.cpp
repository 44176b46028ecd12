#include "ladar_perception/ros/ladar_simulator.h"

#include <algorithm>
#include <cmath>

#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/ros/ladar_simulator_messages.h"

namespace ladar_perception {

namespace {
// Work through at most this much simulated backlog; older firings are skipped (and counted).
constexpr double kMaxBacklog = 1.0;
}  // namespace

LadarSimulatorRos::LadarSimulatorRos(ros::NodeHandle nh, ros::NodeHandle private_nh,
                                     const std::string& name)
    : nh_(nh), pnh_(private_nh), name_(name), diagnostics_(nh, private_nh) {
  diagnostics_.setHardwareID("ladar_simulator");
  diagnostics_.add("simulation", this, &LadarSimulatorRos::diagnose);
  try {
    ok_ = configure(&error_);
  } catch (const std::exception& e) {
    ok_ = false;
    error_ = e.what();
  }
  if (!ok_) {
    ROS_ERROR_STREAM(name_ << ": simulator not started: " << error_);
    diagnostics_.force_update();
    return;
  }
  // Advertise first; the timer starts publishing once everything exists.
  for (const sim::SensorMount& s : rig_.sensors) {
    if (s.kind == sim::SensorKind::kSick) {
      data_pubs_.push_back(nh_.advertise<sensor_msgs::LaserScan>(s.topic, 10));
    } else {
      data_pubs_.push_back(nh_.advertise<sensor_msgs::PointCloud2>(s.topic, 4));
    }
    truth_pubs_.push_back(publish_truth_ ? nh_.advertise<sensor_msgs::PointCloud2>(s.truth_topic, 10)
                                         : ros::Publisher());
  }
  if (publish_clock_) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  tf_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  static_tf_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  wall_start_ = ros::WallTime::now();
  if (publish_clock_) {
    stamp_origin_ = ros::Time(wall_start_.sec, wall_start_.nsec);
    rosgraph_msgs::Clock c;
    c.clock = stamp_origin_;
    clock_pub_.publish(c);
  }
  timer_ = nh_.createWallTimer(ros::WallDuration(0.005), &LadarSimulatorRos::onTimer, this);
  ROS_INFO_STREAM(name_ << ": simulating world '" << world_.name() << "' with " << rig_.sensors.size()
                        << " sensors, drive of " << motion_.duration() << " s");
}

LadarSimulatorRos::~LadarSimulatorRos() { timer_.stop(); }

bool LadarSimulatorRos::configure(std::string* error) {
  std::string world_name, world_image, class_image, sensors_file, noise, trajectory_file;
  int seed = 1, random_poses = 0;
  double pose_hold = 1.0;
  bool loop = true, motion_distortion = false;
  pnh_.param<std::string>("world", world_name, "urban");
  pnh_.param<std::string>("world_image", world_image, "");
  pnh_.param<std::string>("class_image", class_image, "");
  pnh_.param<int>("seed", seed, 1);
  pnh_.param<std::string>("sensors_file", sensors_file, "");
  pnh_.param<std::string>("noise_profile", noise, "");
  pnh_.param<std::string>("trajectory_file", trajectory_file, "");
  pnh_.param<int>("random_poses", random_poses, 0);
  pnh_.param<double>("pose_hold", pose_hold, 1.0);
  pnh_.param<bool>("loop", loop, true);
  pnh_.param<double>("real_time_factor", real_time_factor_, 1.0);
  pnh_.param<bool>("publish_clock", publish_clock_, false);
  pnh_.param<bool>("publish_truth", publish_truth_, true);
  pnh_.param<bool>("motion_distortion", motion_distortion, false);
  pnh_.param<double>("tf_rate", tf_rate_, 50.0);
  if (seed < 0) {
    *error = "~seed must be >= 0";
    return false;
  }
  if (!(real_time_factor_ > 0.0) || real_time_factor_ > 100.0) {
    *error = "~real_time_factor must be in (0, 100]";
    return false;
  }
  if (!(tf_rate_ > 0.0) || tf_rate_ > 1000.0) {
    *error = "~tf_rate must be in (0, 1000]";
    return false;
  }
  seed_ = static_cast<uint32_t>(seed);
  if (!world_image.empty()) {
    sim::ImageWorldOptions io;
    pnh_.param<double>("metres_per_pixel", io.metres_per_pixel, io.metres_per_pixel);
    pnh_.param<double>("height_scale", io.height_scale, io.height_scale);
    if (!sim::World::fromImage(world_image, class_image, io, &world_, error)) return false;
  } else if (!sim::makeStandardWorld(world_name, seed_, &world_, error)) {
    return false;
  }
  rig_ = sim::SensorRig::thesisVehicle();
  if (!sensors_file.empty() && !sim::loadSensorRig(sensors_file, &rig_, error)) return false;
  if (!noise.empty()) {
    sim::NoiseProfile profile;
    if (!sim::noiseProfileFromName(noise, &profile)) {
      *error = "unknown ~noise_profile '" + noise + "' (table4.1, datasheet, none)";
      return false;
    }
    rig_.setNoise(profile);
  }
  if (random_poses > 0) {
    if (!(pose_hold > 0.0)) {
      *error = "~pose_hold must be positive";
      return false;
    }
    motion_ = sim::VehicleMotion::holding(sim::randomVehiclePoses(world_, random_poses, seed_), pose_hold);
  } else {
    sim::Trajectory trajectory = world_.standardDrive();
    if (!trajectory_file.empty() && !sim::loadTrajectoryYaml(trajectory_file, &trajectory, error)) return false;
    if (trajectory.empty()) {
      *error = "the world has no standard drive: set ~trajectory_file or ~random_poses";
      return false;
    }
    motion_ = sim::VehicleMotion::driving(world_, trajectory);
  }
  motion_.loop = loop;
  simulator_ = std::make_unique<sim::RigSimulator>(world_, rig_, motion_, seed_);
  simulator_->motion_distortion = motion_distortion;
  pnh_.setParam("true_extrinsics", sim::extrinsicsYaml(rig_, world_.name(), seed_));
  return true;
}

ros::Time LadarSimulatorRos::stampAt(double t) const { return stamp_origin_ + ros::Duration(t); }

void LadarSimulatorRos::onTimer(const ros::WallTimerEvent&) {
  try {
    if (stamp_origin_.isZero()) {
      // Without our own clock, stamps follow ROS time (wall, or someone else's /clock).
      const ros::Time now = ros::Time::now();
      if (now.isZero()) return;  // use_sim_time and no clock yet
      stamp_origin_ = now;
      wall_start_ = ros::WallTime::now();
      static_tf_->sendTransform(simStaticTransforms(rig_, stamp_origin_).transforms);
    } else if (simulated_ == 0.0 && tf_index_ == 0) {
      static_tf_->sendTransform(simStaticTransforms(rig_, stamp_origin_).transforms);
    }
    double now_sim = (ros::WallTime::now() - wall_start_).toSec() * real_time_factor_;
    if (!motion_.loop) now_sim = std::min(now_sim, motion_.duration());
    lag_ = now_sim - simulated_;
    if (lag_ > kMaxBacklog) {
      // Cannot keep up: skip the backlog instead of falling further behind.
      std::vector<sim::SensorFiring> dropped;
      simulator_->firings(simulated_, now_sim - 0.1, &dropped);
      skipped_ += dropped.size();
      simulated_ = now_sim - 0.1;
      tf_index_ = static_cast<uint64_t>(std::ceil(simulated_ * tf_rate_ - 1e-9));
      ROS_WARN_STREAM_THROTTLE(5.0, name_ << ": simulation falls behind real time; skipped "
                                          << skipped_ << " firings so far (lower ~real_time_factor)");
    }
    if (now_sim > simulated_) step(now_sim);
    diagnostics_.update();
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM_THROTTLE(5.0, name_ << ": simulation step failed: " << e.what());
  }
}

void LadarSimulatorRos::step(double to) {
  firings_.clear();
  simulator_->firings(simulated_, to, &firings_);
  std::size_t next = 0;
  FiringMessages msgs;
  for (;;) {
    const double tf_time = static_cast<double>(tf_index_) / tf_rate_;
    const bool tf_due = tf_time < to;
    const bool firing_due = next < firings_.size();
    if (!tf_due && !firing_due) break;
    if (tf_due && (!firing_due || tf_time <= firings_[next].time)) {
      if (publish_clock_) {
        rosgraph_msgs::Clock c;
        c.clock = stampAt(tf_time);
        clock_pub_.publish(c);
      }
      tf_->sendTransform(simTransform(simulator_->basePose(tf_time), rig_.odom_frame, rig_.base_frame,
                                      stampAt(tf_time)));
      ++tf_index_;
      continue;
    }
    const sim::SensorFiring& f = firings_[next++];
    const bool want_data = data_pubs_[f.sensor].getNumSubscribers() > 0;
    const bool want_truth = publish_truth_ && truth_pubs_[f.sensor].getNumSubscribers() > 0;
    if (!want_data && !want_truth) continue;  // nobody listens: do not ray trace
    simulator_->simulate(f, &output_);
    simFiringMessages(rig_.sensors[f.sensor], output_, stampAt(f.time), want_truth, &msgs);
    if (want_data) {
      if (msgs.scan) data_pubs_[f.sensor].publish(sensor_msgs::LaserScanConstPtr(msgs.scan));
      if (msgs.cloud) data_pubs_[f.sensor].publish(sensor_msgs::PointCloud2ConstPtr(msgs.cloud));
    }
    if (want_truth && msgs.truth) truth_pubs_[f.sensor].publish(sensor_msgs::PointCloud2ConstPtr(msgs.truth));
    ++published_scans_;
  }
  simulated_ = to;
}

void LadarSimulatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  if (!ok_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, error_);
    return;
  }
  if (skipped_ > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "falling behind real time, firings skipped");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "simulating");
  }
  status.add("world", world_.name());
  status.add("simulated seconds", simulated_);
  status.add("lag seconds", lag_);
  status.add("scans published", published_scans_);
  status.add("firings skipped", skipped_);
}

}  // namespace ladar_perception
