// Vehicle trajectories for the simulator: waypoints driven at a constant speed, and the random
// vehicle poses of the thesis's calibration experiment (5.2.1).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace ladar_perception {
namespace sim {

class World;

// A polyline of (x, y) waypoints in odom driven at a constant speed; the heading follows the
// path, with corners rounded over `corner_radius` metres of path on each side so yaw is
// continuous.
class Trajectory {
 public:
  Trajectory() = default;
  // At least two distinct waypoints and a positive speed; false with a reason otherwise.
  static bool fromWaypoints(const std::vector<Eigen::Vector2d>& waypoints, double speed,
                            Trajectory* out, std::string* error);

  bool empty() const { return cumulative_.size() < 2; }
  double speed() const { return speed_; }
  double length() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }
  double duration() const { return speed_ > 0 ? length() / speed_ : 0.0; }
  const std::vector<Eigen::Vector2d>& waypoints() const { return points_; }

  // Position and heading at time t (clamped to [0, duration()]).
  void pose2d(double t, double* x, double* y, double* yaw) const;
  // The same at arc length s along the path.
  void poseAtDistance(double s, double* x, double* y, double* yaw) const;

  double corner_radius = 3.0;

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> cumulative_;  // arc length at each waypoint
  double speed_ = 0.0;
};

// Reads `waypoints: [[x, y], ...]` and `speed: m/s` from a YAML file (config/sim_*.yaml).
bool loadTrajectoryYaml(const std::string& path, Trajectory* out, std::string* error);

// The thesis experiment's vehicle poses: positions uniform in a disk of radius max_offset
// around (centre_x, centre_y), yaw uniform in [-max_yaw, max_yaw]; on the ground of the world
// (World::vehiclePose), so roll and pitch follow the terrain.
struct RandomPoseOptions {
  double centre_x = 0.0;
  double centre_y = 0.0;
  double max_offset = 5.0;
  double max_yaw = 0.5;
};
std::vector<Eigen::Isometry3d> randomVehiclePoses(const World& world, int count, uint64_t seed,
                                                  const RandomPoseOptions& options = {});

}  // namespace sim
}  // namespace ladar_perception
