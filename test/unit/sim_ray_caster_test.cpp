// The ray caster: analytic ranges on flat ground, agreement with a cell-by-cell traversal on
// every standard world, and the ground truth of faces (curb, pothole, slopes, obstacles).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "ladar_perception/sim/random.h"
#include "ladar_perception/sim/ray_caster.h"
#include "ladar_perception/sim/world.h"
#include "sim_standard_worlds.h"

namespace ladar_perception {
namespace sim {
namespace {

const World& standard(const std::string& name) { return cachedStandardWorld(name, 5); }

Eigen::Vector3d direction(double azimuth, double elevation) {
  return Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                         std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
}

TEST(SimRayCaster, FlatGroundAnalyticRange) {
  const World& w = standard("flat");
  const Eigen::Vector3d origin(3.21, -1.7, 2.0);
  for (double el_deg : {-1.5, -2.0, -5.0, -10.0, -24.8, -45.0, -89.0}) {
    for (double az = -M_PI; az < M_PI; az += 0.37) {
      RayHit hit;
      const double el = el_deg * M_PI / 180.0;
      const double expected = 2.0 / std::sin(-el);
      const bool hits = castRay(w, origin, direction(az, el), 200.0, &hit);
      if (expected > 200.0) {
        EXPECT_FALSE(hits);
        continue;
      }
      ASSERT_TRUE(hits) << el_deg << " " << az;
      EXPECT_NEAR(hit.range, expected, 1e-9);
      EXPECT_EQ(hit.surface, SurfaceClass::kRoad);
      EXPECT_FLOAT_EQ(hit.normal.z(), 1.f);
    }
  }
  // Straight down.
  RayHit hit;
  ASSERT_TRUE(castRay(w, origin, Eigen::Vector3d(0, 0, -1), 10.0, &hit));
  EXPECT_NEAR(hit.range, 2.0, 1e-12);
}

TEST(SimRayCaster, MaxRangeAndMissesAreHonoured) {
  const World& w = standard("flat");
  const Eigen::Vector3d origin(0, 0, 2.0);
  RayHit hit;
  const double el = -5.0 * M_PI / 180.0;  // ground at 22.9 m
  EXPECT_FALSE(castRay(w, origin, direction(0.3, el), 22.0, &hit));
  EXPECT_TRUE(castRay(w, origin, direction(0.3, el), 23.0, &hit));
  EXPECT_FALSE(castRay(w, origin, direction(0.3, 0.01), 1000.0, &hit));  // upwards: sky
  EXPECT_FALSE(castRay(w, origin, direction(0.3, 0.0), 1000.0, &hit));   // horizontal: leaves
  // Below the surface: a ray starting inside a column sees nothing.
  EXPECT_FALSE(castRay(w, Eigen::Vector3d(0, 0, -0.5), direction(0.3, -0.2), 100.0, &hit));
  // Bad input does not crash.
  EXPECT_FALSE(castRay(w, Eigen::Vector3d(NAN, 0, 2), direction(0, -0.2), 100.0, &hit));
  EXPECT_FALSE(castRay(w, origin, direction(0, -0.2), -1.0, &hit));
  World empty;
  EXPECT_FALSE(castRay(empty, origin, direction(0, -0.2), 100.0, &hit));
}

// The pyramid traversal finds exactly what a plain cell-by-cell traversal finds.
TEST(SimRayCaster, PyramidMatchesCellByCellTraversal) {
  for (const std::string& name : standardWorldNames()) {
    const World& w = standard(name);
    Rng rng(11);
    int hits = 0;
    for (int k = 0; k < 4000; ++k) {
      const Eigen::Isometry3d pose = w.drivePose(rng.uniform(0.0, w.driveDuration()));
      const Eigen::Vector3d origin = pose * Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1),
                                                            rng.uniform(0.3, 3.0));
      const Eigen::Vector3d dir = direction(rng.uniform(-M_PI, M_PI), rng.uniform(-0.6, 0.05));
      RayHit fast, slow, hinted;
      const bool a = castRay(w, origin, dir, 120.0, &fast);
      const bool b = castRayBruteForce(w, origin, dir, 120.0, &slow);
      ASSERT_EQ(a, b) << name << " ray " << k;
      // Any start level gives the same hit.
      const int level = (k % 3 == 0) ? startLevelFor(w, origin) : rng.uniformInt(0, w.pyramidLevels() - 1);
      ASSERT_EQ(castRay(w, origin, dir, 120.0, level, &hinted), a) << name << " ray " << k;
      if (a) {
        EXPECT_EQ(hinted.range, fast.range) << name << " ray " << k;
      }
      if (!a) continue;
      ++hits;
      EXPECT_NEAR(fast.range, slow.range, 1e-9) << name << " ray " << k;
      EXPECT_EQ(fast.surface, slow.surface) << name << " ray " << k;
      EXPECT_TRUE(fast.normal.isApprox(slow.normal)) << name << " ray " << k;
    }
    EXPECT_GT(hits, 2000) << name;
  }
}

TEST(SimRayCaster, CurbFaceIsCurb) {
  const World& w = standard("urban");
  // Find a stretch of the south gutter with no parked car.
  double x = 0.0;
  for (x = 0.0; x < 100.0; x += 0.5) {
    bool clear = true;
    for (double y = -5.0; y < -1.0; y += 0.1) clear &= w.surfaceClass(x, y) == SurfaceClass::kRoad;
    if (clear) break;
  }
  ASSERT_LT(x, 100.0);
  // Horizontal ray 12 cm above the gutter towards the curb at y = -5.
  RayHit hit;
  ASSERT_TRUE(castRay(w, Eigen::Vector3d(x, -3.0, 0.12), Eigen::Vector3d(0, -1, 0), 10.0, &hit));
  EXPECT_NEAR(hit.range, 2.0, 1e-6);
  EXPECT_EQ(hit.surface, SurfaceClass::kCurb);
  EXPECT_FLOAT_EQ(hit.normal.y(), 1.f);
  // From above, the sidewalk's top is sidewalk.
  ASSERT_TRUE(castRay(w, Eigen::Vector3d(x, -3.0, 2.0), direction(-M_PI / 2, -0.5), 20.0, &hit));
  EXPECT_EQ(hit.surface, SurfaceClass::kSidewalk);
  // and the road is road.
  ASSERT_TRUE(castRay(w, Eigen::Vector3d(x, -3.0, 2.0), Eigen::Vector3d(0, 0, -1), 20.0, &hit));
  EXPECT_EQ(hit.surface, SurfaceClass::kRoad);
}

// Rays onto the hillside from the drive read as terrain (or a tree/car), never as curbs.
TEST(SimRayCaster, SlopesDoNotReadAsCurbs) {
  const World& w = standard("hillside");
  Rng rng(3);
  int terrain = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Isometry3d pose = w.drivePose(rng.uniform(0.0, w.driveDuration()));
    const Eigen::Vector3d origin = pose * Eigen::Vector3d(0, 0, 1.9);
    RayHit hit;
    if (!castRay(w, origin, pose.linear() * direction(rng.uniform(-M_PI, M_PI), rng.uniform(-0.43, 0.03)),
                 60.0, &hit)) {
      continue;
    }
    EXPECT_NE(hit.surface, SurfaceClass::kCurb);
    terrain += hit.surface == SurfaceClass::kTerrain;
  }
  EXPECT_GT(terrain, 15000);
}

