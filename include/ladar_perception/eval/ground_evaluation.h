// (Over 600 lines: the simulator-world evaluation in one header, so that the accuracy tests
// and ground_eval run the same code.)
// Accuracy of a ground model on the simulator's standard worlds with ground truth (the
// accuracy test and the ground_eval tool share this one evaluation). With the evaluation against
// labelled real scans in eval/, not in the ground headers: the ground library does not depend on
// the simulator. Header-only (used by tools and tests that link the simulator).
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
#include <map>
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
      if (c == sim::SurfaceClass::kNone) continue;  // an empty slot of an organised cloud
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

// The evaluation's sensor: a model of the lidar table (cloud/lidar_models.h) at its usual
// mounting height above base_link, level; "hdl64e" is the mount above with
// sim::VelodyneModel::hdl64e (Table 4.1 range limits).
struct EvaluationSensor {
  LidarModel lidar;
  sim::VelodyneModel model;
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  // Rolls and pitches the sensor on its mount [deg] (SensorPose::fromMount conventions).
  void tilt(double roll_deg, double pitch_deg) {
    mount.linear() = SensorPose::fromMount(0.f, static_cast<float>(roll_deg), static_cast<float>(pitch_deg))
                         .sensor_to_ground.linear()
                         .cast<double>();
  }
};

