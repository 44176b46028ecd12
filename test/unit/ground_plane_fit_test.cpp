// The Gaussian re-weighted least squares plane (thesis 3.1, Algorithm 1) as a ground model:
// right on a single plane, wrong where the thesis says it fails (crowned road, hillside).
#include <gtest/gtest.h>

#include <cmath>

#include "ground_surface_scene.h"
#include "ground_world_eval.h"
#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/plane_fit.h"
#include "ladar_perception/ground/vertical_scan.h"

namespace lp = ladar_perception;
using surface_test::SurfaceScene;

namespace {

using surface_test::Score;
using surface_test::score;
using surface_test::withCar;

TEST(PlaneFit, AlgorithmOneRecoversAPlane) {
  // Points on 0.1 x - 0.05 y - 1.5 = z (A x + B y + C z = 1 with C = -1/1.5 ...) plus outliers.
  std::vector<float> x, y, z;
  for (int i = -20; i <= 20; ++i) {
    for (int j = -20; j <= 20; ++j) {
      x.push_back(static_cast<float>(i));
      y.push_back(static_cast<float>(j));
      z.push_back(0.1f * i - 0.05f * j - 1.5f + ((i * 7 + j * 3) % 11 == 0 ? 2.f : 0.f));
    }
  }
  lp::PlaneFitParams p;
  p.max_iterations = 20;
  Eigen::Vector3d c(0, 0, -1.0 / 1.5);
  ASSERT_TRUE(lp::fitPlaneGaussianReweighted(x.data(), y.data(), z.data(), static_cast<int>(x.size()), p, &c));
  // z = 0.1 x - 0.05 y - 1.5  <=>  (0.1/1.5) x - (0.05/1.5) y - (1/1.5) z = 1
  EXPECT_NEAR(c.x(), 0.1 / 1.5, 1e-4);
  EXPECT_NEAR(c.y(), -0.05 / 1.5, 1e-4);
  EXPECT_NEAR(c.z(), -1.0 / 1.5, 1e-4);
  EXPECT_NEAR(lp::heightAbovePlane(c, 0.f, 0.f, -1.5f), 0.f, 1e-4);
  EXPECT_GT(lp::heightAbovePlane(c, 0.f, 0.f, -1.f), 0.4f);  // above the ground: positive
  // Degenerate input: no crash, false.
  Eigen::Vector3d d(0, 0, -1.0);
  EXPECT_FALSE(lp::fitPlaneGaussianReweighted(x.data(), y.data(), z.data(), 2, p, &d));
}

TEST(PlaneFit, SelectableByName) {
  std::string error;
  auto model = lp::makeGroundModel("plane", &error);
  ASSERT_TRUE(model) << error;
  EXPECT_EQ(model->name(), "plane");
}

TEST(PlaneFit, FlatGroundWithObstacles) {
  SurfaceScene scene = withCar(SurfaceScene());
  lp::PlaneFitGround plane;
  const Score s = score(&plane, scene);
  EXPECT_GT(s.ground_recall, 0.99);
  EXPECT_GT(s.obstacle_recall, 0.97);
  EXPECT_NEAR(plane.plane().z(), -1.0 / 1.73, 1e-3);
  EXPECT_NEAR(plane.plane().x(), 0.0, 1e-3);
}

TEST(PlaneFit, SinglePlaneSlopeIsFine) {
  SurfaceScene scene;
  scene.ground = [](double x, double y) { return 0.06 * x - 0.03 * y; };
  lp::PlaneFitGround plane;
  EXPECT_GT(score(&plane, withCar(scene)).ground_recall, 0.99);
}

// The thesis's failures: a crowned road (two planes meeting at the centre line, 3% cross
// slope) and a hillside (flat where the vehicle stands, rising 15% from 8 m ahead).
TEST(PlaneFit, FailsOnACrownedRoadAndAHillside) {
  SurfaceScene crowned;
  crowned.ground = [](double, double y) { return -0.03 * std::fabs(y); };
  SurfaceScene hill;
  hill.ground = [](double x, double) { return x > 8.0 ? 0.15 * (x - 8.0) : 0.0; };
  lp::PlaneFitGround plane;
  const Score c = score(&plane, withCar(crowned));
  const Score h = score(&plane, withCar(hill));
  EXPECT_LT(c.ground_recall, 0.85) << "crowned road";
  EXPECT_LT(h.ground_recall, 0.85) << "hillside";
  // Empty and all-NaN clouds: unknown, no crash.
  lp::PackedCloud empty;
  empty.layout = lp::velodyneXYZIRTLayout(0);
  lp::PointCloudView view;
  ASSERT_TRUE(empty.view(&view));
  lp::GroundClassification result;
  plane.classify(view, lp::SensorPose::fromHeight(1.73f), &result);
  EXPECT_EQ(result.size(), 0u);
}

using lp::testing_support::classRecall;
using lp::testing_support::evaluateWorld;

// The thesis's finding on the simulator's worlds (what ground_eval tabulates, 3 revolutions
// here): right on the flat world, wrong on the crowned rural road, whose shoulders, ditches and
// fields lie 0.6-1.1 m below the plane the road defines: most of the ground beside the road
// reads as obstacle, and the fence posts and people in the fields are cut by the plane (their
// middle reads as ground). The vertical scan method, one line per azimuth column, does not fail.
TEST(PlaneFit, PassesOnFlatFailsOnTheCrownedRuralRoad) {
  lp::PlaneFitGround plane;
  const lp::GroundAccuracy flat = evaluateWorld("flat", &plane);
  EXPECT_GT(flat.groundPrecision(), 0.999);
  EXPECT_GT(flat.groundRecall(), 0.999);
  const lp::GroundAccuracy rural = evaluateWorld("rural", &plane);
  const lp::GroundAccuracy thesis = evaluateWorld("thesis", &plane);  // flat with obstacles
  lp::VerticalScanGround vertical_scan;
  const lp::GroundAccuracy vs = evaluateWorld("rural", &vertical_scan);
  // Flat with car-sized obstacles (thesis world): still right (measured 100 % ground recall,
  // 88.8 % obstacle recall).
  EXPECT_GT(thesis.groundRecall(), 0.99);
  EXPECT_GT(thesis.obstacleRecall(), 0.85);
  // Rural, measured (seed 1, 3 revolutions): ground recall 62.5 % (vertical scan 94.5 %), people
  // 81.1 % (vertical scan 93.1 %).
  EXPECT_LT(rural.groundRecall(), 0.70);
  EXPECT_LT(classRecall(rural, lp::sim::SurfaceClass::kPerson), 0.87);
  EXPECT_GT(vs.groundRecall(), 0.90);
  EXPECT_GT(vs.groundRecall(), rural.groundRecall() + 0.25);
  EXPECT_GT(classRecall(vs, lp::sim::SurfaceClass::kPerson), 0.90);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
