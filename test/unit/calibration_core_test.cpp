// Unit tests of the calibration core on hand-made clouds (no simulator, no ROS). Over 600
// lines: one file for the core's stages, whose tests share the hand-made scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "ladar_perception/calibration/calibrator.h"
#include "ladar_perception/calibration/experiment.h"
#include "ladar_perception/sim/world.h"

namespace lp = ladar_perception;
namespace cal = ladar_perception::calibration;

namespace {

// A hilly terrain with a few Gaussian hills of different sizes: every DOF is observable.
double hills(double x, double y) {
  return 3.0 * std::exp(-((x - 8) * (x - 8) + (y - 3) * (y - 3)) / 8.0) +
         2.5 * std::exp(-((x + 6) * (x + 6) + (y + 9) * (y + 9)) / 5.0) +
         3.0 * std::exp(-((x - 1) * (x - 1) + (y + 12) * (y + 12)) / 12.0) +
         2.0 * std::exp(-((x + 10) * (x + 10) + (y - 8) * (y - 8)) / 3.0) +
         2.0 * std::exp(-((x - 2) * (x - 2) + (y - 14) * (y - 14)) / 4.0) + 0.05 * x;
}
double flat(double, double) { return 0.0; }
// An alley along x: flat floor, walls at |y| > 4 rising 3 m (a steep smooth step).
double alley(double, double y) { return 3.0 / (1.0 + std::exp(-(std::abs(y) - 4.0) * 6.0)); }

// Samples the surface z = f(x, y) around the sensor on a jittered grid and returns the points in
// the sensor frame of `odom_to_sensor`.
template <typename F>
lp::calibration::PointVector sampleScan(F f, const Eigen::Isometry3d& odom_to_sensor,
                                        double radius, double spacing, double noise,
                                        std::mt19937* rng) {
  std::uniform_real_distribution<double> jitter(-0.5 * spacing, 0.5 * spacing);
  std::normal_distribution<double> n(0.0, noise);
  const Eigen::Vector3d c = odom_to_sensor.translation();
  const Eigen::Isometry3d inv = odom_to_sensor.inverse();
  cal::PointVector out;
  for (double x = c.x() - radius; x <= c.x() + radius; x += spacing) {
    for (double y = c.y() - radius; y <= c.y() + radius; y += spacing) {
      const double px = x + jitter(*rng), py = y + jitter(*rng);
      if ((px - c.x()) * (px - c.x()) + (py - c.y()) * (py - c.y()) > radius * radius) continue;
      const Eigen::Vector3d p(px, py, f(px, py) + (noise > 0 ? n(*rng) : 0.0));
      out.push_back((inv * p).cast<float>());
    }
  }
  return out;
}

template <typename F>
cal::CalibrationInput makeInput(F f, const cal::Pose6& reference, const cal::Pose6& target,
                                int scans, double noise, unsigned seed, double max_yaw = 0.4) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  cal::CalibrationInput in;
  in.reference_extrinsic = cal::toIsometry(reference);
  const Eigen::Isometry3d t_target = cal::toIsometry(target);
  for (int k = 0; k < scans; ++k) {
    const Eigen::Isometry3d vehicle =
        cal::toIsometry(cal::makePose(3 * u(rng), 3 * u(rng), 0, 0, 0, max_yaw * u(rng)));
    in.reference.addScan(k, vehicle,
                         sampleScan(f, vehicle * in.reference_extrinsic, 18.0, 0.35, noise, &rng));
    in.target.addScan(k, vehicle, sampleScan(f, vehicle * t_target, 18.0, 0.35, noise, &rng));
  }
  return in;
}

const cal::Pose6 kReference = cal::makePose(0, 0, 2.0, 0, 0, 0);
const cal::Pose6 kTarget = cal::makePose(1.0, 0.1, 1.8, 0.03, -0.02, 0.05);

}  // namespace

TEST(CalibrationPose, RoundTripAndNames) {
  const cal::Pose6 p = cal::makePose(1, -2, 3, 0.1, -0.2, 2.5);
  const cal::Pose6 q = cal::fromIsometry(cal::toIsometry(p));
  EXPECT_LT((p - q).norm(), 1e-12);
  EXPECT_STREQ(cal::dofName(cal::kYaw), "yaw");
  EXPECT_EQ(cal::dofIndex("pitch"), cal::kPitch);
  EXPECT_EQ(cal::dofIndex("bogus"), -1);
  EXPECT_NEAR(cal::wrapAngle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(cal::poseDifference(cal::makePose(0, 0, 0, 0, 0, 3.1),
                                  cal::makePose(0, 0, 0, 0, 0, -3.1))[cal::kYaw],
              -2 * M_PI + 6.2, 1e-12);
}

TEST(CalibrationAccumulation, ProjectsThroughVehiclePoseAndExtrinsic) {
  cal::ScanSet scans;
  const Eigen::Isometry3d v1 = cal::toIsometry(cal::makePose(10, 0, 0, 0, 0, M_PI / 2));
  scans.addScan(0.0, Eigen::Isometry3d::Identity(), cal::PointVector{{1, 0, 0}});
  scans.addScan(0.1, v1, cal::PointVector{{1, 0, 0}, {0, 1, 0}});
  const Eigen::Isometry3d ext = cal::toIsometry(cal::makePose(1, 0, 2, 0, 0, 0));
  cal::PointVector out;
  cal::accumulate(scans, ext, &out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_LT((out[0] - Eigen::Vector3f(2, 0, 2)).norm(), 1e-5);
  // Vehicle at (10,0) facing +y: sensor at base (1,0,2) -> odom (10,1,2); its x axis is odom +y.
  EXPECT_LT((out[1] - Eigen::Vector3f(10, 2, 2)).norm(), 1e-5);
  EXPECT_LT((out[2] - Eigen::Vector3f(9, 1, 2)).norm(), 1e-5);
  const cal::ScanSet second = scans.subset(1, 2);
  EXPECT_EQ(second.numScans(), 1u);
  EXPECT_EQ(second.numPoints(), 2u);
}

TEST(CalibrationAccumulation, VoxelCentroidsAndLaserScan) {
  const cal::PointVector pts = {{0.1f, 0.1f, 0.1f}, {0.3f, 0.3f, 0.3f}, {1.5f, 0.1f, 0.1f}};
  cal::PointVector v = cal::voxelDownsample(pts, 1.0);
  ASSERT_EQ(v.size(), 2u);
  const bool first = (v[0] - Eigen::Vector3f(0.2f, 0.2f, 0.2f)).norm() < 1e-6 ||
                     (v[1] - Eigen::Vector3f(0.2f, 0.2f, 0.2f)).norm() < 1e-6;
  EXPECT_TRUE(first);
  const float ranges[4] = {1.0f, NAN, 100.0f, 2.0f};
  cal::PointVector scan;
  cal::pointsFromLaserScan(ranges, 4, -M_PI / 2, M_PI / 2, 0.5, 80.0, &scan);
  ASSERT_EQ(scan.size(), 2u);  // NaN and out of range dropped
  EXPECT_LT((scan[0] - Eigen::Vector3f(0, -1, 0)).norm(), 1e-6);
  EXPECT_LT((scan[1] - Eigen::Vector3f(-2, 0, 0)).norm(), 1e-5);
}

TEST(CalibrationKdTree, MatchesBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-20, 20);
  cal::PointVector pts(2000);
  for (auto& p : pts) p = Eigen::Vector3f(u(rng), u(rng), 0.1f * u(rng));
  cal::KdTree tree(pts);
  std::vector<int> idx;
  std::vector<float> d2;
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3f query(u(rng), u(rng), u(rng));
    int best = -1;
    float best_d2 = 1e30f;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const float d = (pts[i] - query).squaredNorm();
      if (d < best_d2) { best_d2 = d; best = static_cast<int>(i); }
    }
    float got = 0;
    EXPECT_EQ(tree.nearest(query, &got), best);
    EXPECT_FLOAT_EQ(got, best_d2);
    tree.knn(query, 5, &idx, &d2);
    ASSERT_EQ(idx.size(), 5u);
    EXPECT_EQ(idx[0], best);
    for (int j = 1; j < 5; ++j) EXPECT_LE(d2[j - 1], d2[j]);
  }
  float d = 0;
  EXPECT_EQ(tree.nearest(Eigen::Vector3f(100, 100, 100), &d, 1.0f), -1);  // beyond max distance
}

