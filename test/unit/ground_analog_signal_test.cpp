// The analog signal approach (thesis 3.2) as a ground model: right on planes (a tilt is the
// first harmonic), wrong where the thesis says it fails (crowned road, hillside).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ground_surface_scene.h"
#include "ground_world_eval.h"
#include "ladar_perception/ground/analog_signal.h"
#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/ground_model.h"

namespace lp = ladar_perception;
using surface_test::SurfaceScene;

namespace {

using surface_test::Score;
using surface_test::score;
using surface_test::withCar;

TEST(AnalogSignal, SelectableByName) {
  std::string error;
  auto model = lp::makeGroundModel("analog_signal", &error);
  ASSERT_TRUE(model) << error;
  EXPECT_EQ(model->name(), "analog_signal");
}

TEST(AnalogSignal, FlatGroundWithObstacles) {
  lp::AnalogSignalGround analog;
  const Score s = score(&analog, withCar(SurfaceScene()));
  EXPECT_GT(s.ground_recall, 0.99);
  EXPECT_GT(s.obstacle_recall, 0.95);
  ASSERT_TRUE(analog.fit().valid);
  EXPECT_NEAR(analog.fit().a, 0.0, 2e-3);
  EXPECT_NEAR(analog.fit().b, 0.0, 2e-3);
  // Without `ring` the rows come from the elevation table: the same result.
  lp::AnalogSignalGround no_ring;
  const Score t = score(&no_ring, withCar(SurfaceScene()), false);
  EXPECT_GT(t.ground_recall, 0.99);
  EXPECT_GT(t.obstacle_recall, 0.95);
}

// A tilted plane is the first harmonic: A = dz/dx / h, B = dz/dy / h.
TEST(AnalogSignal, PlaneTiltIsTheFirstHarmonic) {
  SurfaceScene scene;
  scene.ground = [](double x, double y) { return 0.05 * x - 0.03 * y; };
  lp::AnalogSignalGround analog;
  const Score s = score(&analog, withCar(scene));
  EXPECT_GT(s.ground_recall, 0.99);
  ASSERT_TRUE(analog.fit().valid);
  EXPECT_NEAR(analog.fit().a, 0.05 / 1.73, 2e-3);
  EXPECT_NEAR(analog.fit().b, -0.03 / 1.73, 2e-3);
}

TEST(AnalogSignal, FailsOnACrownedRoadAndAHillside) {
  SurfaceScene crowned;
  crowned.ground = [](double, double y) { return -0.03 * std::fabs(y); };
  SurfaceScene hill;
  hill.ground = [](double x, double) { return x > 8.0 ? 0.15 * (x - 8.0) : 0.0; };
  lp::AnalogSignalGround analog;
  EXPECT_LT(score(&analog, withCar(crowned)).ground_recall, 0.9) << "crowned road";
  EXPECT_LT(score(&analog, withCar(hill)).ground_recall, 0.9) << "hillside";
}

TEST(AnalogSignal, EmptyAndNaNClouds) {
  lp::AnalogSignalGround analog;
  lp::PackedCloud cloud;
  cloud.layout = lp::velodyneXYZIRTLayout(100);
  cloud.data.assign(cloud.layout.row_step, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 100; ++i) {
    lp::writeField(cloud.data.data() + i * cloud.layout.point_step, *lp::findField(cloud.layout, "x"), nan);
  }
  lp::PointCloudView view;
  ASSERT_TRUE(cloud.view(&view));
  lp::GroundClassification result;
  analog.classify(view, lp::SensorPose::fromHeight(1.73f), &result);
  EXPECT_EQ(result.count(lp::kLabelUnknown), 100u);
  cloud.layout = lp::velodyneXYZIRTLayout(0);
  cloud.data.clear();
  ASSERT_TRUE(cloud.view(&view));
  analog.classify(view, lp::SensorPose::fromHeight(1.73f), &result);
  EXPECT_EQ(result.size(), 0u);
}

using lp::testing_support::classRecall;
using lp::testing_support::evaluateWorld;

// The thesis's finding on the simulator's worlds (ground_eval's table, 3 revolutions here):
// right on the flat worlds, wrong on the crowned rural road. Each laser's ring crosses the road
// and its shoulders, ditches and fields 0.6-1.1 m lower: no first harmonic plus bias describes
// that, so much of the ground reads as obstacle and obstacles in the fields partly as ground.
TEST(AnalogSignal, PassesOnFlatFailsOnTheCrownedRuralRoad) {
  lp::AnalogSignalGround analog;
  const lp::GroundAccuracy flat = evaluateWorld("flat", &analog);
  EXPECT_GT(flat.groundPrecision(), 0.999);
  EXPECT_GT(flat.groundRecall(), 0.999);
  const lp::GroundAccuracy thesis = evaluateWorld("thesis", &analog);  // flat with obstacles
  const lp::GroundAccuracy rural = evaluateWorld("rural", &analog);
  // Flat with car-sized obstacles (thesis world): still right (measured 100 % ground recall,
  // 88.7 % obstacle recall).
  EXPECT_GT(thesis.groundRecall(), 0.99);
  EXPECT_GT(thesis.obstacleRecall(), 0.85);
  // Rural, measured (seed 1, 3 revolutions): ground recall 64.1 %, people 81.8 % (the vertical
  // scan method: 94.5 % and 93.1 %, ground_plane_fit_test).
  EXPECT_LT(rural.groundRecall(), 0.70);
  EXPECT_LT(classRecall(rural, lp::sim::SurfaceClass::kPerson), 0.87);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
