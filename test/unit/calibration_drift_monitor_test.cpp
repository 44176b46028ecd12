// The drift monitor (continuous recalibration, thesis 5.2.2) on a simulated drive: two HDL-64Es
// at datasheet noise, the vehicle weaving along the thesis world's corridor. Unbumped, it stays
// OK; after the target's mount is knocked by 2 cm (or 0.01 rad) it reaches ERROR within 30 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ladar_perception/calibration/drift_monitor.h"
#include "ladar_perception/calibration/experiment.h"
#include "ladar_perception/sim/world.h"

namespace lp = ladar_perception;
namespace cal = ladar_perception::calibration;

namespace {

// Two HDL-64Es (velodyne-velodyne's mounts) at datasheet noise on the thesis world's drive,
// scans every 2 s, checks every 4 s; the target's mount moves by `bump` at 24 s.
cal::DriftDriveResult drive(const cal::Pose6& bump) {
  lp::sim::World world;
  std::string error;
  EXPECT_TRUE(lp::sim::makeStandardWorld("thesis", 2, &world, &error)) << error;
  cal::PairSetup pair;
  EXPECT_TRUE(cal::pairFromName("velodyne-velodyne", &pair, &error)) << error;
  cal::DriftMonitorParams params;
  params.window = 12.0;
  cal::DriftDriveOptions options;
  options.duration = 56.0;
  options.bump_time = 24.0;
  options.bump = bump;
  cal::DriftDriveResult result;
  EXPECT_TRUE(cal::runDriftDrive(world, pair, params, options, 3, &result, &error,
                                 [](const cal::DriftCheck& c) {
                                   const cal::DriftEstimate& e = c.estimate;
                                   std::printf("t %5.1f s: %-7s offset %+.4f %+.4f %+.4f m, %+.5f %+.5f %+.5f rad; %s\n",
                                               c.time, cal::driftLevelName(e.level), e.offset[0],
                                               e.offset[1], e.offset[2], e.offset[3], e.offset[4],
                                               e.offset[5], e.message.c_str());
                                 }))
      << error;
  return result;
}

TEST(CalibrationDriftMonitor, ATwoCentimetreBumpIsAnErrorWithin30Seconds) {
  const cal::DriftDriveResult run = drive(cal::makePose(0.0, 0.02, 0.0, 0.0, 0.0, 0.0));
  EXPECT_GE(run.checks.size(), 12u);
  EXPECT_EQ(run.warn_before + run.error_before, 0);
  EXPECT_GE(run.detected_after, 0.0);
  EXPECT_LE(run.detected_after, 30.0);
}

TEST(CalibrationDriftMonitor, AHundredthOfARadianBumpIsAnErrorWithin30Seconds) {
  const cal::DriftDriveResult run = drive(cal::makePose(0.0, 0.0, 0.0, 0.0, 0.0, 0.01));
  EXPECT_EQ(run.warn_before + run.error_before, 0);
  EXPECT_GE(run.detected_after, 0.0);
  EXPECT_LE(run.detected_after, 30.0);
}

TEST(CalibrationDriftMonitor, WaitsForScansAndRestartsOnANewConfiguration) {
  cal::DriftMonitorParams params;
  cal::DriftMonitor monitor(params, Eigen::Isometry3d::Identity(), cal::Pose6::Zero());
  cal::DriftEstimate e = monitor.check();
  EXPECT_EQ(e.level, cal::DriftLevel::kUnknown);
  EXPECT_FALSE(e.estimated);
  EXPECT_NE(e.message.find("waiting for scans"), std::string::npos) << e.message;
  // Empty and non-finite scans are ignored; old scans leave the window.
  monitor.addReferenceScan(0.0, Eigen::Isometry3d::Identity(), {});
  monitor.addReferenceScan(std::nan(""), Eigen::Isometry3d::Identity(), {Eigen::Vector3f(1, 0, 0)});
  EXPECT_EQ(monitor.referenceScans(), 0u);
  for (int k = 0; k < 5; ++k) {
    monitor.addReferenceScan(10.0 * k, Eigen::Isometry3d::Identity(), {Eigen::Vector3f(1, 0, 0)});
  }
  EXPECT_EQ(monitor.referenceScans(), 3u);  // 20, 30 and 40: within 20 s of the newest
  monitor.setConfigured(cal::makePose(1, 0, 0, 0, 0, 0));
  EXPECT_EQ(monitor.level(), cal::DriftLevel::kUnknown);
  EXPECT_DOUBLE_EQ(monitor.configured()[0], 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
