// The analog signal approach (thesis 3.2) as a ground model: right on planes (a tilt is the
// first harmonic), wrong where the thesis says it fails (crowned road, hillside).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ground_surface_scene.h"
#include "ladar_perception/ground/analog_signal.h"
#include "ladar_perception/ground/ground_evaluation.h"
#include "ladar_perception/ground/ground_model.h"

namespace lp = ladar_perception;
using surface_test::SurfaceScene;

namespace {

struct Score {
  double ground_recall = 0, obstacle_recall = 0;
};

Score score(lp::GroundModel* model, const SurfaceScene& scene, bool with_ring = true) {
  lp::PackedCloud cloud;
  std::vector<uint8_t> truth;
  scene.revolution(&cloud, &truth, with_ring);
  lp::PointCloudView view;
  EXPECT_TRUE(cloud.view(&view));
  lp::GroundClassification result;
  model->classify(view, lp::SensorPose::fromHeight(static_cast<float>(scene.sensor_height)), &result);
  EXPECT_EQ(result.size(), view.size());
  std::size_t g = 0, g_ok = 0, o = 0, o_ok = 0;
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    if (truth[i] == 0) {
      ++g;
      g_ok += result.labels[i] == lp::kLabelGround;
    } else if (p.z() + scene.sensor_height - scene.ground(p.x(), p.y()) > 0.3) {
      ++o;
      o_ok += result.labels[i] == lp::kLabelObstacle;
    }
  }
  Score s;
  s.ground_recall = g ? static_cast<double>(g_ok) / g : 1.0;
  s.obstacle_recall = o ? static_cast<double>(o_ok) / o : 1.0;
  return s;
}

SurfaceScene withCar(SurfaceScene scene) {
  scene.boxes.push_back({{10.0, -1.0, -1.0}, {14.5, 1.0, 1.5}});
  scene.boxes.push_back({{-8.0, 5.0, -1.0}, {-7.7, 5.3, 3.0}});
  return scene;
}

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

lp::GroundAccuracy evaluateWorld(const std::string& world, lp::GroundModel* model) {
  lp::GroundAccuracy acc;
  std::string error;
  EXPECT_TRUE(lp::evaluateGroundModel(world, model, lp::sim::NoiseProfile::kDatasheet, 3, 1, &acc, &error))
      << error;
  return acc;
}

double classRecall(const lp::GroundAccuracy& acc, lp::sim::SurfaceClass c) {
  const int k = static_cast<int>(c);
  return lp::GroundAccuracy::ratio(acc.class_correct[k], acc.class_points[k]);
}

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