inline bool makeEvaluationSensor(const std::string& name, sim::NoiseProfile noise,
                                 EvaluationSensor* sensor, std::string* error) {
  const LidarModel* lidar = findLidarModel(name);
  if (!lidar) {
    if (error) *error = "unknown sensor " + name + " (known: " + lidarModelNames() + ")";
    return false;
  }
  sensor->lidar = *lidar;
  sensor->model = sim::VelodyneModel::fromLidarModel(*lidar, noise);
  sensor->mount = Eigen::Isometry3d::Identity();
  sensor->mount.translation() = Eigen::Vector3d(0.0, 0.0, name == "hdl64e" ? 1.73 : lidar->mount_height);
  return true;
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
// The same scans of another sensor (makeEvaluationSensor()).
template <typename ScanFn>
bool forEachEvaluationScan(const EvaluationSensor& evaluation_sensor, const std::string& world_name,
                           int scans, uint32_t seed, std::string* error, ScanFn fn) {
  sim::World world;
  if (!sim::makeStandardWorld(world_name, seed, &world, error)) return false;
  const sim::VelodyneModel& velodyne = evaluation_sensor.model;
  const Eigen::Isometry3d mount = evaluation_sensor.mount;
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

template <typename ScanFn>
bool forEachEvaluationScan(const std::string& world_name, sim::NoiseProfile noise, int scans,
                           uint32_t seed, std::string* error, ScanFn fn) {
  EvaluationSensor sensor;
  if (!makeEvaluationSensor("hdl64e", noise, &sensor, error)) return false;
  return forEachEvaluationScan(sensor, world_name, scans, seed, error, fn);
}

// Classifies the evaluation's scans (forEachEvaluationScan) and accumulates the accuracy. The
// model sees the sensor pose relative to base_link (what tf gives the nodelet: base_link
// follows the local ground). at_ground_band > 0: the obstacle returns at the ground are not
// scored (markObstacleReturnsAtTheGround). misses: where the missed obstacle returns are.
// The sensor's scans; the model is told the sensor (GroundModel::setLidarModel) first.
inline bool evaluateGroundModel(const EvaluationSensor& sensor_model, const std::string& world_name,
                                GroundModel* model, int scans, uint32_t seed, GroundAccuracy* acc,
                                std::string* error, double at_ground_band = 0.0,
                                MissBreakdown* misses = nullptr) {
  SensorPose pose;
  pose.sensor_to_ground = sensor_model.mount.cast<float>();
  model->setLidarModel(sensor_model.lidar);
  GroundClassification result;
  std::vector<uint8_t> at_ground;
  return forEachEvaluationScan(
      sensor_model, world_name, scans, seed, error,
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

// The HDL-64E's scans (the evaluation of the tests and of the thesis's findings).
inline bool evaluateGroundModel(const std::string& world_name, GroundModel* model,
                                sim::NoiseProfile noise, int scans, uint32_t seed,
                                GroundAccuracy* acc, std::string* error,
                                double at_ground_band = 0.0, MissBreakdown* misses = nullptr) {
  EvaluationSensor sensor;
  if (!makeEvaluationSensor("hdl64e", noise, &sensor, error)) return false;
  return evaluateGroundModel(sensor, world_name, model, scans, seed, acc, error, at_ground_band, misses);
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

// The bounds' bands of horizontal range from the sensor (the range noise moves a return less
// in height the flatter the ray meets the ground): 0-5, 5-7.5, 7.5-10, 10-15, 15-20, 20-30,
// 30-50, 50+ m.
struct RangeBands {
  static constexpr int kBands = 8;
  static int band(double r) {
    static constexpr double kEdges[kBands - 1] = {5.0, 7.5, 10.0, 15.0, 20.0, 30.0, 50.0};  // [m]
    int b = 0;
    while (b < kBands - 1 && r >= kEdges[b]) ++b;
    return b;
  }
  // Per band, the value that a fraction `kept` of the band's values stay within (0 for an
  // empty band); the values are reordered.
  static std::array<double, kBands> quantiles(std::array<std::vector<double>, kBands>* values, double kept) {
    std::array<double, kBands> q{};
    for (int b = 0; b < kBands; ++b) {
      std::vector<double>& d = (*values)[b];
      if (d.empty()) continue;
      const std::size_t k = std::min(d.size() - 1, static_cast<std::size_t>(kept * static_cast<double>(d.size())));
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
      q[b] = d[k];
    }
    return q;
  }
};

// The scored returns of the evaluation's scans (truth ground or obstacle, finite): calls
// fn(world, scan_index, p, band, cls) with p in the world frame and band the RangeBands band
// of its horizontal distance from the sensor.
template <typename ReturnFn>
bool forEachScoredReturn(const std::string& world_name, sim::NoiseProfile noise, int scans, uint32_t seed,
                         std::string* error, ReturnFn fn) {
  int scan_index = 0;
  return forEachEvaluationScan(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, const Eigen::Isometry3d& sensor, const PointCloudView& view,
          const std::vector<uint8_t>& truth) {
        for (std::size_t i = 0; i < truth.size() && i < view.size(); ++i) {
          const auto c = static_cast<sim::SurfaceClass>(truth[i]);
          if (!sim::isGroundClass(c) && !sim::isObstacleClass(c)) continue;
          const Eigen::Vector3f q = view.xyz(i);
          if (!q.allFinite()) continue;
          const Eigen::Vector3d p = sensor * q.cast<double>();
          const double r = std::hypot(p.x() - sensor.translation().x(), p.y() - sensor.translation().y());
          fn(world, scan_index, p, RangeBands::band(r), truth[i]);
        }
        ++scan_index;
      });
}

inline bool heightTestBound(const std::string& world_name, sim::NoiseProfile noise, int scans,
                            uint32_t seed, double ground_kept, HeightTestBound* out,
                            std::string* error) {
  constexpr int kBands = RangeBands::kBands;
  std::array<std::vector<double>, kBands> ground_dz;
  struct ObstacleReturn {
    double dz;
    int band;
    uint8_t cls;
  };
  std::vector<ObstacleReturn> obstacles;
  const bool ok = forEachScoredReturn(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, int, const Eigen::Vector3d& p, int b, uint8_t cls) {
        const double dz = heightToNearbyGround(world, p);
        if (sim::isGroundClass(static_cast<sim::SurfaceClass>(cls))) {
          if (std::isfinite(dz)) ground_dz[b].push_back(dz);
        } else {
          obstacles.push_back({dz, b, cls});
        }
      });
  if (!ok) return false;
  // No ground in a band: every difference there is separable.
  const std::array<double, kBands> threshold = RangeBands::quantiles(&ground_dz, ground_kept);
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

// The depth of the point p (world frame) below the ground next to it: the height of the
// nearest ground-class cell (its own cell when that is ground, else the nearest within
// max_radius horizontally) minus p.z; negative above it, NaN where there is none.
inline double depthBelowNearestGround(const sim::World& world, const Eigen::Vector3d& p, double max_radius = 1.0) {
  const int cx = world.cellX(p.x()), cy = world.cellY(p.y());
  if (world.validCell(cx, cy) && sim::isGroundClass(world.cellClass(cx, cy))) return world.cellHeight(cx, cy) - p.z();
  const int R = static_cast<int>(std::ceil(max_radius / world.resolution()));
  int best_d2 = R * R + 1;
  double best = std::numeric_limits<double>::quiet_NaN();
  for (int dy = -R; dy <= R; ++dy) {
    for (int dx = -R; dx <= R; ++dx) {
      const int d2 = dx * dx + dy * dy;
      if (d2 >= best_d2 || !world.validCell(cx + dx, cy + dy) ||
          !sim::isGroundClass(world.cellClass(cx + dx, cy + dy))) continue;
      best_d2 = d2;
      best = world.cellHeight(cx + dx, cy + dy) - p.z();
    }
  }
  return best;
}

// How far a region model of holes can go on the evaluation's scans, even against the exact
// ground surface (which no estimate has): the limit behind the pothole target. Seeds are the
// returns deeper below the nearest ground cell (depthBelowNearestGround()) than all but a
// fraction 1 - seed_ground_kept of the ground returns in their range band (as in
// heightTestBound()); seeds less than `link` apart form a hole; a hole of at least `min_seeds`
// seeds takes the returns inside the convex hull of its seeds or within `margin` of one of
// them, unless they lie more than `max_rise` above the ground (a car's side beside a hole).
// The hole's returns are obstacles, every other return ground: the ground recall that costs is
// reported with the obstacle recall. With seeds deeper than 99.99% of the ground (the default)
// no world loses more than 0.3% of its ground to holes; 99.9% finds a few more pothole returns
// but seeds holes along curbs and terrace edges (ground_eval --region-seed-kept).
struct RegionModelParams {
  double seed_ground_kept = 0.9999;
  double link = 0.5;       // [m]
  double margin = 0.15;    // [m]
  int min_seeds = 3;
  double max_rise = 0.005;  // [m]
};

struct RegionModelBound {
  std::size_t obstacle_returns = 0, obstacles_found = 0;
  std::size_t ground_returns = 0, ground_kept = 0;
  std::size_t holes = 0;
  std::array<std::size_t, sim::kNumSurfaceClasses> class_returns{}, class_found{};
  double groundRecall() const { return GroundAccuracy::ratio(ground_kept, ground_returns); }
};

namespace region_bound_detail {

// Counter-clockwise convex hull of pts (Andrew's monotone chain); pts is reordered.
inline std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (pts.size() < 3) return pts;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

inline bool insideConvex(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& q) {
  if (hull.size() < 3) return false;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    if ((b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x()) < 0.0) return false;
  }
  return true;
}

}  // namespace region_bound_detail

inline bool regionModelBound(const std::string& world_name, sim::NoiseProfile noise, int scans, uint32_t seed,
                             const RegionModelParams& params, RegionModelBound* out, std::string* error) {
  constexpr int kBands = RangeBands::kBands;
  struct Return {
    Eigen::Vector2d xy;
    double depth;  // below the nearest ground cell; NaN: none within reach
    int band;
    int scan;
    uint8_t cls;
  };
  std::vector<Return> returns;
  std::array<std::vector<double>, kBands> ground_depth;
  const bool ok = forEachScoredReturn(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, int scan, const Eigen::Vector3d& p, int b, uint8_t cls) {
        const double depth = depthBelowNearestGround(world, p);
        if (sim::isGroundClass(static_cast<sim::SurfaceClass>(cls)) && std::isfinite(depth)) {
          ground_depth[b].push_back(depth);
        }
        returns.push_back({p.head<2>(), depth, b, scan, cls});
      });
  if (!ok) return false;
  *out = RegionModelBound{};
  const std::array<double, kBands> threshold = RangeBands::quantiles(&ground_depth, params.seed_ground_kept);
  auto is_seed = [&](const Return& x) {
    return std::isfinite(x.depth) && x.depth > std::max(threshold[x.band], 0.0);
  };
  std::vector<uint8_t> found(returns.size(), 0);
  // Per scan: link the seeds through a grid of `link` cells (union-find), then fill each hole.
  const double cell = params.link;
  auto key = [cell](const Eigen::Vector2d& xy) {
    return std::make_pair(static_cast<int64_t>(std::floor(xy.x() / cell)), static_cast<int64_t>(std::floor(xy.y() / cell)));
  };
  std::size_t begin = 0;
  while (begin < returns.size()) {
    std::size_t end = begin;
    while (end < returns.size() && returns[end].scan == returns[begin].scan) ++end;
    std::vector<std::size_t> seeds;
    for (std::size_t i = begin; i < end; ++i) {
      if (is_seed(returns[i])) seeds.push_back(i);
    }
    std::vector<std::size_t> parent(seeds.size());
    for (std::size_t s = 0; s < seeds.size(); ++s) parent[s] = s;
    auto find = [&parent](std::size_t s) {
      while (parent[s] != s) s = parent[s] = parent[parent[s]];
      return s;
    };
    std::map<std::pair<int64_t, int64_t>, std::vector<std::size_t>> grid;
    for (std::size_t s = 0; s < seeds.size(); ++s) grid[key(returns[seeds[s]].xy)].push_back(s);
    for (std::size_t s = 0; s < seeds.size(); ++s) {
      const auto k = key(returns[seeds[s]].xy);
      for (int64_t dx = -1; dx <= 1; ++dx) {
        for (int64_t dy = -1; dy <= 1; ++dy) {
          const auto it = grid.find({k.first + dx, k.second + dy});
          if (it == grid.end()) continue;
          for (std::size_t t : it->second) {
            if ((returns[seeds[t]].xy - returns[seeds[s]].xy).norm() < params.link) parent[find(s)] = find(t);
          }
        }
      }
    }
    std::map<std::size_t, std::vector<std::size_t>> holes;  // root -> seeds
    for (std::size_t s = 0; s < seeds.size(); ++s) holes[find(s)].push_back(s);
    for (const auto& h : holes) {
      if (static_cast<int>(h.second.size()) < params.min_seeds) continue;
      ++out->holes;
      std::vector<Eigen::Vector2d> pts;
      Eigen::Vector2d lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
      Eigen::Vector2d hi = -lo;
      for (std::size_t s : h.second) {
        const Eigen::Vector2d& xy = returns[seeds[s]].xy;
        pts.push_back(xy);
        lo = lo.cwiseMin(xy);
        hi = hi.cwiseMax(xy);
        found[seeds[s]] = 1;
      }
      const std::vector<Eigen::Vector2d> hull = region_bound_detail::convexHull(pts);
      lo.array() -= params.margin;
      hi.array() += params.margin;
      for (std::size_t i = begin; i < end; ++i) {
        const Return& x = returns[i];
        if (found[i] || (x.xy.array() < lo.array()).any() || (x.xy.array() > hi.array()).any()) continue;
        if (std::isfinite(x.depth) && x.depth < -params.max_rise) continue;
        bool inside = region_bound_detail::insideConvex(hull, x.xy);
        for (std::size_t j = 0; !inside && j < pts.size(); ++j) inside = (pts[j] - x.xy).norm() < params.margin;
        found[i] = inside;
      }
    }
    begin = end;
  }
  for (std::size_t i = 0; i < returns.size(); ++i) {
    const Return& x = returns[i];
    if (sim::isGroundClass(static_cast<sim::SurfaceClass>(x.cls))) {
      ++out->ground_returns;
      out->ground_kept += !found[i];
    } else {
      ++out->obstacle_returns;
      out->obstacles_found += found[i];
      if (x.cls < sim::kNumSurfaceClasses) {
        ++out->class_returns[x.cls];
        out->class_found[x.cls] += found[i];
      }
    }
  }
  return true;
}

// Negative obstacles scored per hole, the way a user means "found the pothole": a hole is a
// 4-connected set of pothole cells of the world at least min_across wide in x and in y and at
// least min_depth below the median of the ground cells around it. In a scan a hole counts when
// its centre lies within max_range of the sensor horizontally and at least one return falls
// inside it (it is in line of sight); it is found when one of those returns is called an
// obstacle.
struct WorldHole {
  Eigen::Vector2d centre;
  double across = 0.0, depth = 0.0;  // [m]: the smaller of its x and y extents; its depth
  std::vector<std::size_t> cells;    // World::index()
};

struct HoleParams {
  double min_across = 0.25, min_depth = 0.05, max_range = 30.0;  // [m]
};

struct HoleScore {
  std::size_t scans = 0;
  std::size_t holes = 0;                 // holes in the world passing the size and depth tests
  std::size_t seen = 0, found = 0;       // (hole, scan) pairs in range and line of sight
  std::size_t returns_in_holes = 0, returns_called_obstacle = 0;
  // By the hole's horizontal range: below 10 m, 10-20 m, 20 m and beyond.
  std::array<std::size_t, 3> seen_by_range{}, found_by_range{};
  double recall() const { return GroundAccuracy::ratio(found, seen); }
};

inline std::vector<WorldHole> worldHoles(const sim::World& world, const HoleParams& params,
                                         std::vector<int>* cell_hole) {
  const int nx = world.cellsX(), ny = world.cellsY();
  const double res = world.resolution();
  cell_hole->assign(static_cast<std::size_t>(nx) * ny, -1);
  std::vector<uint8_t> seen(cell_hole->size(), 0);
  std::vector<WorldHole> holes;
  std::vector<std::pair<int, int>> stack;
  std::vector<float> rim;
  for (int y0 = 0; y0 < ny; ++y0) {
    for (int x0 = 0; x0 < nx; ++x0) {
      if (seen[world.index(x0, y0)] || world.cellClass(x0, y0) != sim::SurfaceClass::kPothole) continue;
      WorldHole hole;
      int min_x = x0, max_x = x0, min_y = y0, max_y = y0;
      float lowest = world.cellHeight(x0, y0);
      rim.clear();
      stack.assign(1, {x0, y0});
      seen[world.index(x0, y0)] = 1;
      while (!stack.empty()) {
        const auto [x, y] = stack.back();
        stack.pop_back();
        hole.cells.push_back(world.index(x, y));
        min_x = std::min(min_x, x), max_x = std::max(max_x, x);
        min_y = std::min(min_y, y), max_y = std::max(max_y, y);
        lowest = std::min(lowest, world.cellHeight(x, y));
        const int d[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
        for (const auto& dd : d) {
          const int qx = x + dd[0], qy = y + dd[1];
          if (!world.validCell(qx, qy)) continue;
          const std::size_t q = world.index(qx, qy);
          if (world.cellClass(qx, qy) == sim::SurfaceClass::kPothole) {
            if (!seen[q]) {
              seen[q] = 1;
              stack.emplace_back(qx, qy);
            }
          } else if (sim::isGroundClass(world.cellClass(qx, qy))) {
            rim.push_back(world.cellHeight(qx, qy));
          }
        }
      }
      if (rim.empty()) continue;
      std::nth_element(rim.begin(), rim.begin() + static_cast<std::ptrdiff_t>(rim.size() / 2), rim.end());
      hole.depth = rim[rim.size() / 2] - lowest;
      hole.across = std::min(max_x - min_x + 1, max_y - min_y + 1) * res;
      hole.centre = Eigen::Vector2d(world.originX() + (min_x + max_x + 1) * 0.5 * res,
                                    world.originY() + (min_y + max_y + 1) * 0.5 * res);
      if (hole.across < params.min_across - 1e-9 || hole.depth < params.min_depth - 1e-6) continue;
      for (const std::size_t c : hole.cells) (*cell_hole)[c] = static_cast<int>(holes.size());
      holes.push_back(std::move(hole));
    }
  }
  return holes;
}

// The hole a world point lies in (a return on a hole's wall may sit on the cell border: the
// four neighbour cells are tried too), or -1.
inline int holeAt(const sim::World& world, const std::vector<int>& cell_hole, const Eigen::Vector3d& p) {
  const int cx = world.cellX(p.x()), cy = world.cellY(p.y());
  const int d[5][2] = {{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const auto& dd : d) {
    if (world.validCell(cx + dd[0], cy + dd[1])) {
      const int h = cell_hole[world.index(cx + dd[0], cy + dd[1])];
      if (h >= 0) return h;
    }
  }
  return -1;
}

inline bool evaluateHoles(const std::string& world_name, GroundModel* model, sim::NoiseProfile noise,
                          int scans, uint32_t seed, const HoleParams& params, HoleScore* score,
                          std::string* error) {
  SensorPose pose;
  pose.sensor_to_ground = evaluationSensorMount().cast<float>();
  GroundClassification result;
  std::vector<WorldHole> holes;
  std::vector<int> cell_hole;
  std::vector<int> in_sight, called;
  return forEachEvaluationScan(
      world_name, noise, scans, seed, error,
      [&](const sim::World& world, const Eigen::Isometry3d& sensor, const PointCloudView& view,
          const std::vector<uint8_t>& truth) {
        if (score->scans == 0) {
          holes = worldHoles(world, params, &cell_hole);
          score->holes = holes.size();
        }
        ++score->scans;
        model->classify(view, pose, &result);
        in_sight.assign(holes.size(), 0);
        called.assign(holes.size(), 0);
        for (std::size_t i = 0; i < truth.size() && i < view.size(); ++i) {
          if (static_cast<sim::SurfaceClass>(truth[i]) != sim::SurfaceClass::kPothole) continue;
          const Eigen::Vector3f q = view.xyz(i);
          if (!q.allFinite()) continue;
          const int h = holeAt(world, cell_hole, sensor * q.cast<double>());
          if (h < 0) continue;
          ++in_sight[h];
          ++score->returns_in_holes;
          if (result.labels[i] == kLabelObstacle) {
            ++called[h];
            ++score->returns_called_obstacle;
          }
        }
        const Eigen::Vector2d sensor_xy = sensor.translation().head<2>();
        for (std::size_t h = 0; h < holes.size(); ++h) {
          if (!in_sight[h] || (holes[h].centre - sensor_xy).norm() > params.max_range) continue;
          ++score->seen;
          score->found += called[h] > 0;
          const int band = std::min(2, static_cast<int>((holes[h].centre - sensor_xy).norm() / 10.0));
          ++score->seen_by_range[band];
          score->found_by_range[band] += called[h] > 0;
        }
      });
}

}  // namespace ladar_perception
