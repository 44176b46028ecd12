// Sensor rig YAML, the true extrinsics round trip, the firing schedule, vehicle motions and the
// top-down picture.
#include <gtest/gtest.h>

#include <cmath>

#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/world_image.h"

namespace ladar_perception {
namespace sim {
namespace {

const World& flat() {
  static World w;
  if (w.empty()) {
    std::string error;
    EXPECT_TRUE(makeStandardWorld("flat", 1, &w, &error)) << error;
  }
  return w;
}

void expectSameRig(const SensorRig& a, const SensorRig& b) {
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  EXPECT_EQ(a.odom_frame, b.odom_frame);
  EXPECT_EQ(a.base_frame, b.base_frame);
  for (std::size_t k = 0; k < a.sensors.size(); ++k) {
    const SensorMount& x = a.sensors[k];
    const SensorMount& y = b.sensors[k];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.frame_id, y.frame_id);
    EXPECT_EQ(x.topic, y.topic);
    EXPECT_EQ(x.truth_topic, y.truth_topic);
    EXPECT_TRUE(x.base_to_sensor.isApprox(y.base_to_sensor, 1e-9)) << x.name;
    EXPECT_DOUBLE_EQ(x.rateHz(), y.rateHz()) << x.name;
    switch (x.kind) {
      case SensorKind::kVelodyne:
        EXPECT_DOUBLE_EQ(x.velodyne.noise_sigma, y.velodyne.noise_sigma);
        EXPECT_DOUBLE_EQ(x.velodyne.max_range, y.velodyne.max_range);
        EXPECT_EQ(x.velodyne.azimuth_steps, y.velodyne.azimuth_steps);
        break;
      case SensorKind::kSick:
        EXPECT_DOUBLE_EQ(x.sick.noise_sigma, y.sick.noise_sigma);
        EXPECT_DOUBLE_EQ(x.sick.angle_increment, y.sick.angle_increment);
        break;
      case SensorKind::kStereo:
        EXPECT_DOUBLE_EQ(x.stereo.noise_sigma, y.stereo.noise_sigma);
        EXPECT_EQ(x.stereo.columns, y.stereo.columns);
        break;
    }
  }
}

TEST(SimRig, ConfigFileIsTheBuiltInThesisVehicle) {
  SensorRig rig;
  std::string error;
  ASSERT_TRUE(loadSensorRig(std::string(LADAR_SOURCE_DIR) + "/config/sensors.yaml", &rig, &error)) << error;
  expectSameRig(rig, SensorRig::thesisVehicle());
  // The tilted SICK meets the ground about 10 m ahead of itself.
  const SensorMount& front = rig.sensors[1];
  const Eigen::Vector3d beam = front.base_to_sensor.linear() * Eigen::Vector3d::UnitX();
  const double reach = front.base_to_sensor.translation().z() / -beam.z();
  EXPECT_NEAR(reach * beam.head<2>().norm(), 10.0, 0.05);
}

TEST(SimRig, ExtrinsicsYamlReloadsToTheSameRig) {
  SensorRig rig = SensorRig::thesisVehicle(NoiseProfile::kDatasheet);
  rig.sensors[0].base_to_sensor = poseFromXyzRpy({0.3, -0.2, 1.8}, {0.05, -0.1, 0.7});
  const std::string yaml = extrinsicsYaml(rig, "urban", 42);
  SensorRig back;
  std::string error;
  ASSERT_TRUE(parseSensorRig(yaml, &back, &error)) << error << "\n" << yaml;
  expectSameRig(rig, back);
  EXPECT_NE(yaml.find("quaternion_xyzw"), std::string::npos);
  EXPECT_NE(yaml.find("world: urban"), std::string::npos);
}

TEST(SimRig, RpyRoundTrip) {
  const Eigen::Vector3d rpy(0.3, -0.4, 2.5);
  EXPECT_TRUE(rpyOf(poseFromXyzRpy({0, 0, 0}, rpy).linear()).isApprox(rpy, 1e-12));
}

TEST(SimRig, BadRigsAreClearErrors) {
  SensorRig rig;
  std::string error;
  EXPECT_FALSE(parseSensorRig("sensors: []", &rig, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(parseSensorRig("sensors:\n  - {name: a, type: radar, xyz: [0,0,1]}", &rig, &error));
  EXPECT_NE(error.find("radar"), std::string::npos);
  EXPECT_FALSE(parseSensorRig("sensors:\n  - {name: a, type: hdl64e}", &rig, &error));
  EXPECT_NE(error.find("xyz"), std::string::npos);
  EXPECT_FALSE(parseSensorRig("sensors:\n  - {name: a, type: hdl64e, xyz: [0,0]}", &rig, &error));
  EXPECT_FALSE(parseSensorRig(
      "sensors:\n  - {name: a, type: hdl64e, xyz: [0,0,1]}\n  - {name: a, type: lms291, xyz: [0,0,1]}",
      &rig, &error));
  EXPECT_NE(error.find("twice"), std::string::npos);
  EXPECT_FALSE(parseSensorRig("sensors:\n  - {name: a, type: hdl64e, xyz: [0,0,1], max_range: -3}", &rig, &error));
  EXPECT_FALSE(parseSensorRig("sensors: [unclosed", &rig, &error));
  EXPECT_FALSE(loadSensorRig("/nonexistent/sensors.yaml", &rig, &error));
  ASSERT_TRUE(parseSensorRig("noise_profile: none\nsensors:\n  - {name: v, type: hdl64e, xyz: [0,0,2], max_range: 120}",
                             &rig, &error)) << error;
  EXPECT_DOUBLE_EQ(rig.sensors[0].velodyne.noise_sigma, 0.0);
  EXPECT_DOUBLE_EQ(rig.sensors[0].velodyne.max_range, 120.0);
  EXPECT_EQ(rig.sensors[0].topic, "v/points");
}

TEST(SimRig, FiringScheduleFollowsEachRate) {
  const SensorRig rig = SensorRig::thesisVehicle();
  const VehicleMotion motion = VehicleMotion::driving(flat(), flat().standardDrive());
  RigSimulator sim(flat(), rig, motion, 1);
  std::vector<SensorFiring> all;
  // In pieces, as the nodelet asks for them: no firing lost or repeated.
  for (double t = 0.0; t < 2.0; t += 0.013) sim.firings(t, std::min(t + 0.013, 2.0), &all);
  std::vector<int> counts(rig.sensors.size(), 0);
  for (std::size_t k = 0; k < all.size(); ++k) {
    ++counts[all[k].sensor];
    if (k > 0) EXPECT_LE(all[k - 1].time, all[k].time);
  }
  EXPECT_EQ(counts[0], 20);   // HDL-64E 10 Hz
  EXPECT_EQ(counts[1], 150);  // LMS-291 75 Hz
  EXPECT_EQ(counts[3], 150);
  EXPECT_EQ(counts[4], 20);   // stereo 10 Hz
}

TEST(SimRig, SimulatedFiringsAreDeterministicAndInTheSensorFrame) {
  const SensorRig rig = SensorRig::thesisVehicle(NoiseProfile::kNone);
  const VehicleMotion motion = VehicleMotion::driving(flat(), flat().standardDrive());
  RigSimulator sim(flat(), rig, motion, 3);
  std::vector<SensorFiring> firings;
  sim.firings(1.0, 1.1, &firings);
  SensorOutput a, b;
  for (const SensorFiring& f : firings) {
    sim.simulate(f, &a);
    sim.simulate(f, &b);
    EXPECT_EQ(a.scan.cloud.data, b.scan.cloud.data);
    EXPECT_EQ(a.laser.ranges, b.laser.ranges);
    if (rig.sensors[f.sensor].kind == SensorKind::kVelodyne) {
      // Flat ground 1.9 m below the roof sensor.
      PointCloudView view;
      ASSERT_TRUE(a.scan.cloud.view(&view));
      ASSERT_GT(view.size(), 50000u);
      for (std::size_t i = 0; i < view.size(); i += 97) EXPECT_NEAR(view.xyz(i).z(), -1.9f, 1e-4f);
    }
  }
  // Moving during a revolution changes the points of a driving vehicle (not on flat ground,
  // which looks the same from everywhere).
  World urban;
  std::string error;
  ASSERT_TRUE(makeStandardWorld("urban", 1, &urban, &error)) << error;
  const VehicleMotion drive = VehicleMotion::driving(urban, urban.standardDrive());
  RigSimulator still(urban, rig, drive, 3), moving(urban, rig, drive, 3);
  moving.motion_distortion = true;
  SensorOutput c;
  moving.simulate(SensorFiring{1.0, 0, 10}, &c);
  still.simulate(SensorFiring{1.0, 0, 10}, &a);
  EXPECT_NE(a.scan.cloud.data, c.scan.cloud.data);
}

TEST(SimRig, HeldPosesForTheThesisExperiment) {
  const std::vector<Eigen::Isometry3d> poses = randomVehiclePoses(flat(), 10, 5);
  const VehicleMotion motion = VehicleMotion::holding(poses, 0.5);
  EXPECT_DOUBLE_EQ(motion.duration(), 5.0);
  EXPECT_TRUE(motion.poseAt(0.2).isApprox(poses[0]));
  EXPECT_TRUE(motion.poseAt(0.7).isApprox(poses[1]));
  EXPECT_TRUE(motion.poseAt(99.0).isApprox(poses[9]));
}

TEST(SimRig, TopDownPictureShowsClassesAndPath) {
  World w;
  std::string error;
  ASSERT_TRUE(makeStandardWorld("urban", 1, &w, &error)) << error;
  const RgbImage image = renderTopDown(w, w.standardDrive().waypoints(), {w.drivePose(5.0)});
  // 2400 x 800 cells, two cells per pixel to stay within 2000 pixels.
  EXPECT_EQ(image.width, 1200);
  EXPECT_EQ(image.height, 400);
  EXPECT_EQ(image.rgb.size(), 3u * image.width * image.height);
  // The middle of the drive (50, -1.5) is on the white path line.
  const int px = static_cast<int>((50.0 - w.originX()) / (w.resolution() * 2));
  const int row = image.height - static_cast<int>((-1.5 - w.originY()) / (w.resolution() * 2));
  const uint8_t* p = &image.rgb[3 * (static_cast<std::size_t>(row) * image.width + px)];
  EXPECT_EQ(p[0], 255);
  EXPECT_EQ(p[1], 255);
  EXPECT_EQ(p[2], 255);
}

}  // namespace
}  // namespace sim
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
