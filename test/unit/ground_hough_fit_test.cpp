// The Hough ground fit on (r, Height) pairs of analytic vertical scans (thesis 3.3.4).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ground_hough_scene.h"
#include "ladar_perception/ground/hough_ground.h"

namespace lp = ladar_perception;
using hough_test::VerticalScene;

namespace {

struct Labelled {
  std::vector<float> r, h;
  std::vector<uint8_t> truth, labels;
  std::vector<float> p;
  lp::GroundLineFit fit;
};

Labelled fitScene(const VerticalScene& scene, const lp::HoughGroundParams& params = lp::houghGroundDefaultParams()) {
  Labelled out;
  scene.pairs(&out.r, &out.h, &out.truth);
  lp::HoughLineFitter fitter(params);
  out.fit = fitter.fit(out.r.data(), out.h.data(), static_cast<int>(out.r.size()));
  out.labels.resize(out.r.size());
  out.p.resize(out.r.size());
  lp::classifyAgainstLine(out.fit, out.r.data(), out.h.data(), static_cast<int>(out.r.size()),
                          params.tolerances, out.labels.data(), out.p.data());
  return out;
}

class KnownLine : public ::testing::TestWithParam<std::pair<double, double>> {};

// Known lines are recovered exactly (to float precision) although neither Ground nor Slope
// lies on an accumulator cell: the least-squares refinement removes the quantisation.
TEST_P(KnownLine, RecoveredExactly) {
  const double ground = GetParam().first, slope = GetParam().second;
  VerticalScene scene;
  scene.addGroundLine(ground, slope);
  const Labelled s = fitScene(scene);
  ASSERT_TRUE(s.fit.valid);
  EXPECT_NEAR(s.fit.ground, ground, 2e-4);
  EXPECT_NEAR(s.fit.slope, slope, 2e-5);
  EXPECT_LT(s.fit.rms, 1e-4);
  EXPECT_GT(s.fit.inliers, 50);
  EXPECT_GE(s.fit.inliers, s.fit.cell_count - 2);
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    if (s.truth[i] == 2) {
      EXPECT_EQ(s.labels[i], lp::kLabelUnknown);
    } else {
      EXPECT_EQ(s.labels[i], lp::kLabelGround) << "r " << s.r[i] << " h " << s.h[i];
      EXPECT_LT(s.p[i], 0.01f);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(FlatSlopedOffset, KnownLine,
                         ::testing::Values(std::make_pair(0.0, 0.0),       // flat
                                           std::make_pair(0.0, 0.1237),    // uphill
                                           std::make_pair(0.0, -0.0813),   // downhill
                                           std::make_pair(0.377, 0.0),     // offset
                                           std::make_pair(-0.613, 0.0561), // offset and sloped
                                           std::make_pair(0.252, -0.1333)));

TEST(HoughGroundFit, ThesisSettingsAreLimitedToTheCell) {
  VerticalScene scene;
  scene.addGroundLine(0.377, 0.0561);
  const lp::HoughGroundParams p = lp::houghGroundThesisParams();
  const Labelled s = fitScene(scene, p);
  ASSERT_TRUE(s.fit.valid);
  // The accumulator argmax, exactly a cell centre: a line within ErrorTolerance of the truth
  // where the returns are (count(|ErrorValue| < ErrorTolerance) cannot tell more).
  for (float r : {1.f, 5.f, 15.f, 30.f}) {
    EXPECT_NEAR(s.fit.ground + s.fit.slope * r, 0.377 + 0.0561 * r, p.error_tolerance) << r;
  }
  EXPECT_EQ(s.fit.ground, s.fit.cell_ground);
  EXPECT_EQ(s.fit.slope, s.fit.cell_slope);
}

TEST(HoughGroundFit, NoisyLineWithinNoise) {
  VerticalScene scene;
  scene.addGroundLine(0.21, -0.047);
  Labelled s;
  scene.pairs(&s.r, &s.h, &s.truth);
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (float& h : s.h) h += noise(rng);
  lp::HoughLineFitter fitter;
  const lp::GroundLineFit fit = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()));
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.ground, 0.21, 0.015);
  EXPECT_NEAR(fit.slope, -0.047, 0.003);
  EXPECT_NEAR(fit.rms, 0.02, 0.008);
}

