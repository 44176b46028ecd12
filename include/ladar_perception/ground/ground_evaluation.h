// Accuracy of a ground model on the simulator's standard worlds with ground truth (the
// accuracy test and the ground_eval tool share this one evaluation). Header-only so the ground
// library itself does not depend on the simulator.
//
// Truth mapping: sim ground classes (road, sidewalk, terrain) = ground; obstacle classes
// (curb face, car, wall, pole, person, pothole) = obstacle.
//   ground precision = true ground among points labelled ground;
//   ground recall    = labelled ground among true ground;
//   obstacle recall  = labelled obstacle among true obstacles (unknown counts as a miss).
// Optionally (at_ground_band > 0) obstacle returns at the ground are not scored: those within
// that height of a ground surface less than kAtGroundRadius away (the bottom and top 2 cm of a
// curb face, the bottom of a car's side or a wall, a pothole's rim), which at the HDL-64E's
// 2 cm range noise no height test can tell from the ground next to them.
// heightTestBound() measures that limit: the obstacle recall a test of each return's height
// against the exact ground surface reaches while keeping 99% of the ground (ground_eval
// --height-bound).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/sensor_models.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {

struct GroundAccuracy {
  std::size_t scans = 0;
  std::size_t points = 0;
  std::size_t truth_ground = 0, truth_obstacle = 0;
  std::size_t labelled_ground = 0;
  std::size_t not_scored = 0;            // obstacle returns at the ground (at_ground_band)
  std::size_t ground_as_ground = 0;      // true ground labelled ground
  std::size_t obstacle_as_obstacle = 0;  // true obstacle labelled obstacle
  // Per truth class: points and points labelled correctly.
  std::array<std::size_t, sim::kNumSurfaceClasses> class_points{};
  std::array<std::size_t, sim::kNumSurfaceClasses> class_correct{};

  static double ratio(std::size_t a, std::size_t b) {
    return b ? static_cast<double>(a) / static_cast<double>(b) : 1.0;
  }
  double groundPrecision() const { return ratio(ground_as_ground, labelled_ground); }
  double groundRecall() const { return ratio(ground_as_ground, truth_ground); }
  double obstacleRecall() const { return ratio(obstacle_as_obstacle, truth_obstacle); }

  // skip[i] != 0: point i is not scored (empty: every point is).
  void add(const std::vector<uint8_t>& truth, const GroundClassification& result,
           const std::vector<uint8_t>& skip = {}) {
    ++scans;
    for (std::size_t i = 0; i < truth.size() && i < result.size(); ++i) {
      if (i < skip.size() && skip[i]) {
        ++not_scored;
        continue;
      }
      const auto c = static_cast<sim::SurfaceClass>(truth[i]);
      const uint8_t label = result.labels[i];
      const bool g = sim::isGroundClass(c), o = sim::isObstacleClass(c);
      ++points;
      truth_ground += g;
      truth_obstacle += o;
      labelled_ground += label == kLabelGround;
      ground_as_ground += g && label == kLabelGround;
      obstacle_as_obstacle += o && label == kLabelObstacle;
      if (truth[i] < sim::kNumSurfaceClasses) {
        ++class_points[truth[i]];
        class_correct[truth[i]] += (g && label == kLabelGround) || (o && label == kLabelObstacle);
      }
    }
  }
};

// The sensor mount of the evaluation: an HDL-64E 1.73 m above base_link, level (KITTI's).
inline Eigen::Isometry3d evaluationSensorMount() {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.translation() = Eigen::Vector3d(0.0, 0.0, 1.73);
  return m;
}

constexpr double kAtGroundRadius = 0.3;  // [m]

// The height of the point p (world frame) above or below the ground next to it: the smallest
// |p.z - h| over the ground-class cells less than kAtGroundRadius away horizontally (infinity
// where there is none).
inline double heightToNearbyGround(const sim::World& world, const Eigen::Vector3d& p) {
  const int R = static_cast<int>(std::ceil(kAtGroundRadius / world.resolution()));
  const int cx = world.cellX(p.x()), cy = world.cellY(p.y());
  double best = std::numeric_limits<double>::infinity();
  for (int dy = -R; dy <= R; ++dy) {
    for (int dx = -R; dx <= R; ++dx) {
      const int ix = cx + dx, iy = cy + dy;
      if (!world.validCell(ix, iy) || !sim::isGroundClass(world.cellClass(ix, iy))) continue;
      if (static_cast<double>(dx * dx + dy * dy) * world.resolution() * world.resolution() >
          kAtGroundRadius * kAtGroundRadius) continue;
      best = std::min(best, std::abs(p.z() - world.cellHeight(ix, iy)));
    }
  }
  return best;
}

