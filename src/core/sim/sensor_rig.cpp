#include "ladar_perception/sim/sensor_rig.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "ladar_perception/sim/random.h"

namespace ladar_perception {
namespace sim {

const char* sensorKindName(SensorKind kind) {
  switch (kind) {
    case SensorKind::kVelodyne: return "hdl64e";
    case SensorKind::kSick: return "lms291";
    case SensorKind::kStereo: return "stereo";
  }
  return "hdl64e";
}

double SensorMount::rateHz() const {
  switch (kind) {
    case SensorKind::kVelodyne: return velodyne.rate_hz;
    case SensorKind::kSick: return sick.rate_hz;
    case SensorKind::kStereo: return stereo.rate_hz;
  }
  return 0.0;
}

Eigen::Isometry3d poseFromXyzRpy(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = xyz;
  p.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return p;
}

Eigen::Vector3d rpyOf(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return Eigen::Vector3d(roll, pitch, yaw);
}

void SensorRig::setNoise(NoiseProfile profile) {
  for (SensorMount& s : sensors) {
    const LidarModel* lidar = findLidarModel(s.lidar_model);
    s.velodyne.noise_sigma = lidar ? VelodyneModel::fromLidarModel(*lidar, profile).noise_sigma
                                   : VelodyneModel::hdl64e(profile).noise_sigma;
    s.sick.noise_sigma = SickModel::lms291(profile).noise_sigma;
    s.stereo.noise_sigma = StereoModel::bumblebee(profile).noise_sigma;
  }
}

SensorRig SensorRig::thesisVehicle(NoiseProfile profile) {
  SensorRig rig;
  auto add = [&](const std::string& name, SensorKind kind, const std::string& topic,
                 const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
    SensorMount m;
    m.name = name;
    m.kind = kind;
    m.frame_id = name;
    m.topic = topic;
    m.truth_topic = topic + "_truth";
    m.base_to_sensor = poseFromXyzRpy(xyz, rpy);
    rig.sensors.push_back(m);
  };
  add("velodyne", SensorKind::kVelodyne, "velodyne_points", {0.0, 0.0, 1.9}, {0.0, 0.0, 0.0});
  // Tilted down to meet the ground 10 m ahead of / behind the sensor: pitch = atan(1.0 / 10).
  const double tilt = std::atan2(1.0, 10.0);
  add("sick_front", SensorKind::kSick, "sick_front/scan", {2.0, 0.0, 1.0}, {0.0, tilt, 0.0});
  add("sick_rear", SensorKind::kSick, "sick_rear/scan", {-2.0, 0.0, 1.0}, {0.0, tilt, M_PI});
  // Scanning the vertical plane through the vehicle's x axis.
  add("sick_vertical", SensorKind::kSick, "sick_vertical/scan", {1.6, 0.0, 1.7}, {M_PI / 2, 0.0, 0.0});
  add("stereo", SensorKind::kStereo, "stereo/points", {1.7, 0.0, 1.5}, {0.0, 0.2, 0.0});
  rig.setNoise(profile);
  return rig;
}

namespace {

bool readVector3(const YAML::Node& n, const char* key, Eigen::Vector3d* v, std::string* error,
                 const std::string& where) {
  const YAML::Node a = n[key];
  if (!a) {
    *v = Eigen::Vector3d::Zero();
    return true;
  }
  if (!a.IsSequence() || a.size() != 3) {
    *error = where + ": `" + key + "` must be a list of 3 numbers";
    return false;
  }
  *v = Eigen::Vector3d(a[0].as<double>(), a[1].as<double>(), a[2].as<double>());
  if (!v->allFinite()) {
    *error = where + ": `" + key + "` is not finite";
    return false;
  }
  return true;
}

template <typename T>
void readOptional(const YAML::Node& n, const char* key, T* value) {
  if (n[key]) *value = n[key].as<T>();
}

bool parseRoot(const YAML::Node& root, SensorRig* rig, std::string* error) {
  SensorRig out;
  readOptional(root, "odom_frame", &out.odom_frame);
  readOptional(root, "base_frame", &out.base_frame);
  NoiseProfile default_profile = NoiseProfile::kTable41;
  if (root["noise_profile"] &&
      !noiseProfileFromName(root["noise_profile"].as<std::string>(), &default_profile)) {
    *error = "unknown noise_profile '" + root["noise_profile"].as<std::string>() +
             "' (table4.1, datasheet, none)";
    return false;
  }
  const YAML::Node sensors = root["sensors"];
  if (!sensors || !sensors.IsSequence() || sensors.size() == 0) {
    *error = "needs a non-empty `sensors:` list";
    return false;
  }
  std::set<std::string> frames;
  for (std::size_t k = 0; k < sensors.size(); ++k) {
    const YAML::Node s = sensors[k];
    SensorMount m;
    readOptional(s, "name", &m.name);
    const std::string where = "sensor " + std::to_string(k) + (m.name.empty() ? "" : " (" + m.name + ")");
    if (m.name.empty()) {
      *error = where + ": needs a `name`";
      return false;
    }
    const std::string type = s["type"] ? s["type"].as<std::string>() : "";
    const LidarModel* lidar = findLidarModel(type == "velodyne" ? "hdl64e" : type);
    if (lidar) {
      m.kind = SensorKind::kVelodyne;
      m.lidar_model = lidar->name;
    }
    else if (type == "lms291" || type == "sick") m.kind = SensorKind::kSick;
    else if (type == "stereo") m.kind = SensorKind::kStereo;
    else {
      *error = where + ": unknown type '" + type + "' (" + lidarModelNames() + ", lms291, stereo)";
      return false;
    }
    m.frame_id = m.name;
    readOptional(s, "frame_id", &m.frame_id);
    m.topic = m.kind == SensorKind::kSick ? m.name + "/scan" : m.name + "/points";
    readOptional(s, "topic", &m.topic);
    m.truth_topic = m.topic + "_truth";
    readOptional(s, "truth_topic", &m.truth_topic);
    if (!frames.insert(m.frame_id).second || m.frame_id == out.base_frame || m.frame_id == out.odom_frame) {
      *error = where + ": frame_id '" + m.frame_id + "' is used twice";
      return false;
    }
    if (!s["xyz"]) {
      *error = where + ": needs its mount `xyz: [x, y, z]` (metres in " + out.base_frame + ")";
      return false;
    }
    Eigen::Vector3d xyz, rpy;
    if (!readVector3(s, "xyz", &xyz, error, where) || !readVector3(s, "rpy", &rpy, error, where)) {
      return false;
    }
    m.base_to_sensor = poseFromXyzRpy(xyz, rpy);
    NoiseProfile profile = default_profile;
    if (s["noise_profile"] && !noiseProfileFromName(s["noise_profile"].as<std::string>(), &profile)) {
      *error = where + ": unknown noise_profile";
      return false;
    }
    m.velodyne = lidar ? VelodyneModel::fromLidarModel(*lidar, profile) : VelodyneModel::hdl64e(profile);
    m.sick = SickModel::lms291(profile);
    m.stereo = StereoModel::bumblebee(profile);
    std::string invalid;
    switch (m.kind) {
      case SensorKind::kVelodyne:
        readOptional(s, "noise_sigma", &m.velodyne.noise_sigma);
        readOptional(s, "min_range", &m.velodyne.min_range);
        readOptional(s, "max_range", &m.velodyne.max_range);
        readOptional(s, "rate_hz", &m.velodyne.rate_hz);
        readOptional(s, "azimuth_steps", &m.velodyne.azimuth_steps);
        if (s["elevations_deg"]) m.velodyne.elevations_deg = s["elevations_deg"].as<std::vector<float>>();
        invalid = m.velodyne.validate();
        break;
      case SensorKind::kSick:
        readOptional(s, "noise_sigma", &m.sick.noise_sigma);
        readOptional(s, "min_range", &m.sick.min_range);
        readOptional(s, "max_range", &m.sick.max_range);
        readOptional(s, "rate_hz", &m.sick.rate_hz);
        readOptional(s, "angle_min", &m.sick.angle_min);
        readOptional(s, "angle_max", &m.sick.angle_max);
        readOptional(s, "angle_increment", &m.sick.angle_increment);
        invalid = m.sick.validate();
        break;
      case SensorKind::kStereo:
        readOptional(s, "noise_sigma", &m.stereo.noise_sigma);
        readOptional(s, "baseline", &m.stereo.baseline);
        readOptional(s, "disparity_step_px", &m.stereo.disparity_step_px);
        readOptional(s, "min_range", &m.stereo.min_range);
        readOptional(s, "max_range", &m.stereo.max_range);
        readOptional(s, "rate_hz", &m.stereo.rate_hz);
        readOptional(s, "horizontal_fov", &m.stereo.horizontal_fov);
        readOptional(s, "vertical_fov", &m.stereo.vertical_fov);
        readOptional(s, "columns", &m.stereo.columns);
        readOptional(s, "rows", &m.stereo.rows);
        invalid = m.stereo.validate();
        break;
    }
    if (!invalid.empty()) {
      *error = where + ": " + invalid;
      return false;
    }
    out.sensors.push_back(m);
  }
  *rig = out;
  return true;
}

}  // namespace

bool parseSensorRig(const std::string& yaml_text, SensorRig* rig, std::string* error) {
  std::string err;
  try {
    if (parseRoot(YAML::Load(yaml_text), rig, &err)) return true;
  } catch (const std::exception& e) {
    err = e.what();
  }
  if (error) *error = err;
  return false;
}

bool loadSensorRig(const std::string& path, SensorRig* rig, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    if (error) *error = "cannot open sensor rig " + path;
    return false;
  }
  std::stringstream text;
  text << in.rdbuf();
  std::string err;
  if (!parseSensorRig(text.str(), rig, &err)) {
    if (error) *error = path + ": " + err;
    return false;
  }
  return true;
}

std::string extrinsicsYaml(const SensorRig& rig, const std::string& world, uint64_t seed) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);  // round-trips doubles exactly
  y << YAML::Comment("True extrinsics of the simulated sensors (base_link -> sensor). Loadable as a sensor rig.");
  y << YAML::BeginMap;
  y << YAML::Key << "world" << YAML::Value << world;
  y << YAML::Key << "seed" << YAML::Value << seed;
  y << YAML::Key << "odom_frame" << YAML::Value << rig.odom_frame;
  y << YAML::Key << "base_frame" << YAML::Value << rig.base_frame;
  y << YAML::Key << "sensors" << YAML::Value << YAML::BeginSeq;
  for (const SensorMount& s : rig.sensors) {
    const Eigen::Vector3d t = s.base_to_sensor.translation();
    const Eigen::Vector3d rpy = rpyOf(s.base_to_sensor.linear());
    const Eigen::Quaterniond q(s.base_to_sensor.linear());
    y << YAML::BeginMap;
    y << YAML::Key << "name" << YAML::Value << s.name;
    y << YAML::Key << "type" << YAML::Value
      << (s.kind == SensorKind::kVelodyne ? s.lidar_model : std::string(sensorKindName(s.kind)));
    y << YAML::Key << "frame_id" << YAML::Value << s.frame_id;
    y << YAML::Key << "parent_frame" << YAML::Value << rig.base_frame;
    y << YAML::Key << "topic" << YAML::Value << s.topic;
    y << YAML::Key << "truth_topic" << YAML::Value << s.truth_topic;
    y << YAML::Key << "xyz" << YAML::Value << YAML::Flow << YAML::BeginSeq << t.x() << t.y() << t.z() << YAML::EndSeq;
    y << YAML::Key << "rpy" << YAML::Value << YAML::Flow << YAML::BeginSeq << rpy.x() << rpy.y() << rpy.z() << YAML::EndSeq;
    y << YAML::Key << "quaternion_xyzw" << YAML::Value << YAML::Flow << YAML::BeginSeq << q.x() << q.y()
      << q.z() << q.w() << YAML::EndSeq;
    switch (s.kind) {
      case SensorKind::kVelodyne:
        y << YAML::Key << "noise_sigma" << YAML::Value << s.velodyne.noise_sigma;
        y << YAML::Key << "min_range" << YAML::Value << s.velodyne.min_range;
        y << YAML::Key << "max_range" << YAML::Value << s.velodyne.max_range;
        y << YAML::Key << "rate_hz" << YAML::Value << s.velodyne.rate_hz;
        y << YAML::Key << "azimuth_steps" << YAML::Value << s.velodyne.azimuth_steps;
        break;
      case SensorKind::kSick:
        y << YAML::Key << "noise_sigma" << YAML::Value << s.sick.noise_sigma;
        y << YAML::Key << "min_range" << YAML::Value << s.sick.min_range;
        y << YAML::Key << "max_range" << YAML::Value << s.sick.max_range;
        y << YAML::Key << "rate_hz" << YAML::Value << s.sick.rate_hz;
        y << YAML::Key << "angle_min" << YAML::Value << s.sick.angle_min;
        y << YAML::Key << "angle_max" << YAML::Value << s.sick.angle_max;
        y << YAML::Key << "angle_increment" << YAML::Value << s.sick.angle_increment;
        break;
      case SensorKind::kStereo:
        y << YAML::Key << "noise_sigma" << YAML::Value << s.stereo.noise_sigma;
        y << YAML::Key << "min_range" << YAML::Value << s.stereo.min_range;
        y << YAML::Key << "max_range" << YAML::Value << s.stereo.max_range;
        y << YAML::Key << "rate_hz" << YAML::Value << s.stereo.rate_hz;
        y << YAML::Key << "horizontal_fov" << YAML::Value << s.stereo.horizontal_fov;
        y << YAML::Key << "vertical_fov" << YAML::Value << s.stereo.vertical_fov;
        y << YAML::Key << "columns" << YAML::Value << s.stereo.columns;
        y << YAML::Key << "rows" << YAML::Value << s.stereo.rows;
        break;
    }
    y << YAML::EndMap;
  }
  y << YAML::EndSeq << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