TEST(HoughGroundFit, OutliersAreObstaclesAndDoNotMoveTheLine) {
  VerticalScene scene;
  scene.addGroundLine(-0.1, 0.03);
  Labelled s;
  scene.pairs(&s.r, &s.h, &s.truth);
  // Every third return replaced by clutter 0.5 to 3 m above or 0.4 to 1 m below the ground.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> up(0.5f, 3.f), down(0.4f, 1.f);
  std::vector<uint8_t> outlier(s.r.size(), 0);
  for (std::size_t i = 0; i < s.r.size(); i += 3) {
    if (!std::isfinite(s.r[i])) continue;
    s.h[i] += (i % 2) ? up(rng) : -down(rng);
    outlier[i] = 1;
  }
  lp::HoughLineFitter fitter;
  const lp::GroundLineFit fit = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()));
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.ground, -0.1, 1e-3);
  EXPECT_NEAR(fit.slope, 0.03, 1e-4);
  std::vector<uint8_t> labels(s.r.size());
  std::vector<float> p(s.r.size());
  lp::classifyAgainstLine(fit, s.r.data(), s.h.data(), static_cast<int>(s.r.size()),
                          fitter.params().tolerances, labels.data(), p.data());
  // Eq 3.15 needs |GndError| > SlopeErrorMax * r / 2 as well: within 15 m every outlier
  // (0.4 m and more off the line) is an obstacle; farther, only the ground must stay ground.
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    if (!std::isfinite(s.r[i]) || (outlier[i] && s.r[i] > 15.f)) continue;
    EXPECT_EQ(labels[i], outlier[i] ? lp::kLabelObstacle : lp::kLabelGround)
        << "r " << s.r[i] << " h " << s.h[i];
  }
}

// The thesis's Figure 3.5b: an obstacle in front of a wall. The box shadows the ground between
// it and the wall, and the wall offers many returns at one r; the ground line must still be
// the ground, the box and the wall obstacles.
TEST(HoughGroundFit, ObstacleInFrontOfAWall) {
  VerticalScene scene;
  scene.sensor_height = 1.2;
  scene.addGroundLine(0.0, 0.0, -200.0, 14.0);
  scene.addBox(6.0, 7.0, 0.0, 0.9);
  scene.addWall(14.0, 0.0, 6.0);
  // The lower outlier of the figure: a reflection seen below the ground near the wall.
  scene.segments.push_back({{11.0, -0.8}, {11.6, -0.8}, 1});
  const Labelled s = fitScene(scene);
  ASSERT_TRUE(s.fit.valid);
  EXPECT_NEAR(s.fit.ground, 0.0, 1e-3);
  EXPECT_NEAR(s.fit.slope, 0.0, 1e-4);
  int obstacles = 0, ground = 0;
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    if (s.truth[i] == 2) continue;
    if (s.truth[i] == 0) {
      EXPECT_EQ(s.labels[i], lp::kLabelGround) << "r " << s.r[i];
      ++ground;
    } else if (std::fabs(s.h[i]) > 0.25f) {  // the lowest centimetres of a face are ground-like
      EXPECT_EQ(s.labels[i], lp::kLabelObstacle) << "r " << s.r[i] << " h " << s.h[i];
      ++obstacles;
    }
  }
  EXPECT_GT(ground, 40);
  EXPECT_GT(obstacles, 30);
}

// Where the 1-DOF fit of the vertical scan method fails: the ground ahead does not pass through
// the point under the sensor (undulating terrain: the vehicle stands in a dip). The Hough fit
// finds the line; the 1-DOF line pinned to Height 0 mislabels ground.
TEST(HoughGroundFit, BeatsTheOneDofFitWhenTheGroundIsOffset) {
  VerticalScene scene;
  scene.addGroundLine(0.45, 0.02);
  const Labelled s = fitScene(scene);
  ASSERT_TRUE(s.fit.valid);
  EXPECT_NEAR(s.fit.ground, 0.45, 1e-3);
  lp::OneDofLineFitter one_dof;
  const lp::GroundLineFit f1 =
      one_dof.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()), 0.5f, 40.f);
  ASSERT_TRUE(f1.valid);
  std::vector<uint8_t> l1(s.r.size());
  std::vector<float> p1(s.r.size());
  lp::classifyAgainstLine(f1, s.r.data(), s.h.data(), static_cast<int>(s.r.size()),
                          lp::ObstacleToleranceParams(), l1.data(), p1.data());
  int hough_wrong = 0, one_dof_wrong = 0;
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    if (s.truth[i] != 0) continue;
    hough_wrong += s.labels[i] != lp::kLabelGround;
    one_dof_wrong += l1[i] != lp::kLabelGround;
  }
  EXPECT_EQ(hough_wrong, 0);
  EXPECT_GT(one_dof_wrong, 10);
}