// Marks the obstacle returns of `view` (truth: their classes; taken at `sensor` in the world)
// that lie within `band` in height of a ground-class cell less than kAtGroundRadius away
// horizontally.
inline void markObstacleReturnsAtTheGround(const sim::World& world, const Eigen::Isometry3d& sensor,
                                           const PointCloudView& view, const std::vector<uint8_t>& truth,
                                           double band, std::vector<uint8_t>* at_ground) {
  at_ground->assign(truth.size(), 0);
  for (std::size_t i = 0; i < truth.size() && i < view.size(); ++i) {
    if (!sim::isObstacleClass(static_cast<sim::SurfaceClass>(truth[i]))) continue;
    const Eigen::Vector3d p = sensor * view.xyz(i).cast<double>();
    if (!std::isfinite(p.z())) continue;
    (*at_ground)[i] = heightToNearbyGround(world, p) < band;
  }
}

// Where the missed obstacle returns are (ground_eval --misses): by their height to the ground
// next to them (heightToNearbyGround(): below 2, 2-4, 4-6, 6-8 cm, 8 cm or more or no ground
// within kAtGroundRadius) and by horizontal range from the sensor (below 10 m or not).
struct MissBreakdown {
  static constexpr double kNearRange = 10.0;  // [m]
  std::array<std::size_t, 5> missed_by_height{};
  std::size_t near_obstacles = 0, near_missed = 0;  // within kNearRange
  std::size_t far_obstacles = 0, far_missed = 0;

  // One obstacle return at `p` (world frame), seen from `sensor_xy`; missed or not.
  void add(const sim::World& world, const Eigen::Vector3d& p, const Eigen::Vector2d& sensor_xy, bool missed) {
    const bool near = (p.head<2>() - sensor_xy).norm() < kNearRange;
    (near ? near_obstacles : far_obstacles) += 1;
    if (!missed) return;
    (near ? near_missed : far_missed) += 1;
    const double dz = heightToNearbyGround(world, p);
    ++missed_by_height[dz < 0.02 ? 0 : dz < 0.04 ? 1 : dz < 0.06 ? 2 : dz < 0.08 ? 3 : 4];
  }
};

// The evaluation's scans: `scans` HDL-64E revolutions taken along the world's standard drive
// (evenly spaced in time, noise seeds seed * 1000 + k). Calls
// fn(world, sensor_in_world, view, truth) for each; false (and *error) when the world is
// unknown or a scan cannot be read.
template <typename ScanFn>
bool forEachEvaluationScan(const std::string& world_name, sim::NoiseProfile noise, int scans,
                           uint32_t seed, std::string* error, ScanFn fn) {
  sim::World world;
  if (!sim::makeStandardWorld(world_name, seed, &world, error)) return false;
  const sim::VelodyneModel velodyne = sim::VelodyneModel::hdl64e(noise);
  const Eigen::Isometry3d mount = evaluationSensorMount();
  sim::SimulatedScan scan;
  PointCloudView view;
  const double duration = world.driveDuration();
  for (int k = 0; k < scans; ++k) {
    const double t = duration * (static_cast<double>(k) + 0.5) / std::max(scans, 1);
    const Eigen::Isometry3d sensor = world.drivePose(t) * mount;
    sim::simulateVelodyneRevolution(world, sensor, velodyne, seed * 1000u + k, &scan);
    if (!scan.cloud.view(&view, error)) return false;
    fn(static_cast<const sim::World&>(world), sensor, static_cast<const PointCloudView&>(view),
       static_cast<const std::vector<uint8_t>&>(scan.truth));
  }
  return true;
}

