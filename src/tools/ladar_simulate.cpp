// ladar_simulate: ray traces the simulated vehicle's sensors through a world along a trajectory
// and writes a rosbag (thesis 4.2.1), the true extrinsics as YAML and, on request, a top-down
// picture of the world with the trajectory.
//
//   rosrun ladar_perception ladar_simulate --world urban --duration 20 --out urban.bag
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include "ladar_perception/io/image.h"
#include "ladar_perception/ros/ladar_simulator_messages.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/world.h"
#include "ladar_perception/sim/world_image.h"

namespace {

using namespace ladar_perception;

const char* kUsage = R"(usage: ladar_simulate [options] --out BAG
World (one of):
  --world NAME             standard world: thesis urban rural hillside potholes alley flat (default urban)
  --world-image IMAGE      height image (PGM/PNG, black = high) with
    --class-image IMAGE      optional class image (gray = class code, or the class palette)
    --metres-per-pixel M     default 0.1
    --height-scale M         height of black, default 2.0
  --seed N                 world and noise seed (default 1)
Vehicle (default: the world's standard drive):
  --trajectory YAML        `waypoints: [[x, y], ...]` and `speed: m/s` (config/sim_*.yaml)
  --random-poses N         the thesis experiment: N poses within --pose-radius (5 m) and
                           --pose-yaw (0.5 rad) of the origin, each held --pose-hold s (1.0)
  --loop                   restart the drive when it ends (with --duration longer than it)
Sensors:
  --sensors YAML           sensor rig (default: the thesis vehicle = config/sensors.yaml)
  --sensor NAME            every Velodyne of the rig becomes this lidar (hdl64e hdl32e vlp16 vlp32c
                           os1_32 os1_64 os1_128 os2_128; Ouster models publish organised clouds)
  --sensor-height M        ... mounted M above base_link (default: the model's usual height)
  --noise PROFILE          table4.1 (default) | datasheet | none, for every sensor
  --velodyne-sigma M       range noise of the Velodyne(s), metres (after --noise)
  --velodyne-max-range M   Velodyne max range (Table 4.1: 60 m; the unit reaches 120 m)
  --motion-distortion      Velodyne points move with the vehicle during a revolution
Output:
  --out BAG                the rosbag
  --duration S             simulated seconds (default: the whole drive / all poses)
  --extrinsics YAML        true extrinsics (default: BAG with .extrinsics.yaml)
  --no-truth               leave out the ground-truth topics
  --tf-rate HZ             odom -> base_link rate (default 50)
  --start-time SEC         stamp of simulation time 0 (default 1700000000)
  --compression C          none (default) | lz4 | bz2
  --png IMAGE              top-down picture of the world and the trajectory
  --png-only               write only the picture (no --out needed)
)";

struct Args {
  std::map<std::string, std::string> values;
  bool has(const std::string& k) const { return values.count(k) > 0; }
  std::string get(const std::string& k, const std::string& d = "") const {
    auto it = values.find(k);
    return it == values.end() ? d : it->second;
  }
};

bool parseArgs(int argc, char** argv, Args* args, std::string* error) {
  static const char* kFlags[] = {"--loop", "--motion-distortion", "--no-truth", "--png-only", "--help", "-h"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    bool flag = false;
    for (const char* f : kFlags) flag |= a == f;
    if (flag) {
      args->values[a] = "1";
      continue;
    }
    if (a.rfind("--", 0) != 0 || i + 1 >= argc) {
      *error = "unexpected argument '" + a + "'";
      return false;
    }
    args->values[a] = argv[++i];
  }
  static const char* kKnown[] = {"--world", "--world-image", "--class-image", "--metres-per-pixel",
                                 "--height-scale", "--seed", "--trajectory", "--random-poses",
                                 "--pose-radius", "--pose-yaw", "--pose-hold", "--loop", "--sensors", "--sensor", "--sensor-height",
                                 "--noise", "--velodyne-sigma", "--velodyne-max-range", "--motion-distortion", "--out", "--duration",
                                 "--extrinsics", "--no-truth", "--tf-rate", "--start-time",
                                 "--compression", "--png", "--png-only", "--help", "-h"};
  for (const auto& kv : args->values) {
    bool known = false;
    for (const char* k : kKnown) known |= kv.first == k;
    if (!known) {
      *error = "unknown option " + kv.first;
      return false;
    }
  }
  return true;
}

bool toDouble(const std::string& s, double* v) {
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return !s.empty() && end && *end == '\0' && std::isfinite(*v);
}

int fail(const std::string& message) {
  std::cerr << "ladar_simulate: " << message << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  std::string error;
  if (!parseArgs(argc, argv, &args, &error)) return fail(error + "\n" + kUsage);
  if (args.has("--help") || args.has("-h")) {
    std::cout << kUsage;
    return 0;
  }
  auto number = [&](const std::string& key, double fallback, double* out) {
    if (!args.has(key)) {
      *out = fallback;
      return true;
    }
    if (!toDouble(args.get(key), out)) {
      error = key + " needs a number, got '" + args.get(key) + "'";
      return false;
    }
    return true;
  };

  // --- World.
  double seed_d = 1;
  if (!number("--seed", 1, &seed_d) || seed_d < 0) return fail(error.empty() ? "--seed must be >= 0" : error);
  const uint32_t seed = static_cast<uint32_t>(seed_d);
  sim::World world;
  std::string world_name;
  if (args.has("--world-image")) {
    sim::ImageWorldOptions io;
    if (!number("--metres-per-pixel", io.metres_per_pixel, &io.metres_per_pixel) ||
        !number("--height-scale", io.height_scale, &io.height_scale)) {
      return fail(error);
    }
    if (!sim::World::fromImage(args.get("--world-image"), args.get("--class-image"), io, &world, &error)) {
      return fail(error);
    }
    world_name = args.get("--world-image");
  } else {
    world_name = args.get("--world", "urban");
    if (!sim::makeStandardWorld(world_name, seed, &world, &error)) return fail(error);
  }

  // --- Vehicle motion.
  sim::VehicleMotion motion;
  std::vector<Eigen::Vector2d> path;
  std::vector<Eigen::Isometry3d> held;
  if (args.has("--random-poses")) {
    double n = 0, hold = 1.0;
    sim::RandomPoseOptions po;
    if (!number("--random-poses", 0, &n) || n < 1 || !number("--pose-hold", 1.0, &hold) || hold <= 0 ||
        !number("--pose-radius", po.max_offset, &po.max_offset) || !number("--pose-yaw", po.max_yaw, &po.max_yaw)) {
      return fail(error.empty() ? "--random-poses needs N >= 1 and --pose-hold > 0" : error);
    }
    held = sim::randomVehiclePoses(world, static_cast<int>(n), seed, po);
    motion = sim::VehicleMotion::holding(held, hold);
  } else {
    sim::Trajectory trajectory = world.standardDrive();
    if (args.has("--trajectory") && !sim::loadTrajectoryYaml(args.get("--trajectory"), &trajectory, &error)) {
      return fail(error);
    }
    if (trajectory.empty()) {
      return fail("world '" + world_name + "' has no standard drive: give --trajectory or --random-poses");
    }
    path = trajectory.waypoints();
    motion = sim::VehicleMotion::driving(world, trajectory);
  }
  motion.loop = args.has("--loop");

  // --- Picture.
  if (args.has("--png")) {
    const RgbImage image = sim::renderTopDown(world, path, held);
    if (!writePng(args.get("--png"), image, &error)) return fail(error);
    std::cout << "wrote " << args.get("--png") << " (" << image.width << " x " << image.height << ")\n";
  }
  if (args.has("--png-only")) return args.has("--png") ? 0 : fail("--png-only needs --png IMAGE");

  // --- Sensors.
  sim::SensorRig rig = sim::SensorRig::thesisVehicle();
  if (args.has("--sensors") && !sim::loadSensorRig(args.get("--sensors"), &rig, &error)) return fail(error);
  if (args.has("--sensor") || args.has("--sensor-height")) {
    const LidarModel* lidar = findLidarModel(args.get("--sensor", "hdl64e"));
    if (!lidar) return fail("unknown --sensor '" + args.get("--sensor") + "' (" + lidarModelNames() + ")");
    double height = lidar->name == "hdl64e" ? 1.9 : lidar->mount_height;
    if (!number("--sensor-height", height, &height)) return fail(error);
    if (!(height > 0.0)) return fail("--sensor-height must be positive");
    for (sim::SensorMount& s : rig.sensors) {
      if (s.kind != sim::SensorKind::kVelodyne) continue;
      s.lidar_model = lidar->name;
      s.velodyne = sim::VelodyneModel::fromLidarModel(*lidar, sim::NoiseProfile::kTable41);
      s.base_to_sensor.translation().z() = height;
    }
  }
  if (args.has("--noise")) {
    sim::NoiseProfile profile;
    if (!sim::noiseProfileFromName(args.get("--noise"), &profile)) {
      return fail("unknown --noise '" + args.get("--noise") + "' (table4.1, datasheet, none)");
    }
    rig.setNoise(profile);
  }
  for (sim::SensorMount& s : rig.sensors) {
    if (s.kind != sim::SensorKind::kVelodyne) continue;
    if (!number("--velodyne-sigma", s.velodyne.noise_sigma, &s.velodyne.noise_sigma) ||
        !number("--velodyne-max-range", s.velodyne.max_range, &s.velodyne.max_range)) {
      return fail(error);
    }
    const std::string invalid = s.velodyne.validate();
    if (!invalid.empty()) return fail(invalid);
  }

  // --- Bag.
  if (!args.has("--out")) return fail(std::string("--out BAG is required\n") + kUsage);
  SimulationBagOptions options;
  options.path = args.get("--out");
  options.truth = !args.has("--no-truth");
  options.compression = args.get("--compression", "none");
  double start = 1700000000.0;
  if (!number("--duration", motion.duration(), &options.duration) ||
      !number("--tf-rate", options.tf_rate, &options.tf_rate) || !number("--start-time", start, &start)) {
    return fail(error);
  }
  if (!(options.duration > 0.0)) return fail("--duration must be positive");
  if (!(start > 0.0) || start > 4.0e9) return fail("--start-time must be in (0, 4e9) seconds");
  options.start = ros::Time(start);

  sim::RigSimulator simulator(world, rig, motion, seed);
  simulator.motion_distortion = args.has("--motion-distortion");
  const auto t0 = std::chrono::steady_clock::now();
  SimulationBagSummary summary;
  if (!writeSimulationBag(simulator, options, &summary, &error)) return fail(error);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::string extrinsics_path = args.get("--extrinsics");
  if (extrinsics_path.empty()) {
    extrinsics_path = options.path;
    if (extrinsics_path.size() > 4 && extrinsics_path.compare(extrinsics_path.size() - 4, 4, ".bag") == 0) {
      extrinsics_path.resize(extrinsics_path.size() - 4);
    }
    extrinsics_path += ".extrinsics.yaml";
  }
  {
    const std::string tmp = extrinsics_path + ".tmp";
    std::ofstream out(tmp);
    out << sim::extrinsicsYaml(rig, world_name, seed);
    out.close();
    if (!out || std::rename(tmp.c_str(), extrinsics_path.c_str()) != 0) {
      return fail("cannot write " + extrinsics_path);
    }
  }

  std::cout << "wrote " << options.path << ": " << options.duration << " s of world '" << world_name
            << "' in " << wall << " s (" << options.duration / std::max(wall, 1e-9)
            << " x real time)\n";
  for (const auto& kv : summary.messages) std::cout << "  " << kv.first << ": " << kv.second << " messages\n";
  std::cout << "  velodyne points: " << summary.velodyne_points << "\n";
  std::cout << "wrote " << extrinsics_path << "\n";
  return 0;
}
