// Analytic 3D scenes for the ground baseline tests: an HDL-64E-like revolution (the package's
// elevation table, 0.5 degree azimuth steps) ray cast onto a height function z = f(x, y) of the
// ground frame (origin under the sensor) and onto axis-aligned boxes; truth per return.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "ladar_perception/cloud/laser_elevations.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"

namespace surface_test {

namespace lp = ladar_perception;

struct Box {
  Eigen::Vector3d lo, hi;
};

struct SurfaceScene {
  double sensor_height = 1.73;
  double max_range = 70.0;
  std::function<double(double, double)> ground = [](double, double) { return 0.0; };
  std::vector<Box> boxes;

  // Ray from the sensor (0, 0, sensor_height) along unit d: range and truth (0 ground,
  // 1 obstacle), or false without a hit.
  bool cast(const Eigen::Vector3d& d, double* range, uint8_t* truth) const {
    const Eigen::Vector3d o(0, 0, sensor_height);
    double best = max_range + 1.0;
    bool hit = false;
    // Ground: march, then bisect.
    const double step = 0.1;
    double prev_t = 0.5;
    for (double t = 0.5; t <= max_range; t += step) {
      const Eigen::Vector3d p = o + t * d;
      if (p.z() <= ground(p.x(), p.y())) {
        double a = prev_t, b = t;
        for (int k = 0; k < 40; ++k) {
          const double m = 0.5 * (a + b);
          const Eigen::Vector3d q = o + m * d;
          (q.z() <= ground(q.x(), q.y()) ? b : a) = m;
        }
        best = 0.5 * (a + b);
        *truth = 0;
        hit = true;
        break;
      }
      prev_t = t;
    }
    for (const Box& box : boxes) {  // slab test
      double t0 = 0.0, t1 = best;
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        if (std::fabs(d[k]) < 1e-12) {
          ok = o[k] >= box.lo[k] && o[k] <= box.hi[k];
          continue;
        }
        double a = (box.lo[k] - o[k]) / d[k], b = (box.hi[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        ok = t0 <= t1;
      }
      if (ok && t0 > 0.0 && t0 < best) {
        best = t0;
        *truth = 1;
        hit = true;
      }
    }
    *range = best;
    return hit && best <= max_range;
  }

  // One revolution in the sensor frame (level, sensor_height above the origin): velodyne
  // XYZIRT layout (or x, y, z only), truth per point.
  void revolution(ladar_perception::PackedCloud* cloud, std::vector<uint8_t>* truth,
                  bool with_ring = true, int azimuth_steps = 720) const {
    namespace lp = ladar_perception;
    const std::vector<float>& elevations = lp::hdl64eElevationsDeg();
    std::vector<Eigen::Vector3f> pts;
    std::vector<int> rings;
    truth->clear();
    for (int a = 0; a < azimuth_steps; ++a) {
      const double az = 2.0 * M_PI * a / azimuth_steps;
      for (std::size_t ring = 0; ring < elevations.size(); ++ring) {
        const double el = elevations[ring] * M_PI / 180.0;
        const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
        double range;
        uint8_t t;
        if (!cast(d, &range, &t) || range < 2.0) continue;
        pts.push_back((range * d).cast<float>());
        rings.push_back(static_cast<int>(ring));
        truth->push_back(t);
      }
    }
    lp::CloudLayout layout;
    if (with_ring) {
      layout = lp::velodyneXYZIRTLayout(static_cast<uint32_t>(pts.size()));
    } else {
      lp::appendField(&layout, "x", lp::FieldType::kFloat32);
      lp::appendField(&layout, "y", lp::FieldType::kFloat32);
      lp::appendField(&layout, "z", lp::FieldType::kFloat32);
      layout.width = static_cast<uint32_t>(pts.size());
      layout.height = 1;
      layout.row_step = layout.width * layout.point_step;
    }
    cloud->layout = layout;
    cloud->data.assign(static_cast<std::size_t>(layout.point_step) * pts.size(), 0);
    const lp::FieldDesc* ring_field = lp::findField(layout, "ring");
    for (std::size_t i = 0; i < pts.size(); ++i) {
      uint8_t* p = cloud->data.data() + i * layout.point_step;
      lp::writeField(p, *lp::findField(layout, "x"), pts[i].x());
      lp::writeField(p, *lp::findField(layout, "y"), pts[i].y());
      lp::writeField(p, *lp::findField(layout, "z"), pts[i].z());
      if (ring_field) lp::writeField(p, *ring_field, rings[i]);
    }
  }
};

// Ground recall and obstacle recall of a model's labels on one revolution of a scene; obstacles
// count only where the return is more than 0.3 m above the ground function (the lowest
// centimetres of any obstacle face are ground-like to every method).
struct Score {
  double ground_recall = 0, obstacle_recall = 0;
};

inline Score score(lp::GroundModel* model, const SurfaceScene& scene, bool with_ring = true) {
  lp::PackedCloud cloud;
  std::vector<uint8_t> truth;
  scene.revolution(&cloud, &truth, with_ring);
  lp::PointCloudView view;
  EXPECT_TRUE(cloud.view(&view));
  lp::GroundClassification result;
  model->classify(view, lp::SensorPose::fromHeight(static_cast<float>(scene.sensor_height)), &result);
  EXPECT_EQ(result.size(), view.size());
  std::size_t g = 0, g_ok = 0, o = 0, o_ok = 0;
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    if (truth[i] == 0) {
      ++g;
      g_ok += result.labels[i] == lp::kLabelGround;
    } else if (p.z() + scene.sensor_height - scene.ground(p.x(), p.y()) > 0.3) {
      ++o;
      o_ok += result.labels[i] == lp::kLabelObstacle;
    }
  }
  Score s;
  s.ground_recall = g ? static_cast<double>(g_ok) / g : 1.0;
  s.obstacle_recall = o ? static_cast<double>(o_ok) / o : 1.0;
  return s;
}

// The scene with a car ahead and a pole behind on the left.
inline SurfaceScene withCar(SurfaceScene scene) {
  scene.boxes.push_back({{10.0, -1.0, -1.0}, {14.5, 1.0, 1.5}});
  scene.boxes.push_back({{-8.0, 5.0, -1.0}, {-7.7, 5.3, 3.0}});
  return scene;
}

}  // namespace surface_test