VehicleMotion VehicleMotion::driving(const World& world, const Trajectory& trajectory) {
  VehicleMotion m;
  m.world_ = &world;
  m.trajectory_ = trajectory;
  return m;
}

VehicleMotion VehicleMotion::holding(const std::vector<Eigen::Isometry3d>& poses, double hold) {
  VehicleMotion m;
  m.poses_ = poses;
  m.hold_ = hold > 0.0 ? hold : 1.0;
  return m;
}

Eigen::Isometry3d VehicleMotion::poseAt(double t) const {
  const double d = duration();
  if (loop && d > 0.0 && t >= d) t = std::fmod(t, d);
  if (!poses_.empty()) {
    const double k = std::floor(std::max(t, 0.0) / hold_);
    const std::size_t idx = static_cast<std::size_t>(std::min(k, static_cast<double>(poses_.size() - 1)));
    return poses_[idx];
  }
  if (!world_ || trajectory_.empty()) return Eigen::Isometry3d::Identity();
  double x, y, yaw;
  trajectory_.pose2d(t, &x, &y, &yaw);
  return world_->vehiclePose(x, y, yaw);
}

double VehicleMotion::duration() const {
  if (!poses_.empty()) return hold_ * static_cast<double>(poses_.size());
  return trajectory_.duration();
}

