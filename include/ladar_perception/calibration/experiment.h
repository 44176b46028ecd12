// The thesis's calibration experiment (5.2.1) on the simulator: vehicle poses drawn within 5 m
// and 0.5 rad of the origin, the reference sensor 2 m above the ground at the origin, the target
// 1 m forward, the initial guess off by up to +-1 m and +-0.2 rad per axis. Shared by
// calibration_benchmark, the tests and the rostest's data publisher.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ladar_perception/calibration/calibrator.h"
#include "ladar_perception/calibration/drift_monitor.h"
#include "ladar_perception/calibration/network.h"
#include "ladar_perception/sim/sensor_models.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace calibration {

enum class SensorKind { kVelodyne, kSick, kStereo };
const char* sensorKindName(SensorKind kind);

struct SensorSetup {
  SensorKind kind = SensorKind::kVelodyne;
  Pose6 extrinsic = Pose6::Zero();  // base_link -> sensor, the truth
};

// "target-reference" names: velodyne-velodyne, sick-velodyne (a SICK calibrated against a
// Velodyne), sick-sick, stereo-velodyne, velodyne-stereo.
struct PairSetup {
  std::string name;
  SensorSetup reference;
  SensorSetup target;
};
bool pairFromName(const std::string& name, PairSetup* out, std::string* error);
// The calibration's settings for a pair's sensor kinds: the refinement's surface voxel 0.4 m when
// one of them is a stereo camera (the 0.2 m default left the stereo camera 6-18 cm off along the
// direction of travel against a Table 4.1 Velodyne), else the defaults.
void adaptParamsToPair(const PairSetup& pair, CalibrationParams* params);
std::vector<std::string> pairNames();

struct ExperimentOptions {
  int poses = 10;
  double centre_x = 0.0;    // the poses are drawn around this point of the world [m]
  double centre_y = 0.0;
  double max_offset = 5.0;  // [m]
  double max_yaw = 0.5;     // [rad]
  // When >= 0: poses along a corridor instead of a disk, x within +-max_offset of the centre,
  // y within +-max_lateral, yaw within +-max_yaw (driving along an alley).
  double max_lateral = -1.0;
  // A 2D ladar sees one line per scan; it is accumulated while the vehicle drives from each pose
  // to the next (poses interpolated, straight segments). With drive_speed > 0 the vehicle drives
  // at that speed [m/s] and the ladar keeps its own rate (75 Hz for the LMS-291), so a segment of
  // length d gives round(d / drive_speed * 75) scans (at least one), and the last pose one scan;
  // with drive_speed <= 0, sick_scans_per_pose scans per segment. The 3D sensors scan once at
  // each pose (the thesis's 10 poses).
  double drive_speed = 2.0;
  // "thesis": the poses above (random within max_offset and max_yaw). "turns": the vehicle weaves
  // along the world's standard drive (start to end), a slalom of +-turn_amplitude metres with
  // turn_wavelength metres between its repeats, the poses evenly along it, heading along the
  // path: the sensors pass the scene's objects and turn (yaw up to ~0.56 rad at the defaults).
  std::string trajectory = "thesis";
  double turn_amplitude = 2.0;    // [m]
  double turn_wavelength = 20.0;  // [m]
  int sick_scans_per_pose = 20;
  // The stereo camera too frames at its own rate (10 Hz) along the drive, instead of once per
  // pose: a camera that looks forward sees the scene's faces from many places.
  bool stereo_while_driving = true;
  sim::NoiseProfile noise = sim::NoiseProfile::kTable41;
  // The reference sensor's noise instead of `noise` (experiments: which sensor's noise an error
  // comes from); the random streams are the same, so only the noise differs.
  bool reference_noise_set = false;
  sim::NoiseProfile reference_noise = sim::NoiseProfile::kTable41;
  Pose6 guess_offset = (Pose6() << 1.0, 1.0, 1.0, 0.2, 0.2, 0.2).finished();  // uniform +-
};

struct ExperimentTrial {
  CalibrationInput input;
  Pose6 truth = Pose6::Zero();
  Pose6 initial_guess = Pose6::Zero();
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> vehicle_poses;
};

// Simulates one trial (deterministic in `seed`).
bool makeTrial(const sim::World& world, const PairSetup& pair, const ExperimentOptions& options,
               uint64_t seed, ExperimentTrial* out, std::string* error);

// A network of sensors (network.h): the reference and the targets, with their true mounts.
struct NetworkSetup {
  std::string name;
  std::string reference_name;
  SensorSetup reference;
  std::vector<std::string> target_names;
  std::vector<SensorSetup> targets;
};
// The thesis vehicle (sim::SensorRig::thesisVehicle, config/sensors.yaml): the HDL-64E as the
// reference; the LMS-291 looking ahead, the one looking behind and the stereo camera as targets.
NetworkSetup thesisVehicleNetwork();

struct NetworkTrial {
  NetworkInput input;        // each target's initial guess off by up to +-guess_offset
  std::vector<Pose6> truth;  // per target
};

// Simulates one network trial along the trial's poses (deterministic in `seed`).
bool makeNetworkTrial(const sim::World& world, const NetworkSetup& network,
                      const ExperimentOptions& options, uint64_t seed, NetworkTrial* out,
                      std::string* error);

// One scan of a sensor at a vehicle pose, points in the sensor frame (the simulator's output
// read back through PointCloudView, as a driver's cloud would be).
bool simulateSensor(const sim::World& world, const SensorSetup& sensor,
                    const Eigen::Isometry3d& vehicle_pose, sim::NoiseProfile noise, uint64_t seed,
                    PointVector* points, std::string* error);

// The drift monitor's experiment (drift_monitor.h): the vehicle drives back and forth along the
// world's standard drive at `speed`, weaving +-1.5 m every 25 m; both sensors scan every
// scan_interval seconds, the monitor checks every check_interval; at bump_time the target's
// true mount moves by `bump` while the monitor keeps the configured one.
struct DriftDriveOptions {
  double duration = 60.0;       // [s]
  double speed = 1.5;           // [m/s]
  double scan_interval = 2.0;   // [s]
  double check_interval = 4.0;  // [s]
  double bump_time = -1.0;      // [s], < 0: no bump
  Pose6 bump = Pose6::Zero();
  sim::NoiseProfile noise = sim::NoiseProfile::kDatasheet;
};

struct DriftCheck {
  double time = 0;  // [s] of the drive
  DriftEstimate estimate;
};

struct DriftDriveResult {
  std::vector<DriftCheck> checks;
  int warn_before = 0, error_before = 0;  // checks at WARN / ERROR before the bump (false alarms)
  double detected_after = -1;             // [s] from the bump to the first ERROR; -1 never
  double max_check_cpu = 0, mean_check_cpu = 0;  // [s]
};

// `on_check`, when given, sees every check as it happens.
bool runDriftDrive(const sim::World& world, const PairSetup& pair, const DriftMonitorParams& params,
                   const DriftDriveOptions& options, uint64_t seed, DriftDriveResult* out,
                   std::string* error,
                   const std::function<void(const DriftCheck&)>& on_check = nullptr);

}  // namespace calibration
}  // namespace ladar_perception