TEST(CalibrationNearestGrid, MatchesBruteForceWithinItsRadius) {
  // Points on a wavy surface (1 per ~0.2 m, like the surface model) and queries around it, some
  // far from it, some with negative coordinates (cells below zero).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-6, 6);
  std::normal_distribution<float> off(0.0f, 0.4f);
  cal::PointVector pts;
  for (int i = 0; i < 4000; ++i) {
    const float x = u(rng), y = u(rng);
    pts.emplace_back(x, y, 0.5f * std::sin(x) + 0.02f * off(rng));
  }
  cal::NearestGrid grid;
  grid.build(pts, 0.5f);
  cal::KdTree tree(pts);
  int decided_far = 0;
  for (int q = 0; q < 2000; ++q) {
    const float x = u(rng), y = u(rng);
    const Eigen::Vector3f query(x, y, 0.5f * std::sin(x) + off(rng));
    for (const float max_d : {0.3f, 0.5f, 1.5f}) {
      int best = -1;
      float best_d2 = max_d * max_d;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const float d = (pts[i] - query).squaredNorm();
        if (d < best_d2) { best_d2 = d; best = static_cast<int>(i); }
      }
      float got = 0;
      const int j = grid.nearest(query, &got, max_d * max_d);
      if (max_d <= 0.5f) {  // within the cell size: always decided, and exact
        ASSERT_NE(j, cal::NearestGrid::kUndecided);
        EXPECT_EQ(j, best) << q << " " << max_d;
        EXPECT_FLOAT_EQ(got, best_d2);
      } else if (j != cal::NearestGrid::kUndecided) {  // decided beyond it: only when found
        EXPECT_EQ(j, best);
        EXPECT_LE(got, 0.25f);
        ++decided_far;
      } else {
        EXPECT_TRUE(best < 0 || best_d2 > 0.25f);
        EXPECT_EQ(tree.nearest(query, &got, max_d * max_d), best);
      }
    }
  }
  EXPECT_GT(decided_far, 1000);  // most queries near the surface
  float d = 0;
  EXPECT_EQ(grid.nearest(Eigen::Vector3f(100, 100, 100), &d, 0.25f), -1);
  EXPECT_FLOAT_EQ(d, 0.25f);
  EXPECT_EQ(grid.nearest(Eigen::Vector3f(100, 100, 100), &d, 4.0f), cal::NearestGrid::kUndecided);
  EXPECT_EQ(grid.nearest(Eigen::Vector3f(NAN, 0, 0), &d, 0.25f), cal::NearestGrid::kUndecided);
  cal::NearestGrid empty;
  empty.build({}, 0.5f);
  EXPECT_EQ(empty.nearest(Eigen::Vector3f::Zero(), &d, 0.25f), -1);
}

TEST(CalibrationFeatures, LocalMaximaAndMinimaPerBin) {
  // Two bins of 2 m: [0,2)x[0,2) and [2,4)x[0,2).
  const cal::PointVector pts = {{0.5f, 0.5f, 1.0f}, {1.5f, 1.5f, 3.0f}, {1.0f, 0.2f, -1.0f},
                                {2.5f, 0.5f, 0.5f}, {3.5f, 1.0f, 0.7f}};
  const cal::FeatureSet f = cal::extractFeatures(pts, 2.0);
  ASSERT_EQ(f.maxima.size(), 2u);
  ASSERT_EQ(f.minima.size(), 2u);
  EXPECT_FLOAT_EQ(f.maxima[0].z(), 3.0f);
  EXPECT_FLOAT_EQ(f.minima[0].z(), -1.0f);
  EXPECT_FLOAT_EQ(f.maxima[1].z(), 0.7f);
  EXPECT_FLOAT_EQ(f.minima[1].z(), 0.5f);
  EXPECT_TRUE(cal::extractFeatures({}, 2.0).maxima.empty());
  // Negative coordinates bin from the origin too: (-0.5) and (0.5) fall in different bins.
  EXPECT_EQ(cal::extractFeatures({{-0.5f, 0.f, 0.f}, {0.5f, 0.f, 0.f}}, 2.0).maxima.size(), 2u);
}

TEST(CalibrationErrorMetrics, TrimmedClosestPointEq41) {
  const cal::PointVector ref = {{0, 0, 0}, {10, 0, 0}};
  cal::KdTree tree(ref);
  // Squared distances 1, 4, 9, 16 -> smallest half: (1 + 4) / 2.
  const cal::PointVector cloud = {{0, 0, 1}, {10, 2, 0}, {0, 3, 0}, {14, 0, 0}};
  EXPECT_DOUBLE_EQ(cal::trimmedClosestPoint(tree, cloud, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(cal::trimmedClosestPoint(tree, cloud, 1.0), 7.5);
  EXPECT_TRUE(std::isinf(cal::trimmedClosestPoint(tree, {}, 0.5)));
}

TEST(CalibrationErrorMetrics, AverageHeightInGrid) {
  cal::HeightGrid grid;
  grid.build({{0.5f, 0.5f, 1.0f}, {0.6f, 0.4f, 3.0f}, {1.5f, 0.5f, 0.0f}}, 1.0);
  // Bin (0,0): mean 2 vs 2.5 -> 0.25; bin (1,0): 0 vs 1 -> 1; bin (5,5) not in the reference.
  const cal::PointVector target = {{0.2f, 0.2f, 2.5f}, {1.2f, 0.2f, 1.0f}, {5.5f, 5.5f, 9.0f}};
  EXPECT_DOUBLE_EQ(grid.error(target), (0.25 + 1.0) / 2);
  EXPECT_TRUE(std::isinf(grid.error({{50.f, 50.f, 0.f}})));
}

namespace {
// A bowl with a known minimum and some ripple, as an easy synthetic case for every search method.
struct Bowl {
  cal::Pose6 truth = cal::makePose(0.4, -0.3, 0.2, 0.05, -0.08, 0.12);
  double operator()(const cal::Pose6& p) const {
    const cal::Pose6 d = p - truth;
    cal::Pose6 s;
    s << 1, 1, 1, 5, 5, 5;
    return (d.cwiseProduct(s)).squaredNorm();
  }
};
void expectRecovers(const cal::SearchResult& r, const Bowl& bowl, double tol_t, double tol_r) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.best[i], bowl.truth[i], tol_t) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_NEAR(r.best[i], bowl.truth[i], tol_r) << cal::dofName(i);
  EXPECT_GT(r.evaluations, 0);
  EXPECT_FALSE(r.trace.empty());
}
cal::SearchParams bowlParams() {
  cal::SearchParams p;
  p.spread << 1, 1, 1, 0.2, 0.2, 0.2;
  p.min_spread << 0.005, 0.005, 0.005, 0.001, 0.001, 0.001;
  p.max_iterations = 100;
  return p;
}
}  // namespace

