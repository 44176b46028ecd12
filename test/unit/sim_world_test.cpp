// Worlds: generation is deterministic, standard drives stay on drivable ground, the features
// each world promises are there, and image worlds map intensity to height (thesis 4.2.1).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "ladar_perception/io/image.h"
#include "ladar_perception/sim/trajectory.h"
#include "ladar_perception/sim/world.h"
#include "sim_standard_worlds.h"

namespace ladar_perception {
namespace sim {
namespace {

const World& standard(const std::string& name) { return cachedStandardWorld(name, 7); }

TEST(SimWorld, ClassNamesRoundTripAndGroups) {
  for (int k = 0; k < kNumSurfaceClasses; ++k) {
    const SurfaceClass c = static_cast<SurfaceClass>(k);
    SurfaceClass back;
    ASSERT_TRUE(classFromName(className(c), &back));
    EXPECT_EQ(back, c);
    EXPECT_NE(isGroundClass(c), isObstacleClass(c)) << className(c);
  }
  EXPECT_TRUE(isGroundClass(SurfaceClass::kSidewalk));
  EXPECT_TRUE(isObstacleClass(SurfaceClass::kPothole));
  EXPECT_FALSE(isGroundClass(SurfaceClass::kNone));
  EXPECT_FALSE(isObstacleClass(SurfaceClass::kNone));
  SurfaceClass c;
  EXPECT_FALSE(classFromName("lava", &c));
}

TEST(SimWorld, UnknownWorldIsAnError) {
  World w;
  std::string error;
  EXPECT_FALSE(makeStandardWorld("moon", 1, &w, &error));
  EXPECT_NE(error.find("urban"), std::string::npos) << error;
}

TEST(SimWorld, GenerationIsDeterministicForASeed) {
  for (const char* name : {"thesis", "urban", "rural", "potholes"}) {
    World a, b, c;
    std::string error;
    ASSERT_TRUE(makeStandardWorld(name, 42, &a, &error)) << error;
    ASSERT_TRUE(makeStandardWorld(name, 42, &b, &error)) << error;
    ASSERT_TRUE(makeStandardWorld(name, 43, &c, &error)) << error;
    EXPECT_EQ(a.heights(), b.heights()) << name;
    EXPECT_EQ(a.classes(), b.classes()) << name;
    EXPECT_NE(a.heights(), c.heights()) << name << ": another seed should give another world";
  }
}

TEST(SimWorld, OutsideTheWorld) {
  const World& w = standard("flat");
  EXPECT_TRUE(std::isnan(w.height(w.maxX() + 1.0, 0.0)));
  EXPECT_EQ(w.surfaceClass(0.0, w.maxY() + 1.0), SurfaceClass::kNone);
  EXPECT_EQ(w.surfaceClass(1.0, 1.0), SurfaceClass::kRoad);
  EXPECT_FLOAT_EQ(w.height(1.0, 1.0), 0.f);
}

// The vehicle (4.6 m x 2.0 m with margin) only ever stands on ground classes, inside the world,
// and its base_link sits on the ground.
TEST(SimWorld, StandardDrivesStayOnDrivableGround) {
  for (const std::string& name : standardWorldNames()) {
    const World& w = standard(name);
    ASSERT_GT(w.driveDuration(), 10.0) << name;
    for (double t = 0.0; t <= w.driveDuration(); t += 0.25) {
      const Eigen::Isometry3d pose = w.drivePose(t);
      const Eigen::Vector3d p = pose.translation();
      EXPECT_NEAR(p.z(), w.height(p.x(), p.y()), 1e-5) << name;
      for (double a = -2.3; a <= 2.3; a += 0.1) {
        for (double b = -1.0; b <= 1.0; b += 0.1) {
          const Eigen::Vector3d q = pose * Eigen::Vector3d(a, b, 0.0);
          const SurfaceClass c = w.surfaceClass(q.x(), q.y());
          ASSERT_TRUE(isGroundClass(c)) << name << " t=" << t << " at (" << q.x() << ", " << q.y()
                                        << ") is " << className(c);
        }
      }
    }
  }
}

TEST(SimWorld, UrbanHasItsFeatures) {
  const World& w = standard("urban");
  // 15 cm curb between the gutter and the sidewalk on both sides.
  EXPECT_NEAR(w.height(20.0, 5.2) - w.height(20.0, 4.95), 0.15, 0.01);
  EXPECT_NEAR(w.height(20.0, -5.2) - w.height(20.0, -4.95), 0.15, 0.01);
  // Crowned road: the centre is 10 cm above the gutter.
  EXPECT_NEAR(w.height(20.0, 0.0) - w.height(20.0, 4.95), 0.10, 0.01);
  // A person 22 m from the start of the drive.
  const Eigen::Vector3d start = w.drivePose(0.0).translation();
  int person_cells = 0;
  double nearest = 1e9;
  for (int iy = 0; iy < w.cellsY(); ++iy) {
    for (int ix = 0; ix < w.cellsX(); ++ix) {
      if (w.cellClass(ix, iy) != SurfaceClass::kPerson) continue;
      ++person_cells;
      const double x = w.originX() + (ix + 0.5) * w.resolution();
      const double y = w.originY() + (iy + 0.5) * w.resolution();
      nearest = std::min(nearest, std::hypot(x - start.x(), y - start.y()));
    }
  }
  EXPECT_GT(person_cells, 5);
  EXPECT_NEAR(nearest, 22.0, 0.4);
  // Every class of the issue is present.
  std::vector<int> counts(kNumSurfaceClasses, 0);
  for (uint8_t c : w.classes()) ++counts[c];
  for (SurfaceClass c : {SurfaceClass::kRoad, SurfaceClass::kSidewalk, SurfaceClass::kTerrain,
                         SurfaceClass::kCar, SurfaceClass::kWall, SurfaceClass::kPole,
                         SurfaceClass::kPerson}) {
    EXPECT_GT(counts[static_cast<int>(c)], 0) << className(c);
  }
}

// Slopes up to 15 degrees, steep enough to matter, never steeper (1 m baselines).
TEST(SimWorld, HillsideSlopesStayWithin15Degrees) {
  const World& w = standard("hillside");
  double steepest = 0.0;
  for (double x = -60.0; x < 120.0; x += 0.5) {
    for (double y = -50.0; y < 50.0; y += 0.5) {
      if (w.surfaceClass(x, y) != SurfaceClass::kTerrain ||
          w.surfaceClass(x + 1.0, y) != SurfaceClass::kTerrain ||
          w.surfaceClass(x, y + 1.0) != SurfaceClass::kTerrain) {
        continue;
      }
      const double gx = w.height(x + 1.0, y) - w.height(x, y);
      const double gy = w.height(x, y + 1.0) - w.height(x, y);
      steepest = std::max(steepest, std::atan(std::hypot(gx, gy)) * 180.0 / M_PI);
    }
  }
  EXPECT_LE(steepest, 15.5);
  EXPECT_GE(steepest, 12.0);
  // The drive climbs the hill.
  EXPECT_GT(w.drivePose(w.driveDuration()).translation().z() - w.drivePose(0).translation().z(), 8.0);
  // The neighbouring cells of the slope never step by a curb height.
  for (double x = 0.0; x < 100.0; x += 0.1) {
    EXPECT_LT(std::abs(w.height(x + 0.1, 0.05) - w.height(x, 0.05)), w.surfaceModel().curb_min_step);
  }
}

// The rural road's cross-section (3 % crown, 6 % shoulders, 1:4 side slopes, ditches 0.5 m below
// the fields) and what stands on and beside it.
TEST(SimWorld, RuralRoadCrossSection) {
  const World& w = standard("rural");
  for (double x = -40.0; x <= 140.0; x += 9.7) {
    // A stretch without a parked car or a mailbox on either side.
    bool clear = true;
    for (double y = -13.0; y <= 13.0; y += 0.1) clear &= isGroundClass(w.surfaceClass(x, y));
    if (!clear) continue;
    const double crown = w.height(x, 0.05);
    EXPECT_NEAR(crown, 0.6, 0.01);
    for (int side = -1; side <= 1; side += 2) {
      // Lanes: 3 % down from the crown line to the lane edges, both sides.
      EXPECT_NEAR(crown - w.height(x, side * 3.45), 0.03 * 3.4, 0.01) << x;
      EXPECT_EQ(w.surfaceClass(x, side * 3.45), SurfaceClass::kRoad);
      EXPECT_EQ(w.surfaceClass(x, side * 3.55), SurfaceClass::kTerrain);
      // Shoulders at 6 %, 1:4 foreslopes, flat ditch bottoms 0.5 m below the fields.
      EXPECT_NEAR(w.height(x, side * 4.05) - w.height(x, side * 5.05), 0.06, 0.01) << x;
      EXPECT_NEAR(w.height(x, side * 6.05) - w.height(x, side * 8.05), 0.5, 0.01) << x;
      EXPECT_NEAR(w.height(x, side * 9.5), -0.5, 0.01) << x;
      EXPECT_NEAR(w.height(x, side * 11.05) - w.height(x, side * 10.05), 0.25, 0.01) << x;
      // Everything beside the road lies well below it: a plane through the road misses it.
      for (double ay = 7.0; ay <= 50.0; ay += 0.5) {
        if (isGroundClass(w.surfaceClass(x, side * ay))) {
          EXPECT_LT(w.height(x, side * ay), 0.25) << x << " " << ay;
        }
      }
    }
  }
  // Slopes stay within 15 degrees (the 1:4 side slopes are the steepest, 14 degrees), and no
  // step between ground cells reads as a curb.
  double steepest = 0.0;
  for (double x = -60.0; x < 160.0; x += 0.5) {
    for (double y = -55.0; y < 55.0; y += 0.5) {
      if (!isGroundClass(w.surfaceClass(x, y)) || !isGroundClass(w.surfaceClass(x + 1.0, y)) ||
          !isGroundClass(w.surfaceClass(x, y + 1.0))) {
        continue;
      }
      const double gx = w.height(x + 1.0, y) - w.height(x, y);
      const double gy = w.height(x, y + 1.0) - w.height(x, y);
      steepest = std::max(steepest, std::atan(std::hypot(gx, gy)) * 180.0 / M_PI);
    }
  }
  EXPECT_LE(steepest, 15.0);
  EXPECT_GE(steepest, 13.5);
  for (int k = 0; k < 400; ++k) {
    const double y = -19.95 + 0.1 * k;  // cell centres
    if (isGroundClass(w.surfaceClass(30.05, y)) && isGroundClass(w.surfaceClass(30.05, y + 0.1))) {
      EXPECT_LT(std::abs(w.height(30.05, y + 0.1) - w.height(30.05, y)), w.surfaceModel().curb_min_step) << y;
    }
  }
  // The obstacles: cars (parked and the stopped one), people (on the shoulder, in the field),
  // fence posts, mailboxes and trees (poles), hay bales and the barn (walls).
  std::vector<int> counts(kNumSurfaceClasses, 0);
  int fence_posts = 0;
  for (int iy = 0; iy < w.cellsY(); ++iy) {
    for (int ix = 0; ix < w.cellsX(); ++ix) {
      const SurfaceClass c = w.cellClass(ix, iy);
      ++counts[static_cast<int>(c)];
      const double y = w.originY() + (iy + 0.5) * w.resolution();
      fence_posts += c == SurfaceClass::kPole && std::abs(std::abs(y) - 12.85) < 0.01;
    }
  }
  for (SurfaceClass c : {SurfaceClass::kRoad, SurfaceClass::kTerrain, SurfaceClass::kCar, SurfaceClass::kWall,
                         SurfaceClass::kPole, SurfaceClass::kPerson}) {
    EXPECT_GT(counts[static_cast<int>(c)], 0) << className(c);
  }
  EXPECT_EQ(counts[static_cast<int>(SurfaceClass::kCurb)], 0);
  EXPECT_GE(fence_posts, 2 * 58);  // posts every 4 m along 236 m, both sides
  // The person on the north shoulder 25 m from the start of the drive.
  const Eigen::Vector3d start = w.drivePose(0.0).translation();
  double nearest = 1e9;
  for (int iy = 0; iy < w.cellsY(); ++iy) {
    for (int ix = 0; ix < w.cellsX(); ++ix) {
      if (w.cellClass(ix, iy) != SurfaceClass::kPerson) continue;
      const double x = w.originX() + (ix + 0.5) * w.resolution();
      const double y = w.originY() + (iy + 0.5) * w.resolution();
      nearest = std::min(nearest, std::hypot(x - start.x(), y - start.y()));
    }
  }
  EXPECT_NEAR(nearest, 25.0, 0.4);
}

TEST(SimWorld, PotholesAreNegativeObstaclesBesideTheDrive) {
  const World& w = standard("potholes");
  int pothole_cells = 0;
  float deepest = 0.f;
  for (int iy = 0; iy < w.cellsY(); ++iy) {
    for (int ix = 0; ix < w.cellsX(); ++ix) {
      if (w.cellClass(ix, iy) != SurfaceClass::kPothole) continue;
      ++pothole_cells;
      deepest = std::min(deepest, w.cellHeight(ix, iy));
    }
  }
  EXPECT_GT(pothole_cells, 500);
  EXPECT_LT(deepest, -0.15f);
}

TEST(SimWorld, AlleyIsTwoLongWalls) {
  const World& w = standard("alley");
  for (double x = -50.0; x < 150.0; x += 5.0) {
    EXPECT_EQ(w.surfaceClass(x, 3.2), SurfaceClass::kWall);
    EXPECT_EQ(w.surfaceClass(x, -3.2), SurfaceClass::kWall);
    EXPECT_FLOAT_EQ(w.height(x, 3.2), 5.f);
    EXPECT_EQ(w.surfaceClass(x, 0.0), SurfaceClass::kRoad);
  }
}

TEST(SimWorld, TrajectoryFollowsWaypointsAtSpeed) {
  Trajectory t;
  std::string error;
  ASSERT_TRUE(Trajectory::fromWaypoints({{0, 0}, {10, 0}, {10, 10}}, 2.0, &t, &error)) << error;
  EXPECT_DOUBLE_EQ(t.length(), 20.0);
  EXPECT_DOUBLE_EQ(t.duration(), 10.0);
  double x, y, yaw;
  t.pose2d(2.5, &x, &y, &yaw);
  EXPECT_NEAR(x, 5.0, 1e-9);
  EXPECT_NEAR(y, 0.0, 1e-9);
  EXPECT_NEAR(yaw, 0.0, 1e-9);
  t.pose2d(5.0, &x, &y, &yaw);  // the corner: heading halfway round
  EXPECT_NEAR(yaw, M_PI / 4, 1e-6);
  t.pose2d(100.0, &x, &y, &yaw);  // clamped to the end
  EXPECT_NEAR(x, 10.0, 1e-9);
  EXPECT_NEAR(y, 10.0, 1e-9);
  EXPECT_NEAR(yaw, M_PI / 2, 1e-6);
  EXPECT_FALSE(Trajectory::fromWaypoints({{0, 0}}, 2.0, &t, &error));
  EXPECT_FALSE(Trajectory::fromWaypoints({{0, 0}, {1, 0}}, 0.0, &t, &error));
}

TEST(SimWorld, RandomPosesOfTheThesisExperiment) {
  const World& w = standard("thesis");
  const auto poses = randomVehiclePoses(w, 200, 3);
  ASSERT_EQ(poses.size(), 200u);
  double max_offset = 0, max_yaw = 0;
  for (const Eigen::Isometry3d& p : poses) {
    max_offset = std::max(max_offset, p.translation().head<2>().norm());
    const Eigen::Vector3d x = p.linear().col(0);
    max_yaw = std::max(max_yaw, std::abs(std::atan2(x.y(), x.x())));
    EXPECT_NEAR(p.translation().z(), w.height(p.translation().x(), p.translation().y()), 1e-5);
  }
  EXPECT_LE(max_offset, 5.0);
  EXPECT_GT(max_offset, 4.0);
  EXPECT_LE(max_yaw, 0.5 + 1e-9);
  EXPECT_GT(max_yaw, 0.4);
  const auto again = randomVehiclePoses(w, 200, 3);
  EXPECT_TRUE(again[17].isApprox(poses[17]));
}

TEST(SimWorld, TerrainTiltsTheVehicle) {
  World w;
  std::string error;
  ASSERT_TRUE(w.reset(-20, -20, 0.1, 400, 400, 0.f, SurfaceClass::kTerrain, &error));
  for (int iy = 0; iy < 400; ++iy)
    for (int ix = 0; ix < 400; ++ix)
      w.setCell(ix, iy, static_cast<float>(0.1 * (-20 + (ix + 0.5) * 0.1)), SurfaceClass::kTerrain);
  w.finalize();
  // Facing uphill (+x): nose up, which is a negative pitch in ROS.
  const Eigen::Isometry3d up = w.vehiclePose(0, 0, 0);
  EXPECT_NEAR(up.linear().col(0).z(), std::sin(std::atan(0.1)), 1e-3);
  // Facing north (+y) on the same hill: the left side (-x) is lower, rolled right.
  const Eigen::Isometry3d side = w.vehiclePose(0, 0, M_PI / 2);
  EXPECT_NEAR(side.linear().col(1).z(), -std::sin(std::atan(0.1)), 1e-3);
}

TEST(SimWorld, ImageWorldBlackIsHigh) {
  const std::string path = testing::TempDir() + "/sim_world_test.pgm";
  {
    std::ofstream f(path, std::ios::binary);
    f << "P5\n4 2\n255\n";
    const unsigned char pixels[8] = {0, 255, 255, 255, 128, 255, 255, 255};
    f.write(reinterpret_cast<const char*>(pixels), 8);
  }
  ImageWorldOptions options;
  options.metres_per_pixel = 0.5;
  options.height_scale = 2.0;
  World w;
  std::string error;
  ASSERT_TRUE(World::fromImage(path, "", options, &w, &error)) << error;
  EXPECT_EQ(w.cellsX(), 4);
  EXPECT_EQ(w.cellsY(), 2);
  EXPECT_DOUBLE_EQ(w.originX(), -1.0);
  // Top-left pixel (black) is the north-west cell.
  EXPECT_FLOAT_EQ(w.cellHeight(0, 1), 2.f);
  EXPECT_EQ(w.cellClass(0, 1), SurfaceClass::kWall);
  EXPECT_NEAR(w.cellHeight(0, 0), 2.0 * (1.0 - 128.0 / 255.0), 1e-4);
  EXPECT_FLOAT_EQ(w.cellHeight(3, 0), 0.f);
  EXPECT_EQ(w.cellClass(3, 0), SurfaceClass::kTerrain);
  EXPECT_TRUE(w.finalized());
  EXPECT_FALSE(World::fromImage(path + ".missing", "", options, &w, &error));
  EXPECT_FALSE(error.empty());
  std::remove(path.c_str());
}


TEST(SimWorld, ExampleTrajectoryLoadsAndStaysOnTheRoad) {
  Trajectory t;
  std::string error;
  ASSERT_TRUE(loadTrajectoryYaml(std::string(LADAR_SOURCE_DIR) + "/config/sim_urban_detour.yaml", &t, &error))
      << error;
  EXPECT_DOUBLE_EQ(t.speed(), 4.0);
  const World& w = standard("urban");
  for (double time = 0.0; time <= t.duration(); time += 0.25) {
    double x, y, yaw;
    t.pose2d(time, &x, &y, &yaw);
    const Eigen::Isometry3d pose = w.vehiclePose(x, y, yaw);
    for (double a = -2.3; a <= 2.3; a += 0.1) {
      for (double b = -1.0; b <= 1.0; b += 0.1) {
        const Eigen::Vector3d q = pose * Eigen::Vector3d(a, b, 0.0);
        ASSERT_EQ(w.surfaceClass(q.x(), q.y()), SurfaceClass::kRoad) << "t=" << time;
      }
    }
  }
  EXPECT_FALSE(loadTrajectoryYaml("/nonexistent.yaml", &t, &error));
  EXPECT_FALSE(error.empty());
}

TEST(SimWorld, ColourClassImageUsesThePalette) {
  const std::string heights = testing::TempDir() + "/sim_world_test_h.pgm";
  const std::string classes = testing::TempDir() + "/sim_world_test_c.png";
  {
    std::ofstream f(heights, std::ios::binary);
    f << "P5\n2 1\n255\n";
    const unsigned char pixels[2] = {255, 0};
    f.write(reinterpret_cast<const char*>(pixels), 2);
  }
  RgbImage image(2, 1);
  uint8_t rgb[3];
  classColor(SurfaceClass::kSidewalk, rgb);
  image.set(0, 0, rgb[0], rgb[1], rgb[2]);
  classColor(SurfaceClass::kCar, rgb);
  image.set(1, 0, rgb[0] + 5, rgb[1] - 5, rgb[2]);  // near the car colour
  std::string error;
  ASSERT_TRUE(writePng(classes, image, &error)) << error;
  World w;
  ASSERT_TRUE(World::fromImage(heights, classes, ImageWorldOptions(), &w, &error)) << error;
  EXPECT_EQ(w.cellClass(0, 0), SurfaceClass::kSidewalk);
  EXPECT_EQ(w.cellClass(1, 0), SurfaceClass::kCar);
  EXPECT_FLOAT_EQ(w.cellHeight(1, 0), 2.f);
  std::remove(heights.c_str());
  std::remove(classes.c_str());
}

}  // namespace
}  // namespace sim
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
