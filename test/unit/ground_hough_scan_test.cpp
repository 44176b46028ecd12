// LaserScan projection and the Hough ground fit on whole 2D ladar scans through a sensor pose.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ground_hough_scene.h"
#include "ladar_perception/cloud/laser_scan.h"
#include "ladar_perception/ground/hough_ground.h"

namespace lp = ladar_perception;
using hough_test::VerticalScene;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

lp::LaserScanView viewOf(const std::vector<float>& ranges, float angle_min, float increment,
                         float range_min = 0.5f, float range_max = 80.f) {
  lp::LaserScanView v;
  v.angle_min = angle_min;
  v.angle_increment = increment;
  v.range_min = range_min;
  v.range_max = range_max;
  v.ranges = ranges.data();
  v.size = ranges.size();
  return v;
}

// A SICK scanning the vertical plane: its y axis up (rolled +90 degrees about x), `pitch`
// (positive nose down) and mounted `height` above the ground frame's origin.
lp::SensorPose verticalMount(float height, float pitch = 0.f) {
  lp::SensorPose pose;
  pose.sensor_to_ground.linear() =
      (Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY()) *
       Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitX()))
          .toRotationMatrix();
  pose.sensor_to_ground.translation() = Eigen::Vector3f(0.f, 0.f, height);
  return pose;
}

TEST(LaserScan, ProjectionAndInvalidReturns) {
  const std::vector<float> ranges = {1.f, 2.f, kNaN, kInf, -kInf, 0.1f, 90.f, 80.f, 0.5f};
  const lp::LaserScanView scan = viewOf(ranges, 0.f, static_cast<float>(M_PI / 4));
  std::string error;
  ASSERT_TRUE(lp::validateLaserScan(scan, &error)) << error;
  lp::LaserScanProjector projector;
  std::vector<float> x(ranges.size()), y(ranges.size());
  EXPECT_EQ(projector.project(scan, x.data(), y.data()), 4u);
  EXPECT_NEAR(x[0], 1.f, 1e-6);
  EXPECT_NEAR(y[0], 0.f, 1e-6);
  EXPECT_NEAR(x[1], std::sqrt(2.f), 1e-5);
  EXPECT_NEAR(y[1], std::sqrt(2.f), 1e-5);
  for (int k : {2, 3, 4, 5, 6}) EXPECT_TRUE(std::isnan(x[k])) << k;  // NaN, +-Inf, out of range
  EXPECT_NEAR(x[7], 80.f * std::cos(7 * M_PI / 4), 1e-3);                // range_max is valid
  EXPECT_NEAR(x[8], 0.5f * std::cos(2 * M_PI), 1e-6);                    // range_min is valid

  // The packed form: organised, intensity carried, NaN points for invalid returns.
  std::vector<float> intensities(ranges.size(), 7.f);
  lp::LaserScanView with_i = scan;
  with_i.intensities = intensities.data();
  lp::PackedCloud cloud;
  cloud.layout = lp::laserScanLayout(static_cast<uint32_t>(ranges.size()));
  cloud.data.resize(cloud.layout.row_step);
  EXPECT_EQ(projector.projectPacked(with_i, cloud.data.data()), 4u);
  lp::PointCloudView view;
  ASSERT_TRUE(cloud.view(&view, &error)) << error;
  ASSERT_EQ(view.size(), ranges.size());
  EXPECT_NEAR(view.xyz(1).x(), std::sqrt(2.f), 1e-5);
  EXPECT_TRUE(std::isnan(view.xyz(3).z()));
  EXPECT_EQ(view.intensity(0), 7.f);

  // A new geometry refreshes the cached table.
  const lp::LaserScanView turned = viewOf(ranges, static_cast<float>(M_PI / 2), static_cast<float>(M_PI / 4));
  projector.project(turned, x.data(), y.data());
  EXPECT_NEAR(x[0], 0.f, 1e-6);
  EXPECT_NEAR(y[0], 1.f, 1e-6);
}

