// Simulated scans: HDL-64E geometry per laser on flat ground, range limits, noise statistics,
// determinism, the packed XYZIRT layout, the SICK and stereo models, and the ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/world.h"
#include "sim_standard_worlds.h"

namespace ladar_perception {
namespace sim {
namespace {

const World& standard(const std::string& name) { return cachedStandardWorld(name, 9); }

Eigen::Isometry3d at(double x, double y, double z) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  return p;
}

struct Point {
  float x, y, z, intensity, time;
  int ring;
};

std::vector<Point> points(const SimulatedScan& scan) {
  PointCloudView view;
  std::string error;
  EXPECT_TRUE(scan.cloud.view(&view, &error)) << error;
  std::vector<Point> out;
  const FieldAccessor time = view.field("time");
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    out.push_back({p.x(), p.y(), p.z(), view.intensity(i), time.read<float>(view.pointData(i)),
                   view.ring(i)});
  }
  return out;
}

TEST(SimScan, VelodyneLayoutIsTheDriversXYZIRT) {
  SimulatedScan scan;
  simulateVelodyneRevolution(standard("flat"), at(0, 0, 1.9), VelodyneModel::hdl64e(), 1, &scan);
  const CloudLayout& l = scan.cloud.layout;
  ASSERT_EQ(l.fields.size(), 6u);
  EXPECT_EQ(l.point_step, 22u);
  const char* names[] = {"x", "y", "z", "intensity", "ring", "time"};
  const uint32_t offsets[] = {0, 4, 8, 12, 16, 18};
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(l.fields[k].name, names[k]);
    EXPECT_EQ(l.fields[k].offset, offsets[k]);
  }
  EXPECT_EQ(l.fields[4].datatype, static_cast<uint8_t>(FieldType::kUInt16));
  EXPECT_EQ(l.height, 1u);
  EXPECT_EQ(scan.truth.size(), scan.cloud.size());
  EXPECT_EQ(scan.cloud.data.size(), scan.cloud.size() * 22);
  const auto pts = points(scan);
  ASSERT_FALSE(pts.empty());
  for (const Point& p : pts) {
    ASSERT_GE(p.time, 0.f);
    ASSERT_LT(p.time, 0.1f);
    ASSERT_GE(p.ring, 0);
    ASSERT_LT(p.ring, 64);
    ASSERT_GT(p.intensity, 0.f);
  }
  EXPECT_EQ(hdl64eElevationsDeg().size(), 64u);
  EXPECT_NEAR(hdl64eElevationsDeg().front(), -24.8f, 0.05f);
  EXPECT_NEAR(hdl64eElevationsDeg().back(), 2.0f, 0.05f);
}

// Noise free, every downward laser hits flat ground at h / tan(-elevation) on every azimuth
// step, when that is within [min_range, max_range]; upward lasers see nothing.
TEST(SimScan, EachLaserHitsFlatGroundWhereItsElevationSays) {
  VelodyneModel model = VelodyneModel::hdl64e(NoiseProfile::kNone);
  const double h = 1.9;
  SimulatedScan scan;
  simulateVelodyneRevolution(standard("flat"), at(5.0, 3.0, h), model, 1, &scan);
  std::vector<int> per_ring(64, 0);
  for (const Point& p : points(scan)) {
    const double e = model.elevations_deg[p.ring] * M_PI / 180.0;
    ASSERT_LT(e, 0.0);
    const double expected_r = h / std::tan(-e);
    EXPECT_NEAR(std::hypot(p.x, p.y), expected_r, 2e-5 * expected_r) << "ring " << p.ring;
    EXPECT_NEAR(p.z, -h, 1e-4);
    ++per_ring[p.ring];
  }
  for (int ring = 0; ring < 64; ++ring) {
    const double e = model.elevations_deg[ring] * M_PI / 180.0;
    const double range = e < 0 ? h / std::sin(-e) : 1e9;
    const bool in_range = range >= model.min_range && range <= model.max_range;
    EXPECT_EQ(per_ring[ring], in_range ? model.azimuth_steps : 0) << "ring " << ring;
  }
  for (uint8_t c : scan.truth) ASSERT_EQ(c, static_cast<uint8_t>(SurfaceClass::kRoad));
}

TEST(SimScan, MinAndMaxRangeAreHonouredWithNoise) {
  VelodyneModel model = VelodyneModel::hdl64e();
  model.min_range = 6.0;
  model.max_range = 25.0;
  model.noise_sigma = 0.5;
  SimulatedScan scan;
  simulateVelodyneRevolution(standard("urban"), standard("urban").drivePose(3.0) * at(0, 0, 1.9),
                             model, 4, &scan);
  ASSERT_GT(scan.cloud.size(), 10000u);
  double lo = 1e9, hi = 0;
  for (const Point& p : points(scan)) {
    const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    lo = std::min(lo, r);
    hi = std::max(hi, r);
  }
  EXPECT_GE(lo, 6.0 - 1e-4);
  EXPECT_LE(hi, 25.0 + 1e-4);
  EXPECT_LT(lo, 6.5);
  EXPECT_GT(hi, 24.0);
}