// Beyond the thesis: a hill rising away ahead (flat to 12 m, then 12% and 24%). The straight
// line fits the near ground; the bends follow the hill, so its returns stay ground, while a car
// standing on the hill is still an obstacle.
TEST(HoughGroundFit, BendsFollowAHillRisingAhead) {
  VerticalScene scene;
  scene.sensor_height = 1.7;
  scene.segments.push_back({{-200.0, 0.0}, {12.0, 0.0}, 0});
  scene.segments.push_back({{12.0, 0.0}, {22.0, 1.2}, 0});
  scene.segments.push_back({{22.0, 1.2}, {200.0, 1.2 + 0.24 * 178.0}, 0});
  scene.addBox(30.0, 34.5, 1.2 + 0.24 * 8.0, 1.5);
  const Labelled bent = fitScene(scene);
  lp::HoughGroundParams straight_params;
  straight_params.bend_segments = 0;
  const Labelled straight = fitScene(scene, straight_params);
  ASSERT_TRUE(bent.fit.valid);
  EXPECT_GE(bent.fit.bends, 2);
  EXPECT_NEAR(bent.fit.ground, 0.0, 1e-3);
  EXPECT_NEAR(bent.fit.slope, 0.0, 1e-4);
  int bent_wrong = 0, straight_wrong = 0, car = 0;
  for (std::size_t i = 0; i < bent.r.size(); ++i) {
    if (bent.truth[i] == 0) {
      bent_wrong += bent.labels[i] != lp::kLabelGround;
      straight_wrong += straight.labels[i] != lp::kLabelGround;
    } else if (bent.truth[i] == 1 && bent.h[i] > 1.2 + 0.24 * (bent.r[i] - 22.0) + 0.8) {
      // (eq 3.15 with SlopeErrorMax 0.05 needs GndError > 0.75 m at 30 m)
      EXPECT_EQ(bent.labels[i], lp::kLabelObstacle) << "r " << bent.r[i] << " h " << bent.h[i];
      ++car;
    }
  }
  EXPECT_EQ(bent_wrong, 0);
  EXPECT_GT(straight_wrong, 5);
  EXPECT_GE(car, 3);
}

TEST(HoughGroundFit, ConfidenceSeesACompetingLine) {
  // One clear ground line: the best different line has few votes.
  VerticalScene clear;
  clear.addGroundLine(0.0, 0.0);
  const Labelled a = fitScene(clear);
  ASSERT_TRUE(a.fit.valid);
  EXPECT_GT(a.fit.margin, 0.9f);
  EXPECT_LT(a.fit.runner_up, 5);
  // A raised platform 0.6 m up from 9 m on: two parallel candidate lines.
  VerticalScene two;
  two.sensor_height = 2.0;
  two.addGroundLine(0.0, 0.0, -200.0, 9.0);
  two.segments.push_back({{9.0, 0.0}, {9.0, 0.6}, 1});
  two.segments.push_back({{9.0, 0.6}, {200.0, 0.6}, 0});
  const Labelled b = fitScene(two);
  ASSERT_TRUE(b.fit.valid);
  EXPECT_GT(b.fit.runner_up, 10);
  EXPECT_LT(b.fit.margin, 0.9f);
}

TEST(HoughGroundFit, EmptyAndAllNaNGiveNoLine) {
  lp::HoughLineFitter fitter;
  lp::GroundLineFit f = fitter.fit(nullptr, nullptr, 0);
  EXPECT_FALSE(f.valid);
  std::vector<float> nan(361, std::numeric_limits<float>::quiet_NaN());
  f = fitter.fit(nan.data(), nan.data(), 361);
  EXPECT_FALSE(f.valid);
  EXPECT_EQ(f.votes, 0);
  std::vector<uint8_t> labels(361, 0);
  std::vector<float> p(361, 1.f);
  lp::classifyAgainstLine(f, nan.data(), nan.data(), 361, lp::ObstacleToleranceParams(),
                          labels.data(), p.data());
  for (int i = 0; i < 361; ++i) {
    EXPECT_EQ(labels[i], lp::kLabelUnknown);
    EXPECT_EQ(p[i], 0.f);
  }
  // Too few returns for min_inliers.
  const float r[3] = {2.f, 3.f, 4.f}, h[3] = {0.f, 0.f, 0.f};
  EXPECT_FALSE(fitter.fit(r, h, 3).valid);
}

TEST(HoughGroundFit, BadParamsAreRepaired) {
  lp::HoughGroundParams p;
  p.ground_resolution = 0.f;
  p.slope_resolution = -1.f;
  p.ground_max = p.ground_min - 1.f;
  p.error_tolerance = std::numeric_limits<float>::quiet_NaN();
  lp::HoughLineFitter fitter(p);
  EXPECT_GE(fitter.groundCells(), 1);
  EXPECT_GE(fitter.slopeCells(), 1);
  VerticalScene scene;
  scene.addGroundLine(p.ground_min, 0.0);
  Labelled s;
  scene.pairs(&s.r, &s.h, &s.truth);
  const lp::GroundLineFit f = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()));
  EXPECT_TRUE(f.valid);
}

TEST(HoughGroundFit, AccumulatorCountsTheLinesReturns) {
  VerticalScene scene;
  scene.addGroundLine(0.0, 0.0);
  Labelled s;
  scene.pairs(&s.r, &s.h, &s.truth);
  lp::HoughLineFitter fitter;
  const lp::GroundLineFit f = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()));
  int expected = 0;
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    expected += std::isfinite(s.r[i]) && s.r[i] >= 0.5f && s.r[i] <= 40.f;
  }
  const lp::HoughGroundParams& p = fitter.params();
  const int j = static_cast<int>(std::lround((0.0 - p.slope_min) / p.slope_resolution));
  const int c = static_cast<int>(std::lround((0.0 - p.ground_min) / p.ground_resolution));
  EXPECT_EQ(fitter.count(j, c), expected);
  EXPECT_EQ(f.cell_count, expected);
  EXPECT_EQ(f.votes, expected);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