TEST(CalibrationSearch, EveryMethodRecoversAKnownOffset) {
  const Bowl bowl;
  const cal::CostFn cost = [&bowl](const cal::Pose6& p) { return bowl(p); };
  const cal::SearchParams p = bowlParams();
  expectRecovers(cal::gradientDescent(cost, p), bowl, 0.03, 0.01);
  expectRecovers(cal::multiScaleGradientDescent(cost, p), bowl, 0.02, 0.005);
  expectRecovers(cal::intervalSearch(cost, p), bowl, 0.02, 0.005);
  expectRecovers(cal::semiIndependentIntervalSearch(cost, p), bowl, 0.02, 0.005);
  cal::SearchParams pf = p;
  pf.max_iterations = 200;
  const cal::SearchResult r = cal::particleFilter(cost, pf);
  expectRecovers(r, bowl, 0.03, 0.01);
  EXPECT_LT((r.weighted_mean - bowl.truth).head<3>().norm(), 0.3);
}

TEST(CalibrationSearch, ProgressCanCancel) {
  const Bowl bowl;
  int calls = 0;
  const cal::SearchResult r = cal::intervalSearch(
      [&bowl](const cal::Pose6& p) { return bowl(p); }, bowlParams(),
      [&calls](const cal::SearchProgress& pr) { ++calls; return pr.iteration < 2; });
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(calls, 2);
}

TEST(CalibrationRefinement, PointToPlaneRecoversOffsetOnHills) {
  const cal::CalibrationInput in = makeInput(hills, kReference, kTarget, 4, 0.02, 7);
  cal::RefinementParams rp;
  cal::PointVector ref;
  cal::accumulate(in.reference, in.reference_extrinsic, &ref);
  cal::SurfaceModel model;
  model.build(cal::voxelDownsample(ref, rp.reference_voxel), rp);
  ASSERT_GT(model.size(), 1000u);
  const cal::Pose6 start = kTarget + cal::makePose(0.15, -0.1, 0.1, -0.01, 0.015, 0.02);
  const cal::RefinementResult r = cal::refine(model, cal::refinementTarget(in.target, rp), start, rp);
  const cal::Pose6 err = cal::poseDifference(r.extrinsic, kTarget);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.02) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.003) << cal::dofName(i);
}

TEST(CalibrationRefinement, NormalSpaceThinningKeepsFacesAndOneInNOfTheGround) {
  // Level ground and a wall across x = 10 m; the target sees both from the same place.
  cal::PointVector reference, ground, wall;
  for (double x = 0.0; x <= 12.0; x += 0.2) {
    for (double y = -5.0; y <= 5.0; y += 0.2) reference.emplace_back(x, y, 0.0f);
  }
  for (double y = -5.0; y <= 5.0; y += 0.2) {
    for (double z = 0.6; z <= 3.0; z += 0.2) reference.emplace_back(10.0f, y, z);
  }
  for (double x = 1.05; x <= 9.0; x += 0.1) {
    for (double y = -4.0; y <= 4.0; y += 0.5) ground.emplace_back(x, y, 0.01f);
  }
  for (double y = -4.0; y <= 4.0; y += 0.1) wall.emplace_back(9.98f, y, 1.5f);
  cal::PointVector both = ground;
  both.insert(both.end(), wall.begin(), wall.end());
  cal::ScanSet target;
  target.addScan(0.0, Eigen::Isometry3d::Identity(), both);
  cal::RefinementParams rp;
  rp.reference_voxel = 0.2;
  cal::SurfaceModel model;
  model.build(reference, rp);
  const cal::Pose6 at = cal::Pose6::Zero();
  const cal::ScanSet thinned = cal::thinLevelSurfaceReturns(model, target, at, 0.5, 0.8, 4);
  ASSERT_EQ(thinned.numScans(), 1u);
  std::size_t kept_ground = 0, kept_wall = 0;
  for (const Eigen::Vector3f& p : thinned.points) (p.x() > 9.5f ? kept_wall : kept_ground)++;
  EXPECT_EQ(kept_wall, wall.size());  // every return on the face
  EXPECT_EQ(kept_ground, (ground.size() + 3) / 4);  // one in four on the level ground
  // keep_every 1 is the identity.
  EXPECT_EQ(cal::thinLevelSurfaceReturns(model, target, at, 0.5, 0.8, 1).numPoints(), both.size());
}

TEST(CalibrationObservability, FlatPlaneAndAlleyAreNamed) {
  cal::Matrix6 h = cal::Matrix6::Zero();
  h.diagonal() << 1e-6, 1e-6, 100, 80, 90, 1e-7;  // a plane: only z, roll, pitch constrained
  cal::Observability o = cal::analyseObservability(h, 0.01, 100, 1.0);
  EXPECT_EQ(o.unobservable_names, (std::vector<std::string>{"x", "y", "yaw"}));
  EXPECT_TRUE(std::isinf(o.stddev[cal::kX]));
  EXPECT_NEAR(o.stddev[cal::kZ], std::sqrt(0.01 / 100), 1e-9);
  h.setIdentity();
  h *= 50;
  h(0, 0) = 1e-4;  // alley along x
  o = cal::analyseObservability(h, 0.01, 100, 1.0);
  EXPECT_EQ(o.unobservable_names, (std::vector<std::string>{"x"}));
  o = cal::analyseObservability(100 * cal::Matrix6::Identity(), 0.01, 100, 1.0);
  EXPECT_TRUE(o.observable());
}