TEST(LaserScan, BadGeometryIsRejectedWithAReason) {
  const std::vector<float> ranges(10, 1.f);
  std::string error;
  EXPECT_FALSE(lp::validateLaserScan(viewOf(ranges, 0.f, kNaN), &error));
  EXPECT_NE(error.find("angle"), std::string::npos);
  EXPECT_FALSE(lp::validateLaserScan(viewOf(ranges, 0.f, 0.f), &error));
  EXPECT_FALSE(lp::validateLaserScan(viewOf(ranges, 0.f, 1.f), &error));  // 9 rad sweep
  EXPECT_NE(error.find("turn"), std::string::npos);
  EXPECT_FALSE(lp::validateLaserScan(viewOf(ranges, 0.f, 0.01f, 5.f, 1.f), &error));
  EXPECT_NE(error.find("range"), std::string::npos);
  EXPECT_FALSE(lp::validateLaserScan(viewOf(ranges, 0.f, 0.01f, 0.f, kInf), &error));
  lp::LaserScanView no_data = viewOf(ranges, 0.f, 0.01f);
  no_data.ranges = nullptr;
  EXPECT_FALSE(lp::validateLaserScan(no_data, &error));
  // An empty scan is valid (a sensor may publish one), whatever its increment.
  const std::vector<float> none;
  EXPECT_TRUE(lp::validateLaserScan(viewOf(none, 0.f, 0.f), &error));

  lp::HoughGround hough;
  lp::ScanGroundResult result;
  EXPECT_FALSE(hough.classify(viewOf(ranges, 0.f, kNaN), verticalMount(1.f), &result, &error));
  EXPECT_EQ(result.classification.size(), 0u);
  EXPECT_FALSE(result.fit.valid);
}

// The LMS-291 in the vertical plane from straight down to straight up, 361 returns.
struct SickScan {
  std::vector<float> ranges;
  std::vector<uint8_t> truth;
  lp::LaserScanView view() const {
    return viewOf(ranges, static_cast<float>(-M_PI / 2), static_cast<float>(M_PI / 360));
  }
};

SickScan sickScan(const VerticalScene& scene) {
  SickScan s;
  scene.scan(-M_PI / 2, M_PI / 360, 361, &s.ranges, &s.truth);
  return s;
}

TEST(HoughGroundScan, FlatGroundThroughTheMount) {
  VerticalScene scene;
  scene.sensor_height = 1.2;
  scene.addGroundLine(0.0, 0.0);
  const SickScan s = sickScan(scene);
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  ASSERT_TRUE(hough.classify(s.view(), verticalMount(1.2f), &result));
  ASSERT_TRUE(result.fit.valid);
  EXPECT_TRUE(result.signed_r);
  EXPECT_NEAR(result.direction.x(), 1.f, 1e-6);
  EXPECT_NEAR(result.fit.ground, 0.f, 2e-4);
  EXPECT_NEAR(result.fit.slope, 0.f, 2e-5);
  ASSERT_EQ(result.classification.size(), 361u);
  for (std::size_t k = 0; k < 361; ++k) {
    EXPECT_EQ(result.classification.labels[k], s.truth[k] == 2 ? lp::kLabelUnknown : lp::kLabelGround) << k;
  }
}

// tf says 1.2 m but the sensor is 1.5 m above the local ground and pitched 4 degrees nose down
// on a 6% uphill: the 2-DOF line absorbs the height error (Ground* = -0.3 m).
TEST(HoughGroundScan, PitchedMountAndWrongHeight) {
  VerticalScene scene;
  scene.sensor_height = 1.5;
  scene.addGroundLine(0.0, 0.06);
  const float pitch = static_cast<float>(4.0 * M_PI / 180.0);
  // Cast in the sensor's own plane: the scan angle a is the elevation a - pitch in the world.
  SickScan s;
  s.ranges.resize(361);
  s.truth.resize(361);
  for (int k = 0; k < 361; ++k) {
    uint8_t t = 2;
    const double range = scene.cast(-M_PI / 2 + k * M_PI / 360 - pitch, &t);
    s.ranges[k] = static_cast<float>(range);
    s.truth[k] = std::isfinite(range) ? t : 2;
  }
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  ASSERT_TRUE(hough.classify(s.view(), verticalMount(1.2f, pitch), &result));
  ASSERT_TRUE(result.fit.valid);
  EXPECT_NEAR(result.fit.ground, -0.3f, 1e-3);
  EXPECT_NEAR(result.fit.slope, 0.06f, 1e-4);
  for (std::size_t k = 0; k < 361; ++k) {
    if (s.truth[k] == 0) {
      EXPECT_EQ(result.classification.labels[k], lp::kLabelGround) << k;
    }
  }
}