// Range errors against the analytic flat-ground range: zero mean, standard deviation sigma.
TEST(SimScan, NoiseStatisticsMatchSigma) {
  for (double sigma : {0.2, 0.02}) {
    VelodyneModel model = VelodyneModel::hdl64e();
    model.noise_sigma = sigma;
    const double h = 1.9;
    SimulatedScan scan;
    simulateVelodyneRevolution(standard("flat"), at(0, 0, h), model, 77, &scan);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (const Point& p : points(scan)) {
      const double e = model.elevations_deg[p.ring] * M_PI / 180.0;
      const double truth = h / std::sin(-e);
      if (truth < model.min_range + 5 * sigma || truth > model.max_range - 5 * sigma) continue;
      const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
      sum += r - truth;
      sum2 += (r - truth) * (r - truth);
      ++n;
    }
    ASSERT_GT(n, 50000);
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    EXPECT_LT(std::abs(mean), 4.0 * sigma / std::sqrt(n)) << sigma;
    EXPECT_NEAR(sd, sigma, 0.02 * sigma) << sigma;
  }
  EXPECT_DOUBLE_EQ(VelodyneModel::hdl64e().noise_sigma, 0.2);  // Table 4.1
  EXPECT_DOUBLE_EQ(VelodyneModel::hdl64e(NoiseProfile::kDatasheet).noise_sigma, 0.02);
}

TEST(SimScan, DeterministicForASeed) {
  const World& w = standard("urban");
  const Eigen::Isometry3d pose = w.drivePose(4.0) * at(0, 0, 1.9);
  SimulatedScan a, b, c;
  simulateVelodyneRevolution(w, pose, VelodyneModel::hdl64e(), 5, &a);
  simulateVelodyneRevolution(w, pose, VelodyneModel::hdl64e(), 5, &b);
  simulateVelodyneRevolution(w, pose, VelodyneModel::hdl64e(), 6, &c);
  EXPECT_EQ(a.cloud.data, b.cloud.data);
  EXPECT_EQ(a.truth, b.truth);
  EXPECT_NE(a.cloud.data, c.cloud.data);
  // A moving revolution that does not move is the static one.
  SimulatedScan d;
  simulateVelodyneRevolution(w, pose, pose, VelodyneModel::hdl64e(), 5, &d);
  EXPECT_EQ(a.cloud.data, d.cloud.data);
  // Reusing the output keeps results identical.
  simulateVelodyneRevolution(w, pose, VelodyneModel::hdl64e(), 6, &b);
  EXPECT_EQ(b.cloud.data, c.cloud.data);
}

// What the ground-extraction evaluation relies on: from the urban drive the scan sees road,
// sidewalk, curb faces, cars, walls, poles and the person, with truth per point.
TEST(SimScan, UrbanDriveSeesTheFeatures) {
  const World& w = standard("urban");
  SimulatedScan scan;
  simulateVelodyneRevolution(w, w.drivePose(0.0) * at(0, 0, 1.9),
                             VelodyneModel::hdl64e(NoiseProfile::kDatasheet), 1, &scan);
  std::vector<int> counts(256, 0);
  for (uint8_t c : scan.truth) ++counts[c];
  for (SurfaceClass c : {SurfaceClass::kRoad, SurfaceClass::kSidewalk, SurfaceClass::kCurb,
                         SurfaceClass::kCar, SurfaceClass::kWall, SurfaceClass::kPole,
                         SurfaceClass::kPerson, SurfaceClass::kTerrain}) {
    EXPECT_GT(counts[static_cast<int>(c)], 5) << className(c);
  }
  EXPECT_EQ(counts[255], 0);
}

TEST(SimScan, PotholesAndHillAreVisibleFromTheirDrives) {
  {
    const World& w = standard("potholes");
    int pothole = 0;
    SimulatedScan scan;
    for (double t = 0; t < w.driveDuration(); t += 4.0) {
      simulateVelodyneRevolution(w, w.drivePose(t) * at(0, 0, 1.9), VelodyneModel::hdl64e(), 1, &scan);
      for (uint8_t c : scan.truth) pothole += c == static_cast<uint8_t>(SurfaceClass::kPothole);
    }
    EXPECT_GT(pothole, 200);
  }
  {
    const World& w = standard("hillside");
    SimulatedScan scan;
    simulateVelodyneRevolution(w, w.drivePose(8.0) * at(0, 0, 1.9), VelodyneModel::hdl64e(), 1, &scan);
    int car = 0, curb = 0;
    for (uint8_t c : scan.truth) {
      car += c == static_cast<uint8_t>(SurfaceClass::kCar);
      curb += c == static_cast<uint8_t>(SurfaceClass::kCurb);
    }
    EXPECT_GT(car, 50);
    EXPECT_EQ(curb, 0);
  }
}