// The per-point rule: a direction whose points' second differences only wobble about zero is
// weak however large its Hessian eigenvalue, and a weak-but-real curvature (a 2D target's
// ground-line directions) fixes its DOF when the standard deviation it gives is within the
// accuracy wanted, whatever its ratio to the strongest.
TEST(CalibrationObservability, PerPointCurvatureAgainstNoiseAndTolerance) {
  const int n = 20000;
  const double h = 0.1;
  cal::Matrix6 hess = cal::Matrix6::Zero();
  hess.diagonal() << 1e-4, 1e-4, 1.0, 1.0, 1.0, 1.0;  // per correspondence, lever arm 1
  hess *= n;
  // Loss of point i at a step: 0.5 c_d (step_d)^2 summed over d plus a per-point wobble.
  const auto make = [&](const cal::Pose6& curv, const cal::Pose6& wobble) {
    return [=](const cal::Pose6& step, std::vector<float>* losses) {
      losses->assign(n, 0.0f);
      for (int i = 0; i < n; ++i) {
        double l = 1e-3;
        for (int d = 0; d < 6; ++d) {
          const double sign = ((i * 7919 + d * 104729) % 2) ? 1.0 : -1.0;
          l += 0.5 * curv[d] * step[d] * step[d] + sign * wobble[d] * std::abs(step[d]) / h;
        }
        (*losses)[i] = static_cast<float>(l);
      }
    };
  };
  cal::Pose6 curv;
  curv << 1e-4, 1e-4, 1.0, 1.0, 1.0, 1.0;
  // Curvature 1e-4 of the strongest but sigma^2 1e-4 over 20000 points: 0.007 m, fixed.
  cal::Observability o = cal::analyseObservability(hess, 1e-4, n, 1.0, cal::ObservabilityParams(),
                                                   nullptr, make(curv, cal::Pose6::Zero()));
  EXPECT_TRUE(o.observable()) << o.measured_stddev.transpose();
  EXPECT_NEAR(o.measured_stddev[cal::kX], std::sqrt(1e-4 / (n * 1e-4)), 1e-4);
  // The same Hessian, but along x and y the points' losses only wobble (no mean curvature).
  curv[cal::kX] = curv[cal::kY] = 0.0;
  cal::Pose6 wobble = cal::Pose6::Zero();
  wobble[cal::kX] = wobble[cal::kY] = 1e-5;
  o = cal::analyseObservability(hess, 1e-4, n, 1.0, cal::ObservabilityParams(), nullptr,
                                make(curv, wobble));
  EXPECT_EQ(o.unobservable_names, (std::vector<std::string>{"x", "y"}));
  // A real curvature too weak for the accuracy wanted: sigma^2 = 1 gives 0.7 m in x.
  curv[cal::kX] = curv[cal::kY] = 1e-4;
  o = cal::analyseObservability(hess, 1.0, n, 1.0, cal::ObservabilityParams(), nullptr,
                                make(curv, cal::Pose6::Zero()));
  EXPECT_EQ(o.unobservable_names, (std::vector<std::string>{"x", "y"}));
}

// The reported standard deviation against the spread of the solutions over draws of a
// reference whose surface model is off by a smooth field (bumps of a few metres, 3 cm): the
// residuals of the target points on one patch then share its error. sigma^2 H^-1 counts them as
// independent and is several times too small; the sandwich over 8 m clusters of the scores
// comes within a factor of two of the spread.
TEST(CalibrationObservability, ClusterSandwichCoversCorrelatedModelError) {
  const int draws = 8;
  std::vector<cal::Pose6> errors, independent, sandwich;
  for (int d = 0; d < draws; ++d) {
    std::mt19937 rng(100 + d);
    std::uniform_real_distribution<double> centre(-20.0, 20.0);
    std::normal_distribution<double> amplitude(0.0, 0.03);
    std::vector<Eigen::Vector3d> bumps;  // x, y, height
    for (int b = 0; b < 40; ++b) bumps.emplace_back(centre(rng), centre(rng), amplitude(rng));
    const auto off = [&](double x, double y) {
      double z = hills(x, y);
      for (const Eigen::Vector3d& b : bumps) {
        z += b.z() * std::exp(-((x - b.x()) * (x - b.x()) + (y - b.y()) * (y - b.y())) / 8.0);
      }
      return z;
    };
    cal::CalibrationInput in;
    in.reference_extrinsic = cal::toIsometry(kReference);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Isometry3d vehicle =
          cal::toIsometry(cal::makePose(3 * u(rng), 3 * u(rng), 0, 0, 0, 0.4 * u(rng)));
      in.reference.addScan(k, vehicle, sampleScan(off, vehicle * in.reference_extrinsic, 18.0,
                                                  0.35, 0.0, &rng));
      in.target.addScan(k, vehicle,
                        sampleScan(hills, vehicle * cal::toIsometry(kTarget), 18.0, 0.35, 0.01, &rng));
    }
    cal::RefinementParams rp;
    rp.max_correspondence_start = rp.max_correspondence_end;
    cal::PointVector ref;
    cal::accumulate(in.reference, in.reference_extrinsic, &ref);
    cal::SurfaceModel model;
    model.build(cal::voxelDownsample(ref, rp.reference_voxel), rp);
    const cal::ScanSet target = cal::refinementTarget(in.target, rp);
    const cal::Pose6 solution = cal::refine(model, target, kTarget, rp).extrinsic;
    const cal::ObservabilityParams op;
    const cal::Linearisation lin =
        cal::linearise(model, target, solution, rp.max_correspondence_end, rp, nullptr, op.score_cluster);
    ASSERT_GE(lin.score_clusters, op.min_score_clusters);
    errors.push_back(cal::poseDifference(solution, kTarget));
    independent.push_back(cal::analyseObservability(lin.hessian, lin.residual_variance,
                                                    lin.correspondences, lin.lever_arm, op).stddev);
    sandwich.push_back(cal::analyseObservability(lin.hessian, lin.residual_variance,
                                                 lin.correspondences, lin.lever_arm, op, nullptr,
                                                 nullptr, &lin.score_covariance).stddev);
    for (int i = 0; i < 6; ++i) EXPECT_GE(sandwich.back()[i], independent.back()[i]);
  }
  // Per translation DOF: the RMS error over the draws against the mean reported stddev.
  for (int i = 0; i < 3; ++i) {
    double rms = 0, mean_independent = 0, mean_sandwich = 0;
    for (int d = 0; d < draws; ++d) {
      rms += errors[d][i] * errors[d][i] / draws;
      mean_independent += independent[d][i] / draws;
      mean_sandwich += sandwich[d][i] / draws;
    }
    rms = std::sqrt(rms);
    EXPECT_LT(mean_independent, 0.4 * rms) << cal::dofName(i);
    EXPECT_GT(mean_sandwich, 0.5 * rms) << cal::dofName(i);
    EXPECT_LT(mean_sandwich, 3.0 * rms) << cal::dofName(i);
    std::printf("%s: rms error %.4f m, stddev independent %.4f m, sandwich %.4f m\n",
                cal::dofName(i), rms, mean_independent, mean_sandwich);
  }
}

TEST(CalibrationCalibrator, DefaultMethodOnHills) {
  const cal::CalibrationInput in = makeInput(hills, kReference, kTarget, 6, 0.03, 11);
  cal::CalibrationParams p;
  p.initial = kTarget + cal::makePose(0.6, -0.5, 0.4, 0.1, -0.1, 0.15);
  p.bin_size = 2.0;
  int reports = 0;
  const cal::CalibrationResult r =
      cal::calibrate(in, p, [&reports](const cal::SearchProgress&) { ++reports; return true; });
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_GT(reports, 0);
  const cal::Pose6 err = cal::poseDifference(r.extrinsic, kTarget);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.03) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.005) << cal::dofName(i);
  EXPECT_TRUE(r.unobservable.empty());
  EXPECT_EQ(r.restarts, 0);
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(std::isfinite(r.stddev[i]));
  const cal::Pose6 rep = cal::repeatability(in, p, r.extrinsic, 2);
  EXPECT_LT(rep.head<3>().maxCoeff(), 0.05);
}

