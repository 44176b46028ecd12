#include "ladar_perception/calibration/experiment.h"

#include <algorithm>
#include <cmath>

#include "ladar_perception/sim/random.h"
#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/trajectory.h"

namespace ladar_perception {
namespace calibration {

const char* sensorKindName(SensorKind kind) {
  switch (kind) {
    case SensorKind::kVelodyne: return "velodyne";
    case SensorKind::kSick: return "sick";
    case SensorKind::kStereo: return "stereo";
  }
  return "?";
}

std::vector<std::string> pairNames() {
  return {"velodyne-velodyne", "sick-velodyne", "sick-sick", "stereo-velodyne", "velodyne-stereo"};
}

bool pairFromName(const std::string& name, PairSetup* out, std::string* error) {
  // Mounts: the reference 2 m above the ground at the origin, the target 1 m forward (5.2.1).
  // 2D ladars are tilted down to meet the ground about 10 m away, the stereo camera a little.
  const SensorSetup velodyne_ref{SensorKind::kVelodyne, makePose(0, 0, 2.0, 0, 0, 0)};
  const SensorSetup velodyne_tgt{SensorKind::kVelodyne, makePose(1.0, 0, 2.0, 0, 0, 0)};
  const SensorSetup sick_ref{SensorKind::kSick, makePose(0, 0, 2.0, 0, 0.2, 0)};
  const SensorSetup sick_tgt{SensorKind::kSick, makePose(1.0, 0, 2.0, 0, 0.2, 0)};
  const SensorSetup sick_tgt_side{SensorKind::kSick, makePose(1.0, 0, 2.0, 0, 0.25, 0.5)};
  const SensorSetup stereo_ref{SensorKind::kStereo, makePose(0, 0, 2.0, 0, 0.15, 0)};
  const SensorSetup stereo_tgt{SensorKind::kStereo, makePose(1.0, 0, 2.0, 0, 0.15, 0)};
  out->name = name;
  if (name == "velodyne-velodyne") {
    out->reference = velodyne_ref;
    out->target = velodyne_tgt;
  } else if (name == "sick-velodyne") {
    out->reference = velodyne_ref;
    out->target = sick_tgt;
  } else if (name == "sick-sick") {
    out->reference = sick_ref;
    out->target = sick_tgt_side;
  } else if (name == "stereo-velodyne") {
    out->reference = velodyne_ref;
    out->target = stereo_tgt;
  } else if (name == "velodyne-stereo") {
    out->reference = stereo_ref;
    out->target = velodyne_tgt;
  } else {
    if (error) {
      *error = "unknown sensor pair '" + name + "' (pairs:";
      for (const std::string& n : pairNames()) *error += " " + n;
      *error += ")";
    }
    return false;
  }
  return true;
}

void adaptParamsToPair(const PairSetup& pair, CalibrationParams* params) {
  if (pair.reference.kind == SensorKind::kStereo || pair.target.kind == SensorKind::kStereo) {
    params->refinement.reference_voxel = std::max(params->refinement.reference_voxel, 0.4);
  }
}

bool simulateSensor(const sim::World& world, const SensorSetup& sensor,
                    const Eigen::Isometry3d& vehicle_pose, sim::NoiseProfile noise, uint64_t seed,
                    PointVector* points, std::string* error) {
  const Eigen::Isometry3d pose = vehicle_pose * toIsometry(sensor.extrinsic);
  sim::SimulatedScan scan;
  const PackedCloud* cloud = &scan.cloud;
  sim::SimulatedLaserScan laser;
  switch (sensor.kind) {
    case SensorKind::kVelodyne:
      sim::simulateVelodyneRevolution(world, pose, sim::VelodyneModel::hdl64e(noise), seed, &scan);
      break;
    case SensorKind::kSick:
      sim::simulateSickScan(world, pose, sim::SickModel::lms291(noise), seed, &laser);
      cloud = &laser.points.cloud;
      break;
    case SensorKind::kStereo:
      sim::simulateStereoFrame(world, pose, sim::StereoModel::bumblebee(noise), seed, &scan);
      break;
  }
  PointCloudView view;
  if (!cloud->view(&view, error)) return false;
  pointsFromView(view, 0.0, 1e9, points);
  return true;
}

namespace {

// A slalom along the world's standard drive (start to end): at distance s along it, the vehicle
// is amplitude sin(2 pi s / wavelength) to the left, heading along the path (or against it when
// driving back).
struct Slalom {
  Eigen::Vector2d start, along, left;
  double length, heading, amplitude, k;
  Slalom(const sim::World& world, double amplitude_m, double wavelength)
      : amplitude(amplitude_m), k(2.0 * M_PI / wavelength) {
    start = world.drivePose(0.0).translation().head<2>();
    const Eigen::Vector2d end = world.drivePose(world.driveDuration()).translation().head<2>();
    length = std::max((end - start).norm(), 1.0);
    along = (end - start) / length;
    left = Eigen::Vector2d(-along.y(), along.x());
    heading = std::atan2(along.y(), along.x());
  }
  Eigen::Isometry3d pose(const sim::World& world, double s, bool back) const {
    const Eigen::Vector2d p = start + s * along + amplitude * std::sin(k * s) * left;
    const double slope = std::atan(amplitude * k * std::cos(k * s));
    const double yaw = back ? wrapAngle(heading + M_PI - slope) : heading + slope;
    return world.vehiclePose(p.x(), p.y(), yaw);
  }
};

}  // namespace

namespace {

// The vehicle poses of a trial (options.trajectory).
bool trialPoses(const sim::World& world, const ExperimentOptions& options, uint64_t seed,
                std::vector<Eigen::Isometry3d>* poses, std::string* error) {
  sim::RandomPoseOptions pose_options;
  pose_options.max_offset = options.max_offset;
  pose_options.centre_x = options.centre_x;
  pose_options.centre_y = options.centre_y;
  pose_options.max_yaw = options.max_yaw;
  if (options.trajectory == "turns") {
    if (world.driveDuration() <= 0.0 || options.poses < 2) {
      if (error) *error = "trajectory 'turns' needs a world with a standard drive and >= 2 poses";
      return false;
    }
    const Slalom slalom(world, options.turn_amplitude, options.turn_wavelength);
    for (int i = 0; i < options.poses; ++i) {
      poses->push_back(slalom.pose(world, slalom.length * i / (options.poses - 1), false));
    }
  } else if (options.trajectory != "thesis") {
    if (error) *error = "unknown trajectory '" + options.trajectory + "' (thesis, turns)";
    return false;
  } else if (options.max_lateral >= 0) {
    sim::Rng pose_rng(sim::mix64(seed ^ 0x905e5ULL));
    for (int k = 0; k < options.poses; ++k) {
      const double x = options.centre_x + pose_rng.uniform(-1.0, 1.0) * options.max_offset;
      const double y = options.centre_y + pose_rng.uniform(-1.0, 1.0) * options.max_lateral;
      const double yaw = pose_rng.uniform(-1.0, 1.0) * options.max_yaw;
      poses->push_back(world.vehiclePose(x, y, yaw));
    }
  } else {
    *poses = sim::randomVehiclePoses(world, options.poses, sim::mix64(seed ^ 0x905e5ULL),
                                     pose_options);
  }
  return true;
}

// Simulates every sensor along the poses: per pose, each sensor in turn (the random stream
// advances per scan in that order). A 2D ladar and the stereo camera keep their own rate along
// the drive to the next pose; the Velodyne scans once at each pose (the thesis's set-up).
bool simulateAlongPoses(const sim::World& world, const std::vector<const SensorSetup*>& sensors,
                        const std::vector<Eigen::Isometry3d>& poses,
                        const ExperimentOptions& options, uint64_t seed,
                        const std::vector<ScanSet*>& sets, std::string* error) {
  PointVector points;
  uint64_t stream = sim::mix64(seed);
  const double sick_rate = sim::SickModel::lms291(options.noise).rate_hz;
  const double stereo_rate = sim::StereoModel::bumblebee(options.noise).rate_hz;
  double segment_start = 0.0;  // [s]
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const bool last = k + 1 >= poses.size();
    const double length =
        last ? 0.0 : (poses[k + 1].translation() - poses[k].translation()).head<2>().norm();
    const double duration = options.drive_speed > 0 ? length / options.drive_speed : 0.1;
    for (std::size_t side = 0; side < sensors.size(); ++side) {
      const SensorSetup& s = *sensors[side];
      const bool sweep = s.kind == SensorKind::kSick ||
                         (s.kind == SensorKind::kStereo && options.stereo_while_driving);
      const double rate = s.kind == SensorKind::kSick ? sick_rate : stereo_rate;
      int repeats = 1;
      if (sweep) {
        repeats = options.drive_speed > 0
                      ? (last ? 1 : std::max(1, static_cast<int>(std::lround(duration * rate))))
                      : std::max(1, options.sick_scans_per_pose);
      }
      for (int r = 0; r < repeats; ++r) {
        Eigen::Isometry3d vehicle = poses[k];
        const double f = static_cast<double>(r) / repeats;
        if (sweep && !last) {  // driving from pose k towards pose k + 1
          const Eigen::Vector3d a = poses[k].translation(), b = poses[k + 1].translation();
          const double yaw_a = std::atan2(poses[k].linear()(1, 0), poses[k].linear()(0, 0));
          const double yaw_b = std::atan2(poses[k + 1].linear()(1, 0), poses[k + 1].linear()(0, 0));
          const Eigen::Vector3d p = a + f * (b - a);
          vehicle = world.vehiclePose(p.x(), p.y(), yaw_a + f * wrapAngle(yaw_b - yaw_a));
        }
        stream = sim::mix64(stream + 1);
        const sim::NoiseProfile noise =
            side == 0 && options.reference_noise_set ? options.reference_noise : options.noise;
        if (!simulateSensor(world, s, vehicle, noise, stream, &points, error)) return false;
        sets[side]->addScan(segment_start + (sweep ? r / rate : 0.0), vehicle, points);
      }
    }
    segment_start += duration;
  }
  return true;
}

// The initial guess: the truth off by up to +-guess_offset per axis.
Pose6 initialGuess(const Pose6& truth, const ExperimentOptions& options, uint64_t stream) {
  sim::Rng rng(stream);
  Pose6 guess = truth;
  for (int i = 0; i < 6; ++i) guess[i] += rng.uniform(-1.0, 1.0) * options.guess_offset[i];
  return guess;
}

}  // namespace

bool makeTrial(const sim::World& world, const PairSetup& pair, const ExperimentOptions& options,
               uint64_t seed, ExperimentTrial* out, std::string* error) {
  *out = ExperimentTrial();
  std::vector<Eigen::Isometry3d> poses;
  if (!trialPoses(world, options, seed, &poses, error)) return false;
  out->vehicle_poses.assign(poses.begin(), poses.end());
  out->truth = pair.target.extrinsic;
  out->initial_guess = initialGuess(out->truth, options, sim::mix64(seed ^ 0x6e55ULL));
  out->input.reference_extrinsic = toIsometry(pair.reference.extrinsic);
  return simulateAlongPoses(world, {&pair.reference, &pair.target}, poses, options, seed,
                            {&out->input.reference, &out->input.target}, error);
}

NetworkSetup thesisVehicleNetwork() {
  NetworkSetup n;
  n.name = "thesis-vehicle";
  const sim::SensorRig rig = sim::SensorRig::thesisVehicle();
  for (const sim::SensorMount& m : rig.sensors) {
    // The vehicle's 3D ladar is the reference; its two LMS-291 looking ahead and behind and its
    // stereo camera are the targets (the vertical LMS-291 sees the ground ahead only).
    if (m.name == "sick_vertical") continue;
    SensorSetup s;
    s.kind = m.kind == sim::SensorKind::kVelodyne ? SensorKind::kVelodyne
             : m.kind == sim::SensorKind::kSick   ? SensorKind::kSick
                                                  : SensorKind::kStereo;
    s.extrinsic = fromIsometry(m.base_to_sensor);
    if (s.kind == SensorKind::kVelodyne && n.reference_name.empty()) {
      n.reference_name = m.frame_id;
      n.reference = s;
    } else {
      n.target_names.push_back(m.frame_id);
      n.targets.push_back(s);
    }
  }
  return n;
}

bool makeNetworkTrial(const sim::World& world, const NetworkSetup& network,
                      const ExperimentOptions& options, uint64_t seed, NetworkTrial* out,
                      std::string* error) {
  *out = NetworkTrial();
  std::vector<Eigen::Isometry3d> poses;
  if (!trialPoses(world, options, seed, &poses, error)) return false;
  out->input.reference_name = network.reference_name;
  out->input.reference_extrinsic = toIsometry(network.reference.extrinsic);
  out->input.targets.resize(network.targets.size());
  std::vector<const SensorSetup*> sensors{&network.reference};
  std::vector<ScanSet*> sets{&out->input.reference};
  for (std::size_t t = 0; t < network.targets.size(); ++t) {
    NetworkTarget& target = out->input.targets[t];
    target.name = network.target_names[t];
    out->truth.push_back(network.targets[t].extrinsic);
    target.initial = initialGuess(network.targets[t].extrinsic, options,
                                  sim::mix64(seed ^ (0x6e55ULL + 0x1000ULL * t)));
    target.spread = options.guess_offset;
    if (network.targets[t].kind == SensorKind::kStereo) target.surface_voxel = 0.4;
    sensors.push_back(&network.targets[t]);
    sets.push_back(&target.scans);
  }
  return simulateAlongPoses(world, sensors, poses, options, seed, sets, error);
}

namespace {

// Back and forth along the world's drive, weaving +-1.5 m every 25 m.
Eigen::Isometry3d driftDrivePose(const sim::World& world, double distance) {
  const Slalom slalom(world, 1.5, 25.0);
  const double lap = std::fmod(distance, 2.0 * slalom.length);
  const bool back = lap > slalom.length;
  return slalom.pose(world, back ? 2.0 * slalom.length - lap : lap, back);
}

}  // namespace

bool runDriftDrive(const sim::World& world, const PairSetup& pair, const DriftMonitorParams& params,
                   const DriftDriveOptions& options, uint64_t seed, DriftDriveResult* out,
                   std::string* error, const std::function<void(const DriftCheck&)>& on_check) {
  *out = DriftDriveResult();
  if (world.driveDuration() <= 0.0 || !(options.scan_interval > 0.0) ||
      !(options.check_interval > 0.0)) {
    if (error) *error = "the drift drive needs a world with a standard drive and positive intervals";
    return false;
  }
  DriftMonitor monitor(params, toIsometry(pair.reference.extrinsic), pair.target.extrinsic);
  SensorSetup target = pair.target;
  PointVector points;
  double next_check = options.check_interval;
  double cpu_sum = 0;
  uint64_t stream = sim::mix64(seed);
  for (int step = 0;; ++step) {
    const double t = step * options.scan_interval;
    if (t > options.duration + 1e-9) break;
    const bool bumped = options.bump_time >= 0.0 && t >= options.bump_time;
    target.extrinsic = bumped ? Pose6(pair.target.extrinsic + options.bump) : pair.target.extrinsic;
    const Eigen::Isometry3d vehicle = driftDrivePose(world, options.speed * t);
    stream = sim::mix64(stream + 1);
    if (!simulateSensor(world, pair.reference, vehicle, options.noise, stream, &points, error)) return false;
    monitor.addReferenceScan(t, vehicle, points);
    stream = sim::mix64(stream + 1);
    if (!simulateSensor(world, target, vehicle, options.noise, stream, &points, error)) return false;
    monitor.addTargetScan(t, vehicle, points);
    if (t + 1e-9 < next_check) continue;
    next_check += options.check_interval;
    DriftCheck check;
    check.time = t;
    check.estimate = monitor.check();
    cpu_sum += check.estimate.cpu_time;
    out->max_check_cpu = std::max(out->max_check_cpu, check.estimate.cpu_time);
    if (!bumped) {
      out->warn_before += check.estimate.level == DriftLevel::kWarn;
      out->error_before += check.estimate.level == DriftLevel::kError;
    } else if (check.estimate.level == DriftLevel::kError && out->detected_after < 0) {
      out->detected_after = t - options.bump_time;
    }
    if (on_check) on_check(check);
    out->checks.push_back(check);
  }
  if (!out->checks.empty()) out->mean_check_cpu = cpu_sum / out->checks.size();
  return true;
}

}  // namespace calibration
}  // namespace ladar_perception
