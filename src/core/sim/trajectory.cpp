#include "ladar_perception/sim/trajectory.h"

#include <algorithm>
#include <cmath>

#include <yaml-cpp/yaml.h>

#include "ladar_perception/sim/random.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

bool Trajectory::fromWaypoints(const std::vector<Eigen::Vector2d>& waypoints, double speed,
                               Trajectory* out, std::string* error) {
  if (!(speed > 0.0) || !std::isfinite(speed)) {
    if (error) *error = "trajectory speed must be positive";
    return false;
  }
  Trajectory t;
  for (const Eigen::Vector2d& p : waypoints) {
    if (!p.allFinite()) {
      if (error) *error = "trajectory waypoint is not finite";
      return false;
    }
    if (!t.points_.empty() && (p - t.points_.back()).norm() < 1e-6) continue;
    t.cumulative_.push_back(t.points_.empty()
                                ? 0.0
                                : t.cumulative_.back() + (p - t.points_.back()).norm());
    t.points_.push_back(p);
  }
  if (t.points_.size() < 2) {
    if (error) *error = "trajectory needs at least two distinct waypoints";
    return false;
  }
  t.speed_ = speed;
  *out = t;
  return true;
}

void Trajectory::poseAtDistance(double s, double* x, double* y, double* yaw) const {
  if (empty()) {
    *x = *y = *yaw = 0.0;
    return;
  }
  auto position = [&](double d) -> Eigen::Vector2d {
    d = std::clamp(d, 0.0, length());
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), d);
    std::size_t k = static_cast<std::size_t>(it - cumulative_.begin());
    k = std::clamp<std::size_t>(k, 1, points_.size() - 1);
    const double seg = cumulative_[k] - cumulative_[k - 1];
    const double a = seg > 0 ? (d - cumulative_[k - 1]) / seg : 0.0;
    return points_[k - 1] + a * (points_[k] - points_[k - 1]);
  };
  const Eigen::Vector2d p = position(s);
  *x = p.x();
  *y = p.y();
  // Heading: the chord over +-corner_radius of path, so yaw turns smoothly at corners.
  const double r = std::max(corner_radius, 1e-3);
  Eigen::Vector2d chord = position(s + r) - position(s - r);
  if (chord.norm() < 1e-9) chord = points_[1] - points_[0];
  *yaw = std::atan2(chord.y(), chord.x());
}

void Trajectory::pose2d(double t, double* x, double* y, double* yaw) const {
  poseAtDistance(std::clamp(t, 0.0, duration()) * speed_, x, y, yaw);
}

bool loadTrajectoryYaml(const std::string& path, Trajectory* out, std::string* error) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    const YAML::Node wps = root["waypoints"];
    if (!wps || !wps.IsSequence()) {
      if (error) *error = path + ": needs a `waypoints: [[x, y], ...]` list";
      return false;
    }
    std::vector<Eigen::Vector2d> points;
    for (const YAML::Node& w : wps) {
      if (!w.IsSequence() || w.size() != 2) {
        if (error) *error = path + ": every waypoint is [x, y]";
        return false;
      }
      points.emplace_back(w[0].as<double>(), w[1].as<double>());
    }
    const double speed = root["speed"] ? root["speed"].as<double>() : 5.0;
    std::string err;
    if (!Trajectory::fromWaypoints(points, speed, out, &err)) {
      if (error) *error = path + ": " + err;
      return false;
    }
    if (root["corner_radius"]) out->corner_radius = root["corner_radius"].as<double>();
    return true;
  } catch (const std::exception& e) {
    if (error) *error = path + ": " + e.what();
    return false;
  }
}

std::vector<Eigen::Isometry3d> randomVehiclePoses(const World& world, int count, uint64_t seed,
                                                  const RandomPoseOptions& options) {
  std::vector<Eigen::Isometry3d> poses;
  Rng rng(seed);
  for (int k = 0; k < count; ++k) {
    // Uniform in the disk: radius ~ sqrt(U).
    const double radius = options.max_offset * std::sqrt(rng.uniform());
    const double bearing = rng.uniform(-M_PI, M_PI);
    const double yaw = rng.uniform(-options.max_yaw, options.max_yaw);
    poses.push_back(world.vehiclePose(options.centre_x + radius * std::cos(bearing),
                                      options.centre_y + radius * std::sin(bearing), yaw));
  }
  return poses;
}

}  // namespace sim
}  // namespace ladar_perception