// A scan plane that sees the ground ahead and behind (the lower half circle): r is signed
// along the plane, and one line fits both sides.
TEST(HoughGroundScan, SignedRangeAlongTheScanPlane) {
  VerticalScene scene;
  scene.sensor_height = 2.0;
  scene.addGroundLine(0.0, -0.05);
  std::vector<float> ranges;
  std::vector<uint8_t> truth;
  scene.scan(-M_PI, M_PI / 360, 361, &ranges, &truth);  // from backwards, through down, to ahead
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  ASSERT_TRUE(hough.classify(viewOf(ranges, static_cast<float>(-M_PI), static_cast<float>(M_PI / 360)),
                             verticalMount(2.f), &result));
  ASSERT_TRUE(result.fit.valid);
  EXPECT_NEAR(result.fit.slope, -0.05f, 1e-4);
  EXPECT_NEAR(result.fit.ground, 0.f, 1e-3);
  EXPECT_LT(result.fit.r_min, -5.f);
  EXPECT_GT(result.fit.r_max, 5.f);
  EXPECT_LT(result.r[10], 0.f);   // behind
  EXPECT_GT(result.r[350], 0.f);  // ahead
}

// A scanner tilted down 10 degrees (the thesis's other SICKs) is not a vertical scan: r is the
// horizontal distance and flat ground is still one line (Height 0 at every r).
TEST(HoughGroundScan, TiltedScannerUsesHorizontalDistance) {
  const float tilt = static_cast<float>(10.0 * M_PI / 180.0);
  const float height = 1.8f;
  std::vector<float> ranges(181);
  for (int k = 0; k < 181; ++k) {
    const double a = -M_PI / 2 + k * M_PI / 180;
    // Beam (cos a, sin a, 0) pitched down by tilt: z component -cos(a) sin(tilt).
    const double dz = -std::cos(a) * std::sin(tilt);
    ranges[k] = dz < -1e-3 ? static_cast<float>(height / -dz) : kInf;
  }
  lp::SensorPose pose;
  pose.sensor_to_ground.linear() = Eigen::AngleAxisf(tilt, Eigen::Vector3f::UnitY()).toRotationMatrix();
  pose.sensor_to_ground.translation() = Eigen::Vector3f(0.f, 0.f, height);
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  ASSERT_TRUE(hough.classify(viewOf(ranges, static_cast<float>(-M_PI / 2), static_cast<float>(M_PI / 180)),
                             pose, &result));
  EXPECT_FALSE(result.signed_r);
  ASSERT_TRUE(result.fit.valid);
  EXPECT_NEAR(result.fit.ground, 0.f, 1e-3);
  EXPECT_NEAR(result.fit.slope, 0.f, 1e-4);
  EXPECT_EQ(result.classification.count(lp::kLabelObstacle), 0u);
  EXPECT_GT(result.classification.count(lp::kLabelGround), 100u);
}

TEST(HoughGroundScan, EmptyAndAllNaNScans) {
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  const std::vector<float> none;
  ASSERT_TRUE(hough.classify(viewOf(none, -1.f, 0.01f), verticalMount(1.f), &result));
  EXPECT_EQ(result.classification.size(), 0u);
  EXPECT_FALSE(result.fit.valid);
  const std::vector<float> nan(361, kNaN);
  ASSERT_TRUE(hough.classify(viewOf(nan, -1.f, 0.005f), verticalMount(1.f), &result));
  EXPECT_FALSE(result.fit.valid);
  EXPECT_EQ(result.classification.count(lp::kLabelUnknown), 361u);
  const std::vector<float> inf(361, kInf);
  ASSERT_TRUE(hough.classify(viewOf(inf, -1.f, 0.005f), verticalMount(1.f), &result));
  EXPECT_EQ(result.classification.count(lp::kLabelUnknown), 361u);
}

TEST(HoughGroundScan, ObstacleAheadIsFoundInTheScan) {
  VerticalScene scene;
  scene.sensor_height = 1.2;
  scene.addGroundLine(0.0, 0.02);
  scene.addBox(8.0, 12.0, 0.16, 1.4);  // a car 8 m ahead
  const SickScan s = sickScan(scene);
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  ASSERT_TRUE(hough.classify(s.view(), verticalMount(1.2f), &result));
  ASSERT_TRUE(result.fit.valid);
  EXPECT_NEAR(result.fit.slope, 0.02f, 1e-3);
  int car = 0;
  for (std::size_t k = 0; k < 361; ++k) {
    if (s.truth[k] == 0) {
      EXPECT_EQ(result.classification.labels[k], lp::kLabelGround) << k;
    }
    if (s.truth[k] == 1 && result.height[k] - 0.02f * result.r[k] > 0.25f) {
      EXPECT_EQ(result.classification.labels[k], lp::kLabelObstacle) << k;
      EXPECT_GT(result.classification.p_obstacle[k], 0.5f);
      ++car;
    }
  }
  EXPECT_GT(car, 5);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