TEST(SimRayCaster, PotholeHitsArePothole) {
  const World& w = standard("potholes");
  // The pothole straight ahead of the drive's end at (132, 0.3).
  RayHit hit;
  ASSERT_TRUE(castRay(w, Eigen::Vector3d(132.0, 0.3, 2.0), Eigen::Vector3d(0, 0, -1), 10.0, &hit));
  EXPECT_EQ(hit.surface, SurfaceClass::kPothole);
  EXPECT_GT(hit.range, 2.1);
  // A grazing ray that dips into it hits its far wall or bottom: pothole either way.
  const Eigen::Vector3d target(132.0, 0.3, -0.1);
  const Eigen::Vector3d origin(122.0, 0.3, 1.9);
  ASSERT_TRUE(castRay(w, origin, (target - origin).normalized(), 60.0, &hit));
  EXPECT_EQ(hit.surface, SurfaceClass::kPothole);
}

TEST(SimRayCaster, ObstaclesCarryTheirClass) {
  const World& w = standard("alley");
  RayHit hit;
  ASSERT_TRUE(castRay(w, Eigen::Vector3d(10, 0, 1.9), Eigen::Vector3d(0, 1, 0), 60.0, &hit));
  EXPECT_EQ(hit.surface, SurfaceClass::kWall);
  EXPECT_NEAR(hit.range, 3.0, 1e-9);
  EXPECT_FLOAT_EQ(hit.normal.y(), -1.f);
}

}  // namespace
}  // namespace sim
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