// Classifies the evaluation's scans (forEachEvaluationScan) and accumulates the accuracy. The
// model sees the sensor pose relative to base_link (what tf gives the nodelet: base_link
// follows the local ground). at_ground_band > 0: the obstacle returns at the ground are not
// scored (markObstacleReturnsAtTheGround). misses: where the missed obstacle returns are.
inline bool evaluateGroundModel(const std::string& world_name, GroundModel* model,
                                sim::NoiseProfile noise, int scans, uint32_t seed,
                                GroundAccuracy* acc, std::string* error,
                                double at_ground_band = 0.0, MissBreakdown* misses = nullptr) {
  SensorPose pose;
  pose.sensor_to_ground = evaluationSensorMount().cast<float>();
  GroundClassification result;
  std::vector<uint8_t> at_ground;
  return forEachEvaluationScan(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, const Eigen::Isometry3d& sensor, const PointCloudView& view,
          const std::vector<uint8_t>& truth) {
        model->classify(view, pose, &result);
        if (at_ground_band > 0.0) {
          markObstacleReturnsAtTheGround(world, sensor, view, truth, at_ground_band, &at_ground);
        } else {
          at_ground.clear();
        }
        acc->add(truth, result, at_ground);
        if (!misses) return;
        const Eigen::Vector2d sensor_xy = sensor.translation().head<2>();
        for (std::size_t i = 0; i < truth.size() && i < view.size(); ++i) {
          if (!sim::isObstacleClass(static_cast<sim::SurfaceClass>(truth[i]))) continue;
          if (i < at_ground.size() && at_ground[i]) continue;  // not scored
          const Eigen::Vector3f q = view.xyz(i);
          if (!q.allFinite()) continue;
          misses->add(world, sensor * q.cast<double>(), sensor_xy, result.labels[i] != kLabelObstacle);
        }
      });
}

// How far height alone can separate the obstacle returns from the ground on the evaluation's
// scans: the limit of any test of a return's height, even against the exact ground surface
// (which no estimate has). Each return's height difference to the ground next to it is
// heightToNearbyGround(); per band of horizontal range from the sensor (the range noise
// moves a return less in height the flatter the ray meets the ground), the threshold is the
// difference that a fraction `ground_kept` (0.99: the ground recall target) of the ground
// returns stay within; the obstacle returns beyond it are separable.
struct HeightTestBound {
  std::size_t obstacle_returns = 0, separable = 0;
  std::array<std::size_t, sim::kNumSurfaceClasses> class_returns{}, class_separable{};
  double recall() const { return GroundAccuracy::ratio(separable, obstacle_returns); }
};

inline bool heightTestBound(const std::string& world_name, sim::NoiseProfile noise, int scans,
                            uint32_t seed, double ground_kept, HeightTestBound* out,
                            std::string* error) {
  static constexpr double kBandEdges[] = {5.0, 7.5, 10.0, 15.0, 20.0, 30.0, 50.0};  // [m]
  constexpr int kBands = static_cast<int>(sizeof(kBandEdges) / sizeof(kBandEdges[0])) + 1;
  auto band = [](double r) {
    int b = 0;
    while (b < kBands - 1 && r >= kBandEdges[b]) ++b;
    return b;
  };
  std::array<std::vector<double>, kBands> ground_dz;
  struct ObstacleReturn {
    double dz;
    int band;
    uint8_t cls;
  };
  std::vector<ObstacleReturn> obstacles;
  const bool ok = forEachEvaluationScan(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, const Eigen::Isometry3d& sensor, const PointCloudView& view,
          const std::vector<uint8_t>& truth) {
        for (std::size_t i = 0; i < truth.size() && i < view.size(); ++i) {
          const auto c = static_cast<sim::SurfaceClass>(truth[i]);
          const bool g = sim::isGroundClass(c), o = sim::isObstacleClass(c);
          if (!g && !o) continue;
          const Eigen::Vector3f q = view.xyz(i);
          if (!q.allFinite()) continue;
          const Eigen::Vector3d p = sensor * q.cast<double>();
          const int b = band(std::hypot(p.x() - sensor.translation().x(), p.y() - sensor.translation().y()));
          const double dz = heightToNearbyGround(world, p);
          if (g) {
            if (std::isfinite(dz)) ground_dz[b].push_back(dz);
          } else {
            obstacles.push_back({dz, b, truth[i]});
          }
        }
      });
  if (!ok) return false;
  std::array<double, kBands> threshold{};
  for (int b = 0; b < kBands; ++b) {
    std::vector<double>& d = ground_dz[b];
    if (d.empty()) continue;  // no ground in this band: every difference is separable
    const std::size_t k = std::min(d.size() - 1, static_cast<std::size_t>(ground_kept * static_cast<double>(d.size())));
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    threshold[b] = d[k];
  }
  *out = HeightTestBound{};
  for (const ObstacleReturn& o : obstacles) {
    const bool separable = o.dz > threshold[o.band];
    ++out->obstacle_returns;
    out->separable += separable;
    if (o.cls < sim::kNumSurfaceClasses) {
      ++out->class_returns[o.cls];
      out->class_separable[o.cls] += separable;
    }
  }
  return true;
}

}  // namespace ladar_perception
