// The thesis's finding for the vertical SICK (3.3.4), on the simulator with ground truth: on
// the undulating hillside the Hough ground fit labels the ground better than the 1-DOF line of
// the vertical scan method, and on flat ground both are exact.
#include <gtest/gtest.h>

#include "ladar_perception/eval/hough_evaluation.h"

namespace lp = ladar_perception;

namespace {

lp::GroundAccuracy run(const std::string& world, lp::SickGroundFit fit, std::vector<double>* ms = nullptr) {
  lp::GroundAccuracy acc;
  std::string error;
  EXPECT_TRUE(lp::evaluateVerticalSick(world, fit, lp::sim::NoiseProfile::kDatasheet, 60, 1, &acc, ms, &error))
      << error;
  return acc;
}

TEST(HoughGroundSim, BeatsTheOneDofLineOnTheHillside) {
  const lp::GroundAccuracy hough = run("hillside", lp::SickGroundFit::kHough);
  const lp::GroundAccuracy one_dof = run("hillside", lp::SickGroundFit::kOneDof);
  ASSERT_GT(hough.points, 5000u);
  EXPECT_GT(hough.groundRecall(), one_dof.groundRecall() + 0.02);
  EXPECT_GT(hough.groundRecall(), 0.97);
  EXPECT_GE(hough.groundPrecision(), 0.99);
}

TEST(HoughGroundSim, FlatGroundIsExact) {
  std::vector<double> ms;
  const lp::GroundAccuracy hough = run("flat", lp::SickGroundFit::kHough, &ms);
  EXPECT_EQ(hough.groundRecall(), 1.0);
  EXPECT_EQ(hough.groundPrecision(), 1.0);
  EXPECT_EQ(ms.size(), 60u);
  EXPECT_EQ(run("flat", lp::SickGroundFit::kOneDof).groundRecall(), 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
