// The lidar table and what reads it: the ground extractor on every sensor's clouds (ring
// field, Ouster's organised rows counted from the top, no ring at all), the mismatch check,
// measured beam tables, the mount estimate and a tilted mount. Data from the simulator.
#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ladar_perception/cloud/laser_elevations.h"
#include "ladar_perception/cloud/lidar_models.h"
#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/plane_fit.h"
#include "ladar_perception/ground/vertical_scan.h"

using namespace ladar_perception;

namespace {

// One revolution of `name` in the middle of `world`'s drive, sensor `height` above base_link,
// rolled and pitched by the given degrees.
sim::SimulatedScan simulate(const std::string& name, const std::string& world_name, sim::NoiseProfile noise,
                            double roll_deg = 0.0, double pitch_deg = 0.0, Eigen::Isometry3d* mount_out = nullptr) {
  EvaluationSensor sensor;
  std::string error;
  EXPECT_TRUE(makeEvaluationSensor(name, noise, &sensor, &error)) << error;
  sensor.tilt(roll_deg, pitch_deg);
  sim::World world;
  EXPECT_TRUE(sim::makeStandardWorld(world_name, 1, &world, &error)) << error;
  sim::SimulatedScan scan;
  sim::simulateVelodyneRevolution(world, world.drivePose(0.5 * world.driveDuration()) * sensor.mount, sensor.model,
                                  7, &scan);
  if (mount_out) *mount_out = sensor.mount;
  return scan;
}

// The returns of an organised scan as a returns-only cloud in Velodyne's layout (x, y, z,
// intensity, ring, time) with the ring counted from the bottom beam; *slot gets each return's
// slot in the organised cloud.
PackedCloud bottomUpReturns(const PackedCloud& organised, std::vector<std::size_t>* slot) {
  PointCloudView view;
  EXPECT_TRUE(organised.view(&view));
  const int rows = static_cast<int>(organised.layout.height);
  slot->clear();
  for (std::size_t i = 0; i < view.size(); ++i) {
    if (!view.xyz(i).isZero()) slot->push_back(i);
  }
  PackedCloud out;
  out.layout = velodyneXYZIRTLayout(static_cast<uint32_t>(slot->size()));
  out.data.assign(slot->size() * out.layout.point_step, 0);
  const FieldDesc* x = findField(out.layout, "x");
  const FieldDesc* y = findField(out.layout, "y");
  const FieldDesc* z = findField(out.layout, "z");
  const FieldDesc* ring = findField(out.layout, "ring");
  for (std::size_t k = 0; k < slot->size(); ++k) {
    uint8_t* p = out.data.data() + k * out.layout.point_step;
    const Eigen::Vector3f q = view.xyz((*slot)[k]);
    writeField(p, *x, q.x());
    writeField(p, *y, q.y());
    writeField(p, *z, q.z());
    writeField(p, *ring, rows - 1 - view.ring((*slot)[k]));
  }
  return out;
}

double f1(const GroundAccuracy& a) {
  return 2.0 * a.groundPrecision() * a.groundRecall() / (a.groundPrecision() + a.groundRecall());
}

}  // namespace

TEST(LidarModels, TableIsConsistent) {
  std::set<std::string> names;
  for (const LidarModel& m : lidarModels()) {
    EXPECT_TRUE(names.insert(m.name).second) << m.name;
    EXPECT_EQ(findLidarModel(m.name), &m);
    EXPECT_NE(lidarModelNames().find(m.name), std::string::npos);
    EXPECT_GE(m.beams(), 16) << m.name;
    EXPECT_LE(m.beams(), 128) << m.name;
    EXPECT_TRUE(std::is_sorted(m.elevations_deg.begin(), m.elevations_deg.end())) << m.name;
    EXPECT_GT(m.minSpacingDeg(), 0.1f) << m.name;
    EXPECT_FALSE(m.source.empty()) << m.name;
    EXPECT_GT(m.max_range, m.min_range) << m.name;
    EXPECT_TRUE(sim::VelodyneModel::fromLidarModel(m, sim::NoiseProfile::kDatasheet).validate().empty()) << m.name;
  }
  for (const char* n : {"hdl64e", "hdl32e", "vlp16", "vlp32c", "os1_32", "os1_64", "os1_128", "os2_128"}) {
    EXPECT_NE(findLidarModel(n), nullptr) << n;
  }
  EXPECT_EQ(findLidarModel("nonesuch"), nullptr);
  EXPECT_EQ(findLidarModel("hdl64e")->elevations_deg, hdl64eElevationsDeg());
  EXPECT_FLOAT_EQ(findLidarModel("vlp16")->elevations_deg.front(), -15.f);
  EXPECT_FLOAT_EQ(findLidarModel("vlp16")->elevations_deg.back(), 15.f);
  EXPECT_EQ(findLidarModel("os1_64")->ring_order, RingOrder::kTopDown);
  EXPECT_TRUE(findLidarModel("os1_64")->organised);
}