TEST(CalibrationCalibrator, ASolutionOutsideTheSearchRegionRestartsTheCoarseSearch) {
  // The truth lies 0.6 m from the guess, the region allows 1.5 x 0.1 m: every attempt's
  // refinement leaves the region; the coarse search is started again coarse_restarts times, then
  // the failure is reported, not a solution.
  const cal::CalibrationInput in = makeInput(hills, kReference, kTarget, 4, 0.02, 5);
  cal::CalibrationParams p;
  p.initial = kTarget + cal::makePose(0.6, 0.0, 0.0, 0.0, 0.0, 0.0);
  p.spread << 0.1, 0.1, 0.1, 0.02, 0.02, 0.02;
  p.coarse_restarts = 2;
  const cal::CalibrationResult r = cal::calibrate(in, p);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.restarts, 2);
  EXPECT_NE(r.message.find("search region"), std::string::npos) << r.message;
  EXPECT_GT(r.cpu_time, 0.0);
}

TEST(CalibrationCalibrator, DegenerateScenesAreReportedByName) {
  cal::CalibrationParams p;
  p.initial = kTarget + cal::makePose(0.1, 0.1, 0.05, 0.01, 0.01, 0.02);
  p.method = "refine";
  cal::CalibrationResult r = cal::calibrate(makeInput(flat, kReference, kTarget, 4, 0.02, 5), p);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.unobservable, (std::vector<std::string>{"x", "y", "yaw"})) << r.message;
  // Driving along the alley without turning: with yaw diversity the walls would fix x through
  // the turning (accumulation over time), so the vehicle keeps its heading here.
  r = cal::calibrate(makeInput(alley, kReference, kTarget, 4, 0.02, 5, 0.0), p);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.unobservable, (std::vector<std::string>{"x"})) << r.message;
}

TEST(CalibrationCalibrator, BadInputIsAnsweredNotThrown) {
  cal::CalibrationParams p;
  cal::CalibrationResult r = cal::calibrate(cal::CalibrationInput(), p);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no data"), std::string::npos);
  p.method = "simulated_annealing";
  r = cal::calibrate(makeInput(hills, kReference, kTarget, 1, 0.0, 1), p);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("unknown method"), std::string::npos);
  EXPECT_TRUE(cal::isMethod("particle_filter"));
  EXPECT_EQ(cal::defaultMethod(), "coarse_to_fine");
}

namespace {
// A 2D ladar (scan plane = the sensor's x-y plane, 181 beams over 180 degrees) ray-marched onto
// z = f(x, y) from `odom_to_sensor`; points in the sensor frame, at most max_range away.
template <typename F>
cal::PointVector laserScan(F f, const Eigen::Isometry3d& odom_to_sensor, double max_range,
                           double noise, std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, noise);
  cal::PointVector out;
  for (int b = 0; b <= 180; ++b) {
    const double a = -M_PI / 2 + b * M_PI / 180;
    const Eigen::Vector3d dir_s(std::cos(a), std::sin(a), 0);
    const Eigen::Vector3d dir = odom_to_sensor.linear() * dir_s;
    const Eigen::Vector3d o = odom_to_sensor.translation();
    double lo = 0, hi = -1;
    for (double r = 0.05; r <= max_range; r += 0.05) {
      const Eigen::Vector3d p = o + r * dir;
      if (p.z() <= f(p.x(), p.y())) {
        hi = r;
        break;
      }
      lo = r;
    }
    if (hi < 0) continue;
    for (int it = 0; it < 20; ++it) {  // bisection onto the surface
      const double mid = 0.5 * (lo + hi);
      const Eigen::Vector3d p = o + mid * dir;
      (p.z() <= f(p.x(), p.y()) ? hi : lo) = mid;
    }
    const double range = 0.5 * (lo + hi) + (noise > 0 ? n(*rng) : 0.0);
    out.push_back((range * dir_s).cast<float>());
  }
  return out;
}

const cal::Pose6 kSick = cal::makePose(1.0, 0.0, 2.0, 0.0, 0.2, 0.0);  // meets the ground ~10 m ahead
}  // namespace

TEST(CalibrationScanPlane, RotationAboutTheGroundLineKeepsGroundReturns) {
  std::mt19937 rng(3);
  const cal::PointVector scan =
      laserScan(flat, cal::toIsometry(kSick), 60.0, 0.0, &rng);
  ASSERT_GT(scan.size(), 100u);
  cal::Pose6 moved;
  ASSERT_TRUE(cal::rotateAboutGroundLine(kSick, 0.12, 0.0, &moved));
  EXPECT_NEAR(moved[cal::kPitch], 0.08, 1e-9);
  EXPECT_NEAR(moved[cal::kZ], 2.0 * std::sin(0.08) / std::sin(0.2), 1e-9);  // h / sin(p) fixed
  const Eigen::Isometry3d a = cal::toIsometry(kSick), b = cal::toIsometry(moved);
  for (const Eigen::Vector3f& p : scan) {  // the same ground returns, in the same place
    EXPECT_LT(((a * p.cast<double>()) - (b * p.cast<double>())).norm(), 1e-6);
  }
  // The step direction is the derivative of that rotation (refinement.h's parametrisation).
  cal::Pose6 dir, small;
  ASSERT_TRUE(cal::groundLineStepDirection(kSick, 0.0, &dir));
  ASSERT_TRUE(cal::rotateAboutGroundLine(kSick, 1e-5, 0.0, &small));
  EXPECT_LT(cal::poseDifference(cal::applyStep(kSick, 1e-5 * dir), small).norm(), 1e-8);
  // Degenerate mounts: in the ground plane (impossible), parallel to it above (fine).
  EXPECT_TRUE(cal::grazesGround(cal::makePose(1, 0, 0.02, 0, 0.005, 0), 0.0, 0.05, 80.0));
  EXPECT_FALSE(cal::grazesGround(kSick, 0.0, 0.05, 80.0));
  EXPECT_FALSE(cal::grazesGround(cal::makePose(1, 0, 2.0, 0, 0, 0), 0.0, 0.05, 80.0));
  EXPECT_FALSE(cal::rotateAboutGroundLine(cal::makePose(1, 0, 2.0, 0, 0, 0), 0.1, 0.0, &moved));
}

// The sweep's profile along the ground-line family: a member refined before x converged (the
// coarse estimate a metre off in x: it scores several times higher whatever its rotation) is not
// comparable with those refined after, and must not bend the parabola that places the minimum.
TEST(CalibrationScanPlane, SweepProfileFitsOnlyMembersRefinedAlike) {
  const auto member = [](double angle, double x_offset) {
    cal::SweepMember m;
    m.angle = angle;
    EXPECT_TRUE(cal::rotateAboutGroundLine(kSick, angle, 0.0, &m.pose));
    m.pose[cal::kX] += x_offset;
    m.cost = 1e-3 + 0.5 * (angle - 0.005) * (angle - 0.005) + (x_offset != 0 ? 4e-3 : 0.0);
    return m;
  };
  const cal::SweepMember best = member(0.0, 0.0);
  std::vector<cal::SweepMember> profile = {member(-0.025, 0.8), member(-0.0125, 0.0), best,
                                           member(0.0125, 0.0)};
  EXPECT_TRUE(cal::refinedAlike(best, profile[1], 0.0, 0.15));
  EXPECT_TRUE(cal::refinedAlike(profile[3], best, 0.0, 0.15));  // x moves with the rotation
  EXPECT_FALSE(cal::refinedAlike(best, profile[0], 0.0, 0.15));
  double minimum = 0;
  std::size_t nearest = 99;
  double curvature = 0;
  ASSERT_TRUE(cal::sweepProfileMinimum(profile, best, 0.0, 0.15, &minimum, &nearest, &curvature));
  EXPECT_NEAR(minimum, 0.005, 1e-9);  // the three alike members' parabola
  EXPECT_EQ(nearest, 2u);
  // cost = 1e-3 + 0.5 (angle - 0.005)^2: it rises by 500 angle^2, relatively, from its minimum
  // (the polish's test of a flat profile, plane_sweep_polish_min_rise).
  EXPECT_NEAR(curvature, 500.0, 1e-6);
  // With the stale member fitted too, the minimum moves by a quarter of the members' spacing
  // (0.0035 rad: 3.5 cm in z at this mount).
  ASSERT_TRUE(cal::sweepProfileMinimum(profile, best, 0.0, 1e9, &minimum, &nearest));
  EXPECT_GT(std::abs(minimum - 0.005), 0.003);
  // Fewer than three alike members: no parabola.
  profile.pop_back();
  EXPECT_FALSE(cal::sweepProfileMinimum(profile, best, 0.0, 0.15, &minimum, &nearest));
}

