// A simulated vehicle: sensor mounts (base_link -> sensor, from YAML), a vehicle motion, and
// the schedule of every sensor's firings. Shared by the ladar_simulate tool (rosbag) and the
// LadarSimulator nodelet (live), which only turn its outputs into messages.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/sensor_models.h"
#include "ladar_perception/sim/trajectory.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

enum class SensorKind { kVelodyne, kSick, kStereo };
const char* sensorKindName(SensorKind kind);  // "hdl64e", "lms291", "stereo"

struct SensorMount {
  std::string name;
  SensorKind kind = SensorKind::kVelodyne;
  std::string frame_id;     // tf child frame of base_link
  std::string topic;        // data topic (PointCloud2, or LaserScan for a SICK)
  std::string truth_topic;  // per-point SurfaceClass, same order as the data
  Eigen::Isometry3d base_to_sensor = Eigen::Isometry3d::Identity();  // sensor pose in base_link
  VelodyneModel velodyne = VelodyneModel::hdl64e();
  std::string lidar_model = "hdl64e";  // the Velodyne's name in the lidar table (its `type`)
  SickModel sick = SickModel::lms291();
  StereoModel stereo = StereoModel::bumblebee();

  double rateHz() const;
};

struct SensorRig {
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::vector<SensorMount> sensors;

  // The thesis vehicle (4.2.1): an HDL-64E on the roof 1.9 m up, two LMS-291 tilted down to
  // meet the ground about 10 m ahead and behind, one LMS-291 scanning a vertical plane, and a
  // stereo camera. config/sensors.yaml holds the same rig.
  static SensorRig thesisVehicle(NoiseProfile profile = NoiseProfile::kTable41);
  // Sets every sensor's noise sigma from a profile.
  void setNoise(NoiseProfile profile);
};

// Roll, pitch, yaw (radians) as tf's setRPY: R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Isometry3d poseFromXyzRpy(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy);
Eigen::Vector3d rpyOf(const Eigen::Matrix3d& R);

// Reads a rig (format of config/sensors.yaml). Unknown sensor types, missing poses, duplicate
// frames and invalid models are errors.
bool loadSensorRig(const std::string& path, SensorRig* rig, std::string* error);
bool parseSensorRig(const std::string& yaml_text, SensorRig* rig, std::string* error);

// The true extrinsics as YAML: the rig in the format loadSensorRig reads, with quaternions and
// the world, seed and noise profile added for reference.
std::string extrinsicsYaml(const SensorRig& rig, const std::string& world, uint64_t seed);

// Where base_link is over time.
class VehicleMotion {
 public:
  // Drives a trajectory on the world's ground (World::vehiclePose), t in [0, duration()].
  static VehicleMotion driving(const World& world, const Trajectory& trajectory);
  // Stands at each pose for `hold` seconds in turn (the thesis's random poses).
  static VehicleMotion holding(const std::vector<Eigen::Isometry3d>& poses, double hold);

  Eigen::Isometry3d poseAt(double t) const;
  double duration() const;

  // Start over at the end (t wraps modulo duration()) instead of stopping there.
  bool loop = false;

 private:
  const World* world_ = nullptr;
  Trajectory trajectory_;
  std::vector<Eigen::Isometry3d> poses_;
  double hold_ = 1.0;
};

// One firing of one sensor: firing `index` of sensor `sensor` at time index / rate.
struct SensorFiring {
  double time = 0.0;
  std::size_t sensor = 0;
  uint64_t index = 0;
};

// What a firing produces, in the sensor frame. Velodyne and stereo fill `scan`, a SICK fills
// `laser` (its returns are also in laser.points).
struct SensorOutput {
  SimulatedScan scan;
  SimulatedLaserScan laser;
};

class RigSimulator {
 public:
  // world, rig and motion must outlive the simulator.
  RigSimulator(const World& world, const SensorRig& rig, const VehicleMotion& motion, uint64_t seed);

  // Velodyne revolutions see the vehicle move during the revolution (off by default: each
  // revolution is taken from its start pose, the exact ground truth).
  bool motion_distortion = false;

  // Appends the firings with from <= time < to, in time order (ties by sensor order).
  void firings(double from, double to, std::vector<SensorFiring>* out) const;
  // Simulates one firing. Deterministic: a firing's noise depends on (seed, sensor, index).
  void simulate(const SensorFiring& firing, SensorOutput* out) const;

  Eigen::Isometry3d basePose(double t) const { return motion_.poseAt(t); }
  Eigen::Isometry3d sensorPose(std::size_t sensor, double t) const;
  const SensorRig& rig() const { return rig_; }
  const World& world() const { return world_; }

 private:
  const World& world_;
  const SensorRig& rig_;
  const VehicleMotion& motion_;
  uint64_t seed_;
};

}  // namespace sim
}  // namespace ladar_perception