TEST(LidarModels, UserTablesAreCheckedAndSorted) {
  LidarModel m;
  std::string error;
  EXPECT_TRUE(lidarModelFromElevations({3.f, -1.f, 1.f}, &m, &error)) << error;
  EXPECT_EQ(m.elevations_deg, (std::vector<float>{-1.f, 1.f, 3.f}));
  EXPECT_FALSE(lidarModelFromElevations({}, &m, &error));
  EXPECT_FALSE(lidarModelFromElevations({1.f, 1.f}, &m, &error));
  EXPECT_NE(error.find("closer"), std::string::npos);
  EXPECT_FALSE(lidarModelFromElevations({1.f, NAN}, &m, &error));
  EXPECT_FALSE(lidarModelFromElevations({1.f, 95.f}, &m, &error));
  EXPECT_FALSE(lidarModelFromElevations(std::vector<float>(129, 0.f), &m, &error));
}

TEST(LidarModels, SparseBeamScaleFollowsTheBeamSpacing) {
  EXPECT_FLOAT_EQ(sparseBeamScale(hdl64eElevationsDeg()), 1.f);
  EXPECT_FLOAT_EQ(sparseBeamScale(findLidarModel("os1_128")->elevations_deg), 1.f);
  const float vlp16 = sparseBeamScale(findLidarModel("vlp16")->elevations_deg);
  const float os1_32 = sparseBeamScale(findLidarModel("os1_32")->elevations_deg);
  EXPECT_GT(vlp16, os1_32);
  EXPECT_GT(os1_32, 1.5f);
  // The scale replaces the previous sensor's: back to the HDL-64E gives the HDL-64E setting.
  const VerticalScanParams base = verticalScanDefaultParams();
  VerticalScanParams p = paramsForLidarModel(base, *findLidarModel("vlp16"));
  EXPECT_NEAR(p.track_max_step, base.track_max_step * vlp16, 1e-6f);
  p = paramsForLidarModel(p, *findLidarModel("os1_32"));
  EXPECT_NEAR(p.track_max_step, base.track_max_step * os1_32, 1e-6f);
  p = paramsForLidarModel(p, *findLidarModel("hdl64e"));
  EXPECT_NEAR(p.track_max_step, base.track_max_step, 1e-6f);
  EXPECT_EQ(p.laser_elevations_deg, hdl64eElevationsDeg());
}

// Ouster's organised cloud numbers its rows from the top beam: the extractor finds that from the
// elevations and labels every return as it labels the same returns numbered from the bottom.
TEST(LidarModels, TopDownRingsLabelLikeBottomUpRings) {
  const LidarModel& os1 = *findLidarModel("os1_64");
  Eigen::Isometry3d mount;
  const sim::SimulatedScan scan = simulate("os1_64", "urban", sim::NoiseProfile::kDatasheet, 0, 0, &mount);
  ASSERT_EQ(scan.cloud.layout.height, 64u);
  ASSERT_EQ(scan.cloud.layout.width, 1024u);
  std::vector<std::size_t> slot;
  const PackedCloud bottom_up = bottomUpReturns(scan.cloud, &slot);
  ASSERT_GT(slot.size(), 20000u);

  SensorPose pose;
  pose.sensor_to_ground = mount.cast<float>();
  VerticalScanGround organised_model, returns_model;
  organised_model.setLidarModel(os1);
  returns_model.setLidarModel(os1);
  PointCloudView organised_view, returns_view;
  ASSERT_TRUE(scan.cloud.view(&organised_view));
  ASSERT_TRUE(bottom_up.view(&returns_view));
  GroundClassification a, b;
  organised_model.classify(organised_view, pose, &a);
  EXPECT_TRUE(organised_model.lastRings().top_down);
  EXPECT_EQ(organised_model.lastRings().source, PointCloudView::RingSource::kRingField);
  returns_model.classify(returns_view, pose, &b);
  EXPECT_FALSE(returns_model.lastRings().top_down);
  std::size_t differ = 0;
  for (std::size_t k = 0; k < slot.size(); ++k) differ += a.labels[slot[k]] != b.labels[k];
  // The two clouds order the returns differently (by row, by firing), which changes the range
  // image's last-written return of a shared cell, nothing else.
  EXPECT_LT(differ, slot.size() / 200) << differ << " of " << slot.size();
  // Empty slots are unknown.
  for (std::size_t i = 0; i < organised_view.size(); ++i) {
    if (organised_view.xyz(i).isZero()) {
      ASSERT_EQ(a.labels[i], kLabelUnknown) << i;
    }
  }

  // The same organised cloud without its ring field: rows from the layout.
  PackedCloud no_ring = scan.cloud;
  for (FieldDesc& f : no_ring.layout.fields) {
    if (f.name == "ring") f.name = "beam_row";
  }
  PointCloudView rows_view;
  ASSERT_TRUE(no_ring.view(&rows_view));
  ASSERT_EQ(rows_view.ringSource(), PointCloudView::RingSource::kRows);
  GroundClassification c;
  VerticalScanGround rows_model;
  rows_model.setLidarModel(os1);
  rows_model.classify(rows_view, pose, &c);
  EXPECT_TRUE(rows_model.lastRings().top_down);
  EXPECT_EQ(c.labels, a.labels);
}