// A 2D ladar's range noise moves its ground returns along their rays: weighted by the reference
// alone, the residual shrinks as the scan plane flattens (u . n -> 0), so the flatter member of
// the ground-line family scores better than the truth; with the range noise in the weighting
// (RefinementParams::range_noise) the family scores alike over a flat ground.
TEST(CalibrationRefinement, RangeNoiseWeightingRemovesTheFlatScanBias) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  cal::CalibrationInput in;
  in.reference_extrinsic = cal::toIsometry(kReference);
  const Eigen::Isometry3d t_sick = cal::toIsometry(kSick);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Isometry3d vehicle =
        cal::toIsometry(cal::makePose(3 * u(rng), 3 * u(rng), 0, 0, 0, 0.4 * u(rng)));
    in.reference.addScan(k, vehicle, sampleScan(flat, vehicle * in.reference_extrinsic, 25.0, 0.3,
                                                0.0, &rng));
    in.target.addScan(k, vehicle, laserScan(flat, vehicle * t_sick, 30.0, 0.1, &rng));
  }
  cal::RefinementParams rp;
  rp.keep_edges = true;
  rp.noise_floor = 0.02;
  cal::PointVector reference;
  cal::accumulate(in.reference, in.reference_extrinsic, &reference);
  cal::SurfaceModel model;
  model.build(cal::voxelDownsample(reference, rp.reference_voxel), rp);
  cal::Pose6 flatter;
  ASSERT_TRUE(cal::rotateAboutGroundLine(kSick, 0.05, 0.0, &flatter));  // pitch 0.15
  // The mean robust loss over the correspondences (the same returns find one in both).
  const auto cost = [&](const cal::Pose6& p, const cal::RefinementParams& params) {
    return cal::linearise(model, in.target, p, params.max_correspondence_end, params).cost;
  };
  EXPECT_LT(cost(flatter, rp), 0.8 * cost(kSick, rp));  // the bias
  rp.range_noise = 0.1;
  rp.reference_noise = 0.0025;
  EXPECT_NEAR(cost(flatter, rp), cost(kSick, rp), 0.05 * cost(kSick, rp));
}

// A tilted 2D ladar calibrated against a dense 3D reference over the hills, the SICK accumulated
// along a drive (75 Hz at ~2 m/s: one scan every ~3 cm; every 10th here), from a guess off along
// the ground-line ambiguity (z and pitch together) and in the other DOFs.
TEST(CalibrationCalibrator, TwoDimensionalTargetRecoversAKnownOffsetOnHills) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  cal::CalibrationInput in;
  in.reference_extrinsic = cal::toIsometry(kReference);
  const Eigen::Isometry3d t_sick = cal::toIsometry(kSick);
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < 6; ++k) {
    poses.push_back(cal::toIsometry(cal::makePose(3 * u(rng), 3 * u(rng), 0, 0, 0, 0.4 * u(rng))));
    in.reference.addScan(k, poses.back(),
                         sampleScan(hills, poses.back() * in.reference_extrinsic, 18.0, 0.3, 0.02, &rng));
  }
  for (std::size_t k = 0; k + 1 < poses.size(); ++k) {
    const Eigen::Vector3d a = poses[k].translation(), b = poses[k + 1].translation();
    const double ya = cal::fromIsometry(poses[k])[cal::kYaw], yb = cal::fromIsometry(poses[k + 1])[cal::kYaw];
    const int scans = static_cast<int>((b - a).norm() / 0.3) + 1;
    for (int s = 0; s < scans; ++s) {
      const double f = static_cast<double>(s) / scans;
      const Eigen::Vector3d p = a + f * (b - a);
      const Eigen::Isometry3d vehicle =
          cal::toIsometry(cal::makePose(p.x(), p.y(), 0, 0, 0, ya + f * (yb - ya)));
      in.target.addScan(k + f, vehicle, laserScan(hills, vehicle * t_sick, 30.0, 0.01, &rng));
    }
  }
  ASSERT_GT(in.target.numScans(), 20u);
  cal::CalibrationParams p;
  cal::Pose6 off_family;
  ASSERT_TRUE(cal::rotateAboutGroundLine(kSick, -0.1, 0.0, &off_family));  // z ~1 m too high
  p.initial = off_family + cal::makePose(0.2, -0.15, 0.0, 0.03, 0.0, 0.05);
  p.spread << 0.5, 0.5, 1.2, 0.1, 0.15, 0.1;
  const cal::CalibrationResult r = cal::calibrate(in, p);
  EXPECT_FALSE(r.plane_sweep.empty());
  const cal::Pose6 err = cal::poseDifference(r.extrinsic, kSick);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.05) << cal::dofName(i) << " " << r.message;
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.01) << cal::dofName(i) << " " << r.message;
}

