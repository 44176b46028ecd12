// Replays the fuzzers' seed corpus and every input that once crashed a fuzz target
// (test/fuzz/corpus/<target>/ and test/fuzz/regressions/<target>/) through the same entry
// points scripts/fuzz builds with libFuzzer. Under scripts/test's AddressSanitizer +
// UndefinedBehaviorSanitizer pass a regression shows as a sanitizer abort; in a plain build the
// targets' own checks (labels per point, an error message for every rejection) still trap.
#include <string>

#include <gtest/gtest.h>

#define LADAR_FUZZ_ENTRY ladarFuzzPointCloud
#include "../fuzz/fuzz_point_cloud.cpp"
#undef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY ladarFuzzLaserScan
#include "../fuzz/fuzz_laser_scan.cpp"
#undef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY ladarFuzzConfigFiles
#include "../fuzz/fuzz_config_files.cpp"
#undef LADAR_FUZZ_ENTRY
#include "../fuzz/fuzz_replay.h"

using ladar_perception::fuzz::replay;

TEST(FuzzRegression, PointCloudIntoEveryGroundModel) {
  EXPECT_GE(replay("fuzz_point_cloud", &ladarFuzzPointCloud, true), 3);
}

TEST(FuzzRegression, LaserScanIntoHoughGround) {
  EXPECT_GE(replay("fuzz_laser_scan", &ladarFuzzLaserScan, false), 3);
}

TEST(FuzzRegression, WorldAndConfigFiles) {
  EXPECT_GE(replay("fuzz_config_files", &ladarFuzzConfigFiles, true), 5);
}

// The input behind the first regression: a point straight above the sensor (x = y = 0, in
// range by its z) once made the vertical scan divide 0 by 0 for its azimuth column.
TEST(FuzzRegression, PointStraightAboveTheSensorIsLabelled) {
  using namespace ladar_perception;
  CloudLayout layout;
  layout.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}};
  layout.width = 3;
  layout.point_step = 12;
  layout.row_step = 36;
  const float pts[9] = {0.f, 0.f, 5.f, 0.f, 0.f, -1.8f, 10.f, 0.f, -1.8f};
  PointCloudView view;
  std::string error;
  ASSERT_TRUE(PointCloudView::create(reinterpret_cast<const uint8_t*>(pts), sizeof(pts), layout,
                                     &view, &error)) << error;
  for (const std::string& name : groundModelNames()) {
    auto model = makeGroundModel(name, &error);
    ASSERT_TRUE(model) << error;
    GroundClassification out;
    for (float roll : {0.f, 0.1f}) {
      SensorPose pose = SensorPose::fromHeight(1.8f);
      pose.sensor_to_ground.linear() =
          Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX()).toRotationMatrix();
      model->classify(view, pose, &out);
      ASSERT_EQ(out.labels.size(), 3u) << name;
    }
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