RigSimulator::RigSimulator(const World& world, const SensorRig& rig, const VehicleMotion& motion,
                           uint64_t seed)
    : world_(world), rig_(rig), motion_(motion), seed_(seed) {}

void RigSimulator::firings(double from, double to, std::vector<SensorFiring>* out) const {
  const std::size_t first = out->size();
  for (std::size_t s = 0; s < rig_.sensors.size(); ++s) {
    const double rate = rig_.sensors[s].rateHz();
    if (!(rate > 0.0) || !(to > from)) continue;
    // Firing k is at k / rate; the first k with k / rate >= from.
    uint64_t k = static_cast<uint64_t>(std::max(0.0, std::ceil(from * rate - 1e-9)));
    for (;; ++k) {
      const double t = static_cast<double>(k) / rate;
      if (t >= to) break;
      if (t >= from) out->push_back({t, s, k});
    }
  }
  std::stable_sort(out->begin() + static_cast<std::ptrdiff_t>(first), out->end(),
                   [](const SensorFiring& a, const SensorFiring& b) {
                     return a.time < b.time || (a.time == b.time && a.sensor < b.sensor);
                   });
}

Eigen::Isometry3d RigSimulator::sensorPose(std::size_t sensor, double t) const {
  return motion_.poseAt(t) * rig_.sensors[sensor].base_to_sensor;
}

void RigSimulator::simulate(const SensorFiring& firing, SensorOutput* out) const {
  const SensorMount& s = rig_.sensors[firing.sensor];
  const uint64_t seed = mix64(seed_ ^ mix64((static_cast<uint64_t>(firing.sensor) << 40) ^ firing.index));
  const Eigen::Isometry3d pose = sensorPose(firing.sensor, firing.time);
  switch (s.kind) {
    case SensorKind::kVelodyne:
      if (motion_distortion) {
        simulateVelodyneRevolution(world_, pose, sensorPose(firing.sensor, firing.time + s.velodyne.period()),
                                   s.velodyne, seed, &out->scan);
      } else {
        simulateVelodyneRevolution(world_, pose, s.velodyne, seed, &out->scan);
      }
      break;
    case SensorKind::kSick:
      simulateSickScan(world_, pose, s.sick, seed, &out->laser);
      break;
    case SensorKind::kStereo:
      simulateStereoFrame(world_, pose, s.stereo, seed, &out->scan);
      break;
  }
}

}  // namespace sim
}  // namespace ladar_perception