// Along a weak direction the nearest-neighbour correspondences re-form after each Gauss-Newton
// step and pull back, so plain steps cover a small part of the way and the refinement stalls
// short of the minimum (a SICK over mostly flat ground: 2.5 mm per iteration in y from 0.13 m
// off). Doubling the step while the cost over all points falls (extrapolation_steps) gets there.
// The scene: a flat ground with a few low bumps, the SICK's ground-line rotation held as after
// the sweep, the start 0.15 m off in y and 0.1 m in x, Table 4.1-like noise.
TEST(CalibrationRefinement, ExtrapolatedStepsConvergeAlongAWeakDirection) {
  const auto bumps = [](double x, double y) {
    const auto bump = [](double dx, double dy, double s) {
      return 1.2 / (1.0 + std::exp((std::max(std::abs(dx), std::abs(dy)) - s) * 8.0));
    };
    return bump(x - 9, y - 3, 1.0) + bump(x - 11, y + 4, 1.2) + bump(x + 2, y - 10, 1.0) +
           bump(x - 4, y + 9, 0.8);
  };
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  cal::CalibrationInput in;
  in.reference_extrinsic = cal::toIsometry(kReference);
  const Eigen::Isometry3d t_sick = cal::toIsometry(kSick);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Isometry3d vehicle =
        cal::toIsometry(cal::makePose(3 * u(rng), 3 * u(rng), 0, 0, 0, 0.5 * u(rng)));
    in.reference.addScan(k, vehicle, sampleScan(bumps, vehicle * in.reference_extrinsic, 22.0,
                                                0.25, 0.2, &rng));
    for (int s = 0; s < 6; ++s) {  // a few scans per stop, the vehicle creeping forward
      const Eigen::Isometry3d creep = vehicle * cal::toIsometry(cal::makePose(0.5 * s, 0, 0, 0, 0, 0));
      in.target.addScan(k + 0.1 * s, creep, laserScan(bumps, creep * t_sick, 30.0, 0.1, &rng));
    }
  }
  cal::RefinementParams rp;
  rp.keep_edges = true;
  rp.noise_floor = 0.02;
  rp.max_correspondence_start = rp.max_correspondence_end;
  rp.max_iterations = 20;
  ASSERT_TRUE(cal::groundLineStepDirection(kSick, 0.0, &rp.frozen_direction));
  cal::PointVector reference;
  cal::accumulate(in.reference, in.reference_extrinsic, &reference);
  cal::SurfaceModel model;
  model.build(cal::voxelDownsample(reference, rp.reference_voxel), rp);
  const cal::ScanSet target = cal::refinementTarget(in.target, rp);
  const cal::Pose6 start = kSick + cal::makePose(0.1, 0.15, 0.0, 0.0, 0.0, 0.0);
  const cal::Pose6 plain = cal::poseDifference(cal::refine(model, target, start, rp).extrinsic, kSick);
  rp.extrapolation_steps = 5;
  const cal::RefinementResult r = cal::refine(model, target, start, rp);
  const cal::Pose6 fast = cal::poseDifference(r.extrinsic, kSick);
  // Where plain Gauss-Newton ends after ten times the iterations (a local minimum of the
  // nearest-neighbour cost ~6 cm off in y here, the reference being as noisy as the HDL-64E's
  // 0.2 m): the extrapolated refinement gets there in 20 iterations, the plain one is still
  // well short.
  cal::RefinementParams long_rp = rp;
  long_rp.extrapolation_steps = 0;
  long_rp.max_iterations = 200;
  const cal::Pose6 end = cal::refine(model, target, start, long_rp).extrinsic;
  const double fast_short = cal::poseDifference(r.extrinsic, end).head<2>().norm();
  const double plain_short = cal::poseDifference(kSick + plain, end).head<2>().norm();
  EXPECT_LT(fast_short, 0.015);
  EXPECT_GT(plain_short, 2.0 * fast_short);
  EXPECT_GT(plain_short, 0.02);
  EXPECT_LT(fast.head<2>().norm(), plain.head<2>().norm());
  // The extrapolated steps never raise the robust cost over all points above the start's.
  const double at_start = cal::robustCostOverAll(
      cal::linearise(model, target, start, rp.max_correspondence_end, rp), target.numPoints(),
      rp.max_correspondence_end, rp.huber);
  EXPECT_LT(cal::robustCostOverAll(r.at_solution, target.numPoints(), rp.max_correspondence_end,
                                   rp.huber),
            at_start);
}

TEST(CalibrationCalibrator, ASweepMemberTheFinalRefinementMovesFarRestartsTheSearch) {
  // calibration_benchmark --pair sick-velodyne --seed 3 --only 0: the coarse search settles in a
  // wrong basin, the ground-line sweep's member is 1.6 m off in x, and the final refinement
  // moves it by more than plane_sweep_consistency (but stays inside the search region). That is
  // the signal to search again; without restarts left, the result is no success.
  lp::sim::World world;
  std::string error;
  ASSERT_TRUE(lp::sim::makeStandardWorld("thesis", 3, &world, &error)) << error;
  cal::PairSetup pair;
  ASSERT_TRUE(cal::pairFromName("sick-velodyne", &pair, &error)) << error;
  cal::ExperimentTrial trial;
  ASSERT_TRUE(cal::makeTrial(world, pair, cal::ExperimentOptions(), 3 * 1000003ULL + 0, &trial,
                             &error))
      << error;
  cal::CalibrationParams params;
  params.initial = trial.initial_guess;
  params.search.seed = 3 * 7919ULL;
  params.coarse_restarts = 0;
  const cal::CalibrationResult once = cal::calibrate(trial.input, params);
  // The wrong basin is a matter of the search's floating-point path: a build whose compiler
  // orders the sums otherwise (clang, in scripts/test's sanitizer pass) finds the truth's basin
  // at once, and there is nothing to restart.
  if (once.success && cal::poseDifference(once.extrinsic, trial.truth).head<2>().norm() < 0.05) {
    GTEST_SKIP() << "this build's coarse search found the truth's basin without a restart";
  }
  EXPECT_FALSE(once.success) << once.message;  // named unobservable here (x, y, yaw)
  EXPECT_GT(cal::poseDifference(once.extrinsic, trial.truth).head<2>().norm(), 0.3);
  // With the default restarts, the moved member restarts the coarse search, which then finds
  // the truth's basin.
  params.coarse_restarts = cal::CalibrationParams().coarse_restarts;
  const cal::CalibrationResult r = cal::calibrate(trial.input, params);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_GE(r.restarts, 1);
  const cal::Pose6 err = cal::poseDifference(r.extrinsic, trial.truth);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.05) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.01) << cal::dofName(i);
}

namespace {

// The trial and settings of `calibration_benchmark --pair PAIR --world WORLD --seed 1 --only T`
// with `options` (trajectory, noise).
void benchmarkTrial(const std::string& world_name, const std::string& pair_name,
                    const cal::ExperimentOptions& options, int t, cal::ExperimentTrial* trial,
                    cal::CalibrationParams* params) {
  lp::sim::World world;
  std::string error;
  ASSERT_TRUE(lp::sim::makeStandardWorld(world_name, 1, &world, &error)) << error;
  cal::PairSetup pair;
  ASSERT_TRUE(cal::pairFromName(pair_name, &pair, &error)) << error;
  ASSERT_TRUE(cal::makeTrial(world, pair, options, 1000003ULL + t, trial, &error)) << error;
  params->spread = options.guess_offset;
  cal::adaptParamsToPair(pair, params);
  params->initial = trial->initial_guess;
  params->search.seed = 7919ULL + t;
}

}  // namespace

TEST(CalibrationCalibrator, TheGroundLineRotationIsPolishedOnTheWholeTarget) {
  // calibration_benchmark --pair sick-velodyne --trajectory turns --world urban --noise none
  // --only 0: the sweep places the SICK's rotation about its ground line from briefly refined
  // members on thinned targets, 0.005 rad off (5 cm in z); the final refinement holds it. The
  // whole target scores the truth lower, and the polish finds it.
  cal::ExperimentOptions options;
  options.trajectory = "turns";
  options.noise = lp::sim::NoiseProfile::kNone;
  cal::ExperimentTrial trial;
  cal::CalibrationParams params;
  benchmarkTrial("urban", "sick-velodyne", options, 0, &trial, &params);
  if (HasFatalFailure()) return;
  cal::CalibrationParams unpolished = params;
  unpolished.plane_sweep_polish_step = 0.0;
  const cal::CalibrationResult before = cal::calibrate(trial.input, unpolished);
  const cal::CalibrationResult r = cal::calibrate(trial.input, params);
  const cal::Pose6 e0 = cal::poseDifference(before.extrinsic, trial.truth);
  const cal::Pose6 e = cal::poseDifference(r.extrinsic, trial.truth);
  std::printf("z %+.4f -> %+.4f m, pitch %+.5f -> %+.5f rad\n", e0[cal::kZ], e[cal::kZ],
              e0[cal::kPitch], e[cal::kPitch]);
  // Measured: z +0.054 -> +0.008 m, pitch +0.0052 -> +0.0007 rad. The sweep's placement is a
  // matter of the search's floating-point path: a build whose compiler orders the sums otherwise
  // (clang, in scripts/test's sanitizer pass) placed it 1.2 cm off, and the polish took it to
  // 0.3 cm. Either way the polished estimate is within 2 cm and 0.002 rad, and no worse.
  EXPECT_TRUE(r.success) << r.message;
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(e[i]), 0.02) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(e[i]), 0.002) << cal::dofName(i);
  EXPECT_LE(std::abs(e[cal::kZ]), std::abs(e0[cal::kZ]) + 0.002);
}