// LMS-291 tilted down to meet the ground 10 m ahead (thesis 4.2.1).
TEST(SimScan, SickTiltedDownMeetsTheGround10mAhead) {
  SickModel model = SickModel::lms291(NoiseProfile::kNone);
  EXPECT_EQ(model.beams(), 361);
  const double h = 1.2;
  Eigen::Isometry3d pose = at(0, 0, h);
  pose.linear() = Eigen::AngleAxisd(std::atan2(h, 10.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  SimulatedLaserScan scan;
  simulateSickScan(standard("flat"), pose, model, 1, &scan);
  ASSERT_EQ(scan.ranges.size(), 361u);
  EXPECT_FLOAT_EQ(scan.angle_min, static_cast<float>(-M_PI / 2));
  EXPECT_NEAR(scan.angle_max, M_PI / 2, 1e-6);
  EXPECT_NEAR(scan.ranges[180], std::hypot(10.0, h), 1e-4);
  EXPECT_EQ(scan.beam_truth[180], static_cast<uint8_t>(SurfaceClass::kRoad));
  // The beams at +-90 degrees stay level with the sensor: no return.
  EXPECT_TRUE(std::isinf(scan.ranges[0]));
  EXPECT_EQ(scan.beam_truth[0], static_cast<uint8_t>(SurfaceClass::kNone));
  EXPECT_EQ(scan.points.cloud.size(), scan.points.truth.size());
  std::size_t finite = 0;
  for (float r : scan.ranges) finite += std::isfinite(r);
  EXPECT_EQ(scan.points.cloud.size(), finite);
  // Every return, put back in the world, is on the ground.
  PointCloudView view;
  ASSERT_TRUE(scan.points.cloud.view(&view));
  for (std::size_t i = 0; i < view.size(); ++i) {
    EXPECT_NEAR((pose * view.xyz(i).cast<double>()).z(), 0.0, 1e-4);
  }
}

TEST(SimScan, SickScanningAVerticalPlane) {
  SickModel model = SickModel::lms291(NoiseProfile::kNone);
  Eigen::Isometry3d pose = at(0, 0, 1.5);
  pose.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  SimulatedLaserScan scan;
  simulateSickScan(standard("alley"), pose, model, 1, &scan);
  // Beam -90 degrees points straight down; beam +90 straight up (sky).
  EXPECT_NEAR(scan.ranges.front(), 1.5, 1e-6);
  EXPECT_TRUE(std::isinf(scan.ranges.back()));
  // Beam 0 looks along the alley: its ground hits are road, never wall.
  for (std::size_t b = 0; b < scan.ranges.size(); ++b) {
    if (std::isfinite(scan.ranges[b])) {
      EXPECT_EQ(scan.beam_truth[b], static_cast<uint8_t>(SurfaceClass::kRoad));
    }
  }
}

TEST(SimScan, SickNoiseAndLimits) {
  SickModel model = SickModel::lms291();
  EXPECT_DOUBLE_EQ(model.noise_sigma, 0.1);
  EXPECT_DOUBLE_EQ(model.max_range, 80.0);
  EXPECT_DOUBLE_EQ(model.min_range, 0.5);
  SimulatedLaserScan scan;
  const World& w = standard("urban");
  simulateSickScan(w, w.drivePose(2.0) * at(1.0, 0, 0.5), model, 3, &scan);
  int returns = 0;
  for (float r : scan.ranges) {
    if (!std::isfinite(r)) continue;
    ++returns;
    EXPECT_GE(r, 0.5f);
    EXPECT_LE(r, 80.f);
  }
  EXPECT_GT(returns, 100);
}

TEST(SimScan, StereoDepthCloud) {
  const StereoModel model = StereoModel::bumblebee();
  EXPECT_DOUBLE_EQ(model.min_range, 2.0);
  EXPECT_DOUBLE_EQ(model.max_range, 12.0);
  EXPECT_DOUBLE_EQ(model.noise_sigma, 0.5);
  Eigen::Isometry3d pose = at(0, 0, 1.5);
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  SimulatedScan scan;
  simulateStereoFrame(standard("flat"), pose, model, 2, &scan);
  ASSERT_GT(scan.cloud.size(), 1000u);
  EXPECT_EQ(scan.cloud.layout.point_step, 12u);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  for (std::size_t i = 0; i < view.size(); ++i) {
    const float r = view.xyz(i).norm();
    EXPECT_GE(r, 2.f);
    EXPECT_LE(r, 12.f);
    EXPECT_GT(view.xyz(i).x(), 0.f);
  }
}

TEST(SimScan, StereoDepthNoiseGrowsWithDepthSquared) {
  // Looking straight down at flat ground, every pixel's depth (its x in the camera's body frame)
  // is the height. The spread of the measured depth follows sigma_d z^2 / (f b), from the model's
  // Table 4.1 0.5 m at its 12 m maximum range; its values are the sub-pixel disparity steps.
  const StereoModel model = StereoModel::bumblebee();
  EXPECT_NEAR(model.depthSigma(model.max_range), model.noise_sigma, 1e-12);
  EXPECT_NEAR(model.depthSigma(3.0), model.noise_sigma * 9.0 / 144.0, 1e-12);
  const double fb = model.focalPixels() * model.baseline;
  for (double height : {3.0, 9.0}) {
    Eigen::Isometry3d pose = at(0, 0, height);
    pose.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
    SimulatedScan scan;
    simulateStereoFrame(standard("flat"), pose, model, 4, &scan);
    PointCloudView view;
    ASSERT_TRUE(scan.cloud.view(&view));
    ASSERT_GT(view.size(), 10000u);
    double sum = 0, sum2 = 0;
    for (std::size_t i = 0; i < view.size(); ++i) {
      const double depth = view.xyz(i).x();
      const double steps = fb / depth / model.disparity_step_px;  // a whole number of steps
      EXPECT_NEAR(steps, std::round(steps), 1e-3 * steps) << depth;
      sum += depth - height;
      sum2 += (depth - height) * (depth - height);
    }
    const double n = static_cast<double>(view.size());
    const double sigma = std::sqrt(sum2 / n - (sum / n) * (sum / n));
    EXPECT_NEAR(sigma, model.depthSigma(height), 0.1 * model.depthSigma(height)) << height;
  }
  // Without noise: exact depths, no rounding.
  Eigen::Isometry3d pose = at(0, 0, 5.0);
  pose.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  SimulatedScan scan;
  simulateStereoFrame(standard("flat"), pose, StereoModel::bumblebee(NoiseProfile::kNone), 4, &scan);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  ASSERT_GT(view.size(), 10000u);
  for (std::size_t i = 0; i < view.size(); i += 97) EXPECT_NEAR(view.xyz(i).x(), 5.0, 1e-4);
}

TEST(SimScan, InvalidModelsGiveEmptyScans) {
  VelodyneModel model = VelodyneModel::hdl64e();
  model.azimuth_steps = 0;
  EXPECT_FALSE(model.validate().empty());
  SimulatedScan scan;
  simulateVelodyneRevolution(standard("flat"), at(0, 0, 2), model, 1, &scan);
  EXPECT_EQ(scan.cloud.size(), 0u);
  EXPECT_TRUE(scan.truth.empty());
  PointCloudView view;
  EXPECT_TRUE(scan.cloud.view(&view));
}


// With motion, each firing is cast from the pose interpolated to its time and its points are in
// the sensor frame of that moment: azimuth step k equals a static revolution from that pose.
TEST(SimScan, MovingRevolutionUsesThePoseOfEachFiring) {
  const World& w = standard("urban");
  VelodyneModel model = VelodyneModel::hdl64e(NoiseProfile::kNone);
  model.azimuth_steps = 360;
  const Eigen::Isometry3d a = w.drivePose(2.0) * at(0, 0, 1.9);
  const Eigen::Isometry3d b = w.drivePose(2.1) * at(0, 0, 1.9);
  SimulatedScan moving, still;
  simulateVelodyneRevolution(w, a, b, model, 1, &moving);
  const auto pm = points(moving);
  for (int k : {0, 90, 180, 359}) {
    const double f = static_cast<double>(k) / model.azimuth_steps;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(a.linear()).slerp(f, Eigen::Quaterniond(b.linear())).toRotationMatrix();
    pose.translation() = (1 - f) * a.translation() + f * b.translation();
    simulateVelodyneRevolution(w, pose, model, 1, &still);
    const auto ps = points(still);
    const float time = static_cast<float>(k * model.period() / model.azimuth_steps);
    std::vector<Point> m_k, s_k;
    for (const Point& p : pm) if (p.time == time) m_k.push_back(p);
    for (const Point& p : ps) if (p.time == time) s_k.push_back(p);
    ASSERT_EQ(m_k.size(), s_k.size()) << k;
    ASSERT_GT(m_k.size(), 30u);
    for (std::size_t i = 0; i < m_k.size(); ++i) {
      EXPECT_EQ(m_k[i].ring, s_k[i].ring);
      EXPECT_NEAR(m_k[i].x, s_k[i].x, 1e-4);
      EXPECT_NEAR(m_k[i].y, s_k[i].y, 1e-4);
      EXPECT_NEAR(m_k[i].z, s_k[i].z, 1e-4);
    }
  }
}

}  // namespace
}  // namespace sim
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