TEST(LidarModels, MismatchesAreNamed) {
  const sim::SimulatedScan scan = simulate("vlp16", "urban", sim::NoiseProfile::kDatasheet);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  ASSERT_TRUE(view.hasRing());
  EXPECT_EQ(checkCloudAgainstLidarModel(view, *findLidarModel("vlp16")), "");
  const std::string wrong = checkCloudAgainstLidarModel(view, *findLidarModel("hdl64e"));
  EXPECT_NE(wrong.find("16 distinct rings"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("hdl64e has 64"), std::string::npos) << wrong;
  // A 16-beam cloud against a 128-beam table is a mismatch too; a 64-beam one against a VLP-16.
  EXPECT_NE(checkCloudAgainstLidarModel(view, *findLidarModel("os1_128")), "");
  const sim::SimulatedScan hdl = simulate("hdl64e", "urban", sim::NoiseProfile::kDatasheet);
  PointCloudView hdl_view;
  ASSERT_TRUE(hdl.cloud.view(&hdl_view));
  EXPECT_NE(checkCloudAgainstLidarModel(hdl_view, *findLidarModel("vlp16")), "");

  // Without a ring field: the elevations tell (VLP-16 up to +15 deg, HDL-64E up to +2 deg).
  PackedCloud no_ring = scan.cloud;
  for (FieldDesc& f : no_ring.layout.fields) {
    if (f.name == "ring") f.name = "beam";
  }
  PointCloudView plain;
  ASSERT_TRUE(no_ring.view(&plain));
  ASSERT_FALSE(plain.hasRing());
  EXPECT_EQ(checkCloudAgainstLidarModel(plain, *findLidarModel("vlp16")), "");
  const std::string span = checkCloudAgainstLidarModel(plain, *findLidarModel("hdl64e"));
  EXPECT_NE(span.find("elevation"), std::string::npos) << span;
}

TEST(LidarModels, MeasuredRingElevationsMatchTheTable) {
  const sim::SimulatedScan scan = simulate("vlp32c", "urban", sim::NoiseProfile::kNone);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  std::vector<float> measured;
  std::string error;
  ASSERT_TRUE(measureRingElevations(view, &measured, &error)) << error;
  const std::vector<float>& table = findLidarModel("vlp32c")->elevations_deg;
  ASSERT_EQ(measured.size(), table.size());
  for (std::size_t k = 0; k < table.size(); ++k) EXPECT_NEAR(measured[k], table[k], 0.02) << k;
  LidarModel m;
  EXPECT_TRUE(lidarModelFromElevations(measured, &m, &error)) << error;
}

TEST(LidarModels, MountEstimateRecoversATiltedSensor) {
  Eigen::Isometry3d mount;
  const sim::SimulatedScan scan = simulate("vlp32c", "flat", sim::NoiseProfile::kDatasheet, -2.0, 3.0, &mount);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  MountEstimate est;
  ASSERT_TRUE(estimateMountFromGround(view, 1.5f, &est));
  EXPECT_NEAR(est.height, mount.translation().z(), 0.05);
  EXPECT_NEAR(est.roll_deg, -2.0, 0.3);
  EXPECT_NEAR(est.pitch_deg, 3.0, 0.3);
}

// Every sensor of the table at datasheet noise, the sparse ones too, and a tilted mount.
TEST(LidarModels, SparseAndTiltedSensorsSeparateGround) {
  struct Case {
    const char* sensor;
    const char* world;
    double roll, pitch, min_f1;
  };
  for (const Case& c : {Case{"vlp16", "urban", 0, 0, 0.95}, Case{"vlp16", "rural", 0, 0, 0.95},
                        Case{"os1_32", "rural", 0, 0, 0.97}, Case{"os1_64", "urban", 2, 4, 0.97},
                        Case{"hdl32e", "rural", 0, 0, 0.97}}) {
    EvaluationSensor sensor;
    std::string error;
    ASSERT_TRUE(makeEvaluationSensor(c.sensor, sim::NoiseProfile::kDatasheet, &sensor, &error)) << error;
    sensor.tilt(c.roll, c.pitch);
    VerticalScanGround model;
    GroundAccuracy acc;
    ASSERT_TRUE(evaluateGroundModel(sensor, c.world, &model, 3, 1, &acc, &error)) << error;
    EXPECT_GE(f1(acc), c.min_f1) << c.sensor << " " << c.world << " P " << acc.groundPrecision() << " R "
                                 << acc.groundRecall();
    EXPECT_GE(acc.obstacleRecall(), 0.9) << c.sensor << " " << c.world;
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