TEST(CalibrationCalibrator, AFlatGroundLineProfileIsReportedUnobservable) {
  // calibration_benchmark --pair sick-sick --only 6 (the thesis's random poses): two SICKs see
  // too little of each other's scene to fix the rotation about the target's ground line. The
  // estimate sat 16 cm off in z and 0.02 rad in pitch, and the curvature at it called every DOF
  // observable: a reported success. The polish's profile along the family is flat (it rises by
  // less than plane_sweep_flat_rise), so the DOFs the rotation moves are named unobservable.
  cal::ExperimentTrial trial;
  cal::CalibrationParams params;
  benchmarkTrial("thesis", "sick-sick", cal::ExperimentOptions(), 6, &trial, &params);
  if (HasFatalFailure()) return;
  const cal::CalibrationResult r = cal::calibrate(trial.input, params);
  const cal::Pose6 e = cal::poseDifference(r.extrinsic, trial.truth);
  // Where the search ends is a matter of its floating-point path: a build whose compiler orders
  // the sums otherwise (clang, in scripts/test's sanitizer pass) ends within 1 cm of the truth,
  // with a profile that is not flat, and its success is true.
  if (r.success && e.head<3>().cwiseAbs().maxCoeff() < 0.05 && e.tail<3>().cwiseAbs().maxCoeff() < 0.01) {
    GTEST_SKIP() << "this build's search found the truth; no flat profile to name: " << r.message;
  }
  EXPECT_FALSE(r.success) << r.message;
  EXPECT_NE(std::find(r.unobservable.begin(), r.unobservable.end(), "pitch"), r.unobservable.end())
      << r.message;
  EXPECT_FALSE(std::isfinite(r.stddev[cal::kPitch]));
  std::printf("error z %+.3f m, pitch %+.4f rad: %s\n", e[cal::kZ], e[cal::kPitch], r.message.c_str());
}

TEST(CalibrationCalibrator, SwappedRolesCancelTheSurfaceModelBias) {
  // Two Velodynes at Table 4.1 noise (0.2 m): a surface model fitted to one sensor's noisy returns
  // sits a few millimetres off the true surfaces, so the refinement of the other against it ends
  // ~4 mm off in z on every trial of the thesis experiment. Refined the other way round as well
  // and averaged, the two models' offsets cancel.
  lp::sim::World world;
  std::string error;
  ASSERT_TRUE(lp::sim::makeStandardWorld("thesis", 1, &world, &error)) << error;
  cal::PairSetup pair;
  ASSERT_TRUE(cal::pairFromName("velodyne-velodyne", &pair, &error)) << error;
  cal::ExperimentOptions options;
  options.poses = 5;
  cal::ExperimentTrial trial;
  ASSERT_TRUE(cal::makeTrial(world, pair, options, 1000003ULL, &trial, &error)) << error;
  cal::CalibrationParams params;
  params.method = "refine";
  params.initial = trial.truth + cal::makePose(0.05, -0.05, 0.05, 0.01, -0.01, 0.01);
  params.symmetric_refinement = false;
  const cal::CalibrationResult one_way = cal::calibrate(trial.input, params);
  params.symmetric_refinement = true;
  const cal::CalibrationResult both_ways = cal::calibrate(trial.input, params);
  ASSERT_TRUE(one_way.success) << one_way.message;
  ASSERT_TRUE(both_ways.success) << both_ways.message;
  const cal::Pose6 e1 = cal::poseDifference(one_way.extrinsic, trial.truth);
  const cal::Pose6 e2 = cal::poseDifference(both_ways.extrinsic, trial.truth);
  std::printf("z error one way %.4f m, both ways %.4f m\n", e1[cal::kZ], e2[cal::kZ]);
  EXPECT_GT(std::abs(e1[cal::kZ]), 0.0025);
  EXPECT_LT(std::abs(e2[cal::kZ]), 0.5 * std::abs(e1[cal::kZ]));
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(e2[i]), 0.01) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(e2[i]), 0.001) << cal::dofName(i);
}

TEST(CalibrationExperiment, TurnsTrajectoryWeavesAlongTheDriveAndTheStereoFramesOnTheWay) {
  lp::sim::World world;
  std::string error;
  ASSERT_TRUE(lp::sim::makeStandardWorld("urban", 1, &world, &error)) << error;
  cal::PairSetup pair;
  ASSERT_TRUE(cal::pairFromName("stereo-velodyne", &pair, &error)) << error;
  cal::ExperimentOptions options;
  options.trajectory = "turns";
  cal::ExperimentTrial trial;
  ASSERT_TRUE(cal::makeTrial(world, pair, options, 7, &trial, &error)) << error;
  ASSERT_EQ(trial.vehicle_poses.size(), 10u);
  const Eigen::Vector3d start = world.drivePose(0.0).translation();
  const Eigen::Vector3d end = world.drivePose(world.driveDuration()).translation();
  EXPECT_LT((trial.vehicle_poses.front().translation() - start).head<2>().norm(), 1e-6);
  const Eigen::Vector2d along = (end - start).head<2>().normalized();
  double max_offset = 0, max_yaw = 0;
  for (const auto& pose : trial.vehicle_poses) {
    const Eigen::Vector2d d = (pose.translation() - start).head<2>();
    max_offset = std::max(max_offset, std::abs(d.x() * along.y() - d.y() * along.x()));
    const double yaw = std::atan2(pose.linear()(1, 0), pose.linear()(0, 0)) -
                       std::atan2(along.y(), along.x());
    max_yaw = std::max(max_yaw, std::abs(cal::wrapAngle(yaw)));
  }
  EXPECT_GT(max_offset, 1.0);  // it weaves ...
  EXPECT_LE(max_offset, options.turn_amplitude + 1e-6);
  EXPECT_GT(max_yaw, 0.2);  // ... and turns
  EXPECT_LT(max_yaw, std::atan(options.turn_amplitude * 2 * M_PI / options.turn_wavelength) + 1e-6);
  // The Velodyne scans at the poses, the stereo camera at its own 10 Hz along the drive.
  EXPECT_EQ(trial.input.reference.numScans(), 10u);
  EXPECT_GT(trial.input.target.numScans(), 100u);
  options.trajectory = "spiral";
  EXPECT_FALSE(cal::makeTrial(world, pair, options, 7, &trial, &error));
  EXPECT_NE(error.find("unknown trajectory"), std::string::npos) << error;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
