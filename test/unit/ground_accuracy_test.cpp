// Accuracy of the vertical scan ground extraction on the simulator's worlds with ground truth
// (realistic HDL-64E noise, the "datasheet" profile, 0.02 m), 3 revolutions along each world's
// standard drive. The targets are ground precision and recall >= 99 % and obstacle
// recall >= 97 % per world. Where the model reaches a target the test asserts the target;
// where it does not yet (urban: curb faces and the low parts of walls and cars seen at grazing
// incidence; potholes: shallow bowl edges; obstacle recall on the hillside's poles and car),
// it asserts the level measured when the test was written, so a regression fails, and the gap
// is reported in the ground_eval table rather than hidden.
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/vertical_scan.h"

using namespace ladar_perception;

namespace {

struct Expectation {
  const char* world;
  double ground_precision, ground_recall, obstacle_recall;
};

GroundAccuracy evaluate(const std::string& world, const VerticalScanParams& params) {
  VerticalScanGround model(params);
  GroundAccuracy acc;
  std::string error;
  EXPECT_TRUE(evaluateGroundModel(world, &model, sim::NoiseProfile::kDatasheet, 3, 1, &acc, &error))
      << error;
  return acc;
}

class GroundAccuracyTest : public ::testing::TestWithParam<Expectation> {};

TEST_P(GroundAccuracyTest, DefaultModelPerWorld) {
  const Expectation e = GetParam();
  const GroundAccuracy acc = evaluate(e.world, verticalScanDefaultParams());
  ASSERT_GT(acc.points, 100000u);
  EXPECT_GE(acc.groundPrecision(), e.ground_precision) << e.world;
  EXPECT_GE(acc.groundRecall(), e.ground_recall) << e.world;
  EXPECT_GE(acc.obstacleRecall(), e.obstacle_recall) << e.world;
}

INSTANTIATE_TEST_SUITE_P(
    Worlds, GroundAccuracyTest,
    ::testing::Values(
        // Targets met (on these 3 scans: hillside 99.98 / 99.69 / 98.75 %, urban 99.25 / 99.14 /
        // 98.93 %, rural 99.92 / 99.29 / 99.38 %; without laser_neighbours, the default before
        // laser_neighbours, hillside obstacle recall 97.0 % and urban 97.9 / 98.98 / 96.92 %).
        Expectation{"flat", 0.99, 0.99, 0.97},
        Expectation{"hillside", 0.99, 0.99, 0.97},
        Expectation{"urban", 0.99, 0.99, 0.97},
        Expectation{"rural", 0.99, 0.99, 0.97},
        // Ground targets met; pothole recall measured 60.1 % on these 3 scans (68.0 % without
        // the local ground stage, which takes back the shallow returns level with the road
        // around them; 57.9 % without laser_neighbours). A fifth of the pothole returns lie
        // within 3 cm of the road plane. Per hole, the way a driver counts them, the stage
        // finds one hole fewer of 305 (doc/benchmarks.md, Negative obstacles).
        Expectation{"potholes", 0.99, 0.99, 0.58}),
    [](const ::testing::TestParamInfo<Expectation>& info) { return std::string(info.param.world); });

TEST(GroundAccuracy, DefaultBeatsThesisOnObstaclesAndKeepsTheGround) {
  // Beyond the thesis: the bent, coupled line and the vertical-surface term find far more of
  // the urban obstacles at a small cost in ground recall, and the thesis settings find no
  // pothole at all.
  const GroundAccuracy thesis = evaluate("urban", verticalScanThesisParams());
  const GroundAccuracy fresh = evaluate("urban", verticalScanDefaultParams());
  EXPECT_GT(fresh.obstacleRecall(), thesis.obstacleRecall() + 0.2);
  EXPECT_GT(fresh.groundPrecision(), thesis.groundPrecision());
  const GroundAccuracy thesis_holes = evaluate("potholes", verticalScanThesisParams());
  const GroundAccuracy fresh_holes = evaluate("potholes", verticalScanDefaultParams());
  EXPECT_GT(fresh_holes.obstacleRecall(), thesis_holes.obstacleRecall() + 0.3);
}

TEST(GroundAccuracy, NegativeObstaclesOnlyBelowASupportedLine) {
  // Rural: behind a car or a person at the top of an embankment, the ground falling into the
  // ditch is seen only in bins the obstacle fills, below a line extrapolated over it. Calling
  // returns below the line obstacles only within negative_support_distance of the column's own
  // ground returns keeps that ground; the potholes, all near returns of the road, are found as
  // before.
  VerticalScanParams ungated = verticalScanDefaultParams();
  ungated.negative_support_distance = 0.f;
  const GroundAccuracy on = evaluate("rural", verticalScanDefaultParams());
  const GroundAccuracy off = evaluate("rural", ungated);
  // 99.31 % on these 3 scans, 99.07 % ungated (99.42 / 99.16 % on ground_eval's 10), before
  // the local ground stage; with it 99.62 / 99.37 %, and 99.66 / 99.47 % since the line no
  // longer climbs over returns it refused (chordClimbsOverReturns): a floor against
  // regressions. The gap was wider while the line's tail went on climbing behind the obstacle
  // (98.98 %); it no longer rises faster than the column's straight estimate. The gate's cost
  // in obstacle recall: 99.66 against 99.91 % ungated with the local ground stage.
  EXPECT_GE(on.groundRecall(), 0.985);
  EXPECT_GT(on.groundRecall(), off.groundRecall() + 0.0015);
  EXPECT_GT(on.obstacleRecall(), off.obstacleRecall() - 0.005);
  const GroundAccuracy holes_on = evaluate("potholes", verticalScanDefaultParams());
  const GroundAccuracy holes_off = evaluate("potholes", ungated);
  EXPECT_NEAR(holes_on.obstacleRecall(), holes_off.obstacleRecall(), 0.002);
  std::printf("rural ground recall %.4f (ungated %.4f), obstacle recall %.4f (%.4f); potholes %.4f (%.4f)\n",
              on.groundRecall(), off.groundRecall(), on.obstacleRecall(), off.obstacleRecall(),
              holes_on.obstacleRecall(), holes_off.obstacleRecall());
}

TEST(GroundAccuracy, ObstacleReturnsAtTheGroundAreMarked) {
  // Road at height 0 with a 1 m box (class car) over x in [5, 6]: returns on its face within
  // 2 cm of the road next to it are at the ground; higher ones, the box's top and the road's
  // own returns are not.
  sim::World world;
  std::string error;
  ASSERT_TRUE(world.reset(0.0, -5.0, 0.1, 100, 100, 0.f, sim::SurfaceClass::kRoad, &error)) << error;
  for (int ix = 50; ix < 60; ++ix) {
    for (int iy = 0; iy < 100; ++iy) world.setCell(ix, iy, 1.f, sim::SurfaceClass::kCar);
  }
  world.finalize();
  const std::vector<Eigen::Vector3f> points = {
      {5.01f, 0.f, 0.01f}, {5.01f, 0.f, 0.1f}, {5.01f, 0.f, 0.5f}, {5.5f, 0.f, 1.f}, {3.f, 0.f, 0.f}};
  const std::vector<uint8_t> truth = {4, 4, 4, 4, 0};
  CloudLayout l = xyziLayout(static_cast<uint32_t>(points.size()));
  PackedCloud cloud;
  cloud.layout = l;
  cloud.data.assign(static_cast<std::size_t>(l.row_step) * l.height, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::memcpy(cloud.data.data() + i * l.point_step, points[i].data(), 12);
  }
  PointCloudView view;
  ASSERT_TRUE(cloud.view(&view, &error)) << error;
  std::vector<uint8_t> at_ground;
  markObstacleReturnsAtTheGround(world, Eigen::Isometry3d::Identity(), view, truth, 0.02, &at_ground);
  EXPECT_EQ(at_ground, (std::vector<uint8_t>{1, 0, 0, 0, 0}));
}

TEST(GroundAccuracy, MissesAreBrokenDownByHeightAndRange) {
  // Road at height 0 with a hole 0.1 m deep over x in [5, 6] (ground_eval --misses): a missed
  // return 1 cm down the hole's wall is "below 2 cm", one 5 cm down "4-6 cm"; one in the middle
  // of a 1 m hole 20 m out has no ground within 0.3 m; found returns are counted, not placed.
  sim::World world;
  std::string error;
  ASSERT_TRUE(world.reset(0.0, -5.0, 0.1, 300, 100, 0.f, sim::SurfaceClass::kRoad, &error)) << error;
  for (int ix = 50; ix < 60; ++ix) {
    for (int iy = 0; iy < 100; ++iy) world.setCell(ix, iy, -0.1f, sim::SurfaceClass::kPothole);
  }
  for (int ix = 195; ix < 205; ++ix) {
    for (int iy = 0; iy < 100; ++iy) world.setCell(ix, iy, -0.1f, sim::SurfaceClass::kPothole);
  }
  world.finalize();
  MissBreakdown b;
  const Eigen::Vector2d sensor(0.0, 0.0);
  b.add(world, Eigen::Vector3d(5.95, 0.0, -0.01), sensor, true);
  b.add(world, Eigen::Vector3d(5.95, 0.0, -0.05), sensor, true);
  b.add(world, Eigen::Vector3d(5.5, 0.0, -0.1), sensor, false);
  b.add(world, Eigen::Vector3d(20.0, 0.0, -0.1), sensor, true);
  EXPECT_EQ(b.missed_by_height, (std::array<std::size_t, 5>{1, 0, 1, 0, 1}));
  EXPECT_EQ(b.near_obstacles, 3u);
  EXPECT_EQ(b.near_missed, 2u);
  EXPECT_EQ(b.far_obstacles, 1u);
  EXPECT_EQ(b.far_missed, 1u);
}

TEST(GroundAccuracy, HeightAloneSeparatesThePotholesOnlyWithoutNoise) {
  // The limit of a per-return height test against the exact ground (ground_eval
  // --height-bound): without noise every pothole return is below the road next to it; at the
  // HDL-64E's 2 cm range noise the shallow rim and the top of the far wall are not (2 scans:
  // 81.6 % separable), and at Table 4.1's 0.2 m far fewer.
  std::string error;
  HeightTestBound none, datasheet, table41;
  ASSERT_TRUE(heightTestBound("potholes", sim::NoiseProfile::kNone, 2, 1, 0.99, &none, &error)) << error;
  ASSERT_TRUE(heightTestBound("potholes", sim::NoiseProfile::kDatasheet, 2, 1, 0.99, &datasheet, &error)) << error;
  ASSERT_TRUE(heightTestBound("potholes", sim::NoiseProfile::kTable41, 2, 1, 0.99, &table41, &error)) << error;
  const int pothole = static_cast<int>(sim::SurfaceClass::kPothole);
  ASSERT_GT(none.obstacle_returns, 100u);
  EXPECT_EQ(none.class_returns[pothole], none.obstacle_returns);
  EXPECT_GE(none.recall(), 0.995);
  EXPECT_GT(datasheet.recall(), 0.7);
  EXPECT_LT(datasheet.recall(), 0.9);
  EXPECT_LT(table41.recall(), datasheet.recall() - 0.3);
  EXPECT_FALSE(heightTestBound("no_such_world", sim::NoiseProfile::kNone, 1, 1, 0.99, &none, &error));
}

TEST(GroundAccuracy, ARegionModelOnTheExactGroundFindsThePotholes) {
  // The limit of a region model of holes on the exact ground (ground_eval --region-bound):
  // linking the deep returns into holes and filling each hole's convex hull finds the shallow
  // rim and wall returns that no per-return height test can (2 scans: 98.5 % without noise,
  // 93.3 % at the HDL-64E's 2 cm, 9 % at Table 4.1's 0.2 m), at little cost to the ground.
  std::string error;
  const RegionModelParams params;
  RegionModelBound none, datasheet, table41, flat;
  ASSERT_TRUE(regionModelBound("potholes", sim::NoiseProfile::kNone, 2, 1, params, &none, &error)) << error;
  ASSERT_TRUE(regionModelBound("potholes", sim::NoiseProfile::kDatasheet, 2, 1, params, &datasheet, &error)) << error;
  ASSERT_TRUE(regionModelBound("potholes", sim::NoiseProfile::kTable41, 2, 1, params, &table41, &error)) << error;
  ASSERT_TRUE(regionModelBound("flat", sim::NoiseProfile::kDatasheet, 2, 1, params, &flat, &error)) << error;
  const int pothole = static_cast<int>(sim::SurfaceClass::kPothole);
  ASSERT_GT(none.class_returns[pothole], 100u);
  auto recall = [pothole](const RegionModelBound& b) {
    return GroundAccuracy::ratio(b.class_found[pothole], b.class_returns[pothole]);
  };
  EXPECT_GT(recall(none), 0.97);
  EXPECT_GT(recall(datasheet), 0.9);
  HeightTestBound height;
  ASSERT_TRUE(heightTestBound("potholes", sim::NoiseProfile::kDatasheet, 2, 1, 0.99, &height, &error)) << error;
  EXPECT_GT(recall(datasheet), height.recall() + 0.05);  // beyond height alone
  EXPECT_LT(recall(table41), 0.5);
  EXPECT_GT(datasheet.groundRecall(), 0.99);
  EXPECT_GT(flat.groundRecall(), 0.99);
  EXPECT_EQ(flat.obstacle_returns, 0u);
  // Seeds deeper than 99.99 % of the ground leave urban its ground (2 scans: 99.97 %, 7 holes);
  // at 99.9 % the faces of the world's cells along the curbs seed holes (97.9 %, 15 holes).
  RegionModelBound urban, urban_loose;
  RegionModelParams loose = params;
  loose.seed_ground_kept = 0.999;
  ASSERT_TRUE(regionModelBound("urban", sim::NoiseProfile::kDatasheet, 2, 1, params, &urban, &error)) << error;
  ASSERT_TRUE(regionModelBound("urban", sim::NoiseProfile::kDatasheet, 2, 1, loose, &urban_loose, &error)) << error;
  EXPECT_GT(urban.groundRecall(), 0.995);
  EXPECT_LT(urban_loose.groundRecall(), 0.99);
  EXPECT_FALSE(regionModelBound("no_such_world", sim::NoiseProfile::kNone, 1, 1, params, &none, &error));
}

TEST(GroundAccuracy, ConvexHullOfAHolesSeeds) {
  using region_bound_detail::convexHull;
  using region_bound_detail::insideConvex;
  // A square's corners with points inside and on an edge: the hull is the four corners.
  const std::vector<Eigen::Vector2d> hull = convexHull(
      {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}, {0.5, 0}, {0.2, 0.7}});
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_TRUE(insideConvex(hull, {0.5, 0.5}));
  EXPECT_TRUE(insideConvex(hull, {0.99, 0.01}));
  EXPECT_FALSE(insideConvex(hull, {1.01, 0.5}));
  EXPECT_FALSE(insideConvex(hull, {-0.5, -0.5}));
  // Fewer than three points (or all on a line) enclose nothing.
  EXPECT_FALSE(insideConvex(convexHull({{0, 0}, {1, 1}}), {0.5, 0.5}));
  EXPECT_FALSE(insideConvex(convexHull({{0, 0}, {1, 1}, {2, 2}}), {1, 1}));
}

TEST(GroundAccuracy, TargetsOnTheReturnsAwayFromTheGround) {
  // Scoring only the obstacle returns more than 2 cm from the ground next to them (the
  // --at-ground-band 0.02 of ground_eval): the obstacle recall target is met on urban and the
  // hillside; measured on these 3 scans 98.5 / 99.0 / 97.8 % (urban), 99.96 / 99.7 / 97.4 %
  // (hillside), 61.7 % of the potholes.
  VerticalScanGround model(verticalScanDefaultParams());
  for (const char* w : {"urban", "hillside"}) {
    GroundAccuracy acc;
    std::string error;
    ASSERT_TRUE(evaluateGroundModel(w, &model, sim::NoiseProfile::kDatasheet, 3, 1, &acc, &error, 0.02))
        << error;
    EXPECT_GT(acc.not_scored, 0u) << w;
    EXPECT_GE(acc.obstacleRecall(), 0.97) << w;
    EXPECT_GE(acc.groundPrecision(), 0.98) << w;
    EXPECT_GE(acc.groundRecall(), 0.99) << w;
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

TEST(GroundAccuracy, LaserNeighboursBeatTheBinsAlone) {
  // laser_neighbours (on by default; off in the "bins" settings): the returns of the rows
  // above and below at the same azimuth put the feet and tops of curb faces, car sides and
  // walls, and the rims of holes, on the obstacle side; negative obstacles are measured from
  // the foot of a step. On these 3 scans, urban: 99.35 / 99.22 / 99.07 % with them, 98.00 /
  // 99.29 / 97.10 % without; potholes 68.0 % against 57.9 % (before the column's face test).
  // The default without its local ground stage (which needs them), against the bins alone.
  VerticalScanParams neighbours = verticalScanDefaultParams();
  neighbours.local_ground = false;
  const GroundAccuracy with = evaluate("urban", neighbours);
  const GroundAccuracy without = evaluate("urban", verticalScanBinsParams());
  EXPECT_GT(with.groundPrecision(), without.groundPrecision() + 0.01);
  EXPECT_GT(with.obstacleRecall(), without.obstacleRecall() + 0.015);
  // The column's face test (track_face_dr) gives the bins alone more ground recall than the
  // neighbours' faces keep: 99.22 % with them, 99.29 % without (99.15 / 98.99 % before it).
  EXPECT_GE(with.groundRecall(), without.groundRecall() - 0.002);
  const GroundAccuracy holes = evaluate("potholes", neighbours);
  const GroundAccuracy holes_without = evaluate("potholes", verticalScanBinsParams());
  EXPECT_GT(holes.obstacleRecall(), holes_without.obstacleRecall() + 0.08);
}

TEST(GroundAccuracy, LaserNeighboursDoNotDependOnTheInputOrder) {
  // The neighbours come from a range image by row and sub-column, not from the order of the
  // returns: a scan in the simulator's firing order and the same returns shuffled get the same
  // label per return.
  sim::World world;
  std::string error;
  ASSERT_TRUE(sim::makeStandardWorld("urban", 1, &world, &error)) << error;
  sim::SimulatedScan scan;
  sim::simulateVelodyneRevolution(world, world.drivePose(0.4 * world.driveDuration()) * evaluationSensorMount(),
                                  sim::VelodyneModel::hdl64e(sim::NoiseProfile::kDatasheet), 11, &scan);
  const std::size_t n = scan.cloud.size();
  ASSERT_GT(n, 50000u);
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  uint32_t state = 2024u;
  for (std::size_t i = n - 1; i > 0; --i) {  // Fisher-Yates with a fixed LCG
    state = state * 1664525u + 1013904223u;
    std::swap(order[i], order[state % (i + 1)]);
  }
  PackedCloud shuffled = scan.cloud;
  const std::size_t step = scan.cloud.layout.point_step;
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(&shuffled.data[i * step], &scan.cloud.data[order[i] * step], step);
  }
  PointCloudView a, b;
  ASSERT_TRUE(scan.cloud.view(&a, &error)) << error;
  ASSERT_TRUE(shuffled.view(&b, &error)) << error;
  SensorPose pose;
  pose.sensor_to_ground = evaluationSensorMount().cast<float>();
  VerticalScanGround model(verticalScanDefaultParams());
  GroundClassification in_order, in_shuffle;
  model.classify(a, pose, &in_order);
  model.classify(b, pose, &in_shuffle);
  std::size_t differ = 0, flipped = 0;
  VerticalScanGround plain(verticalScanBinsParams());
  GroundClassification without;
  plain.classify(a, pose, &without);
  for (std::size_t i = 0; i < n; ++i) {
    differ += in_shuffle.labels[i] != in_order.labels[order[i]];
    flipped += in_order.labels[i] != without.labels[i];
  }
  std::printf("%zu returns, %zu relabelled by the neighbours, %zu differ when shuffled\n", n, flipped, differ);
  EXPECT_GT(flipped, 200u);  // the neighbours changed something in this scan
  // Of returns that share a range-image cell the last one in input order is the neighbour, so
  // a few labels could differ in principle; none do in this scan.
  EXPECT_LE(differ, n / 1000) << differ << " of " << n;
}

TEST(GroundAccuracy, LaserNeighboursTestEveryReturnTheyCanRelabel) {
  // With the default terms the face rules run only on ground returns in a cell next to an
  // obstacle or above a deep return. A SlopeErrorMax growth of the smallest denormal per metre
  // adds nothing to SlopeErrorMax (0.004 + 1e-43 rounds to 0.004) but takes the labelling's
  // general loop, after which every ground return is tested: the labels and P(obstacle) must
  // be the same. Urban (faces) and potholes (far walls); the same model object over both
  // worlds and both parameter sets, so the cell stamps carry over between scans.
  SensorPose pose;
  pose.sensor_to_ground = evaluationSensorMount().cast<float>();
  // The local ground stage is off in both: it looks for the feet of faces in the cells this
  // pass marks, and in every cell when it marked none (as after the general loop), by design.
  VerticalScanParams base = verticalScanDefaultParams();
  base.local_ground = false;
  VerticalScanParams every = base;
  every.tolerances.slope_error_max_per_m = std::numeric_limits<float>::denorm_min();
  VerticalScanGround marked(base), all(every);
  for (const char* name : {"urban", "potholes"}) {
    sim::World world;
    std::string error;
    ASSERT_TRUE(sim::makeStandardWorld(name, 1, &world, &error)) << error;
    for (int k = 0; k < 2; ++k) {
      sim::SimulatedScan scan;
      sim::simulateVelodyneRevolution(world,
                                      world.drivePose((0.3 + 0.4 * k) * world.driveDuration()) * evaluationSensorMount(),
                                      sim::VelodyneModel::hdl64e(sim::NoiseProfile::kDatasheet), 20 + k, &scan);
      PointCloudView view;
      ASSERT_TRUE(scan.cloud.view(&view, &error)) << error;
      GroundClassification a, b;
      marked.classify(view, pose, &a);
      all.classify(view, pose, &b);
      ASSERT_EQ(a.labels.size(), b.labels.size());
      std::size_t differ = 0, obstacles = 0;
      for (std::size_t i = 0; i < a.labels.size(); ++i) {
        differ += a.labels[i] != b.labels[i] || a.p_obstacle[i] != b.p_obstacle[i];
        obstacles += a.labels[i] == kLabelObstacle;
      }
      EXPECT_EQ(differ, 0u) << name << " scan " << k;
      EXPECT_GT(obstacles, 100u) << name;
    }
  }
}

TEST(GroundAccuracy, AThresholdOfOneLeavesNoObstacle) {
  // P(obstacle) lies in [0, 1]: at obstacle_threshold 1 nothing is an obstacle, also not the
  // faces and hole rims the laser neighbours relabel (they take their neighbour's P, raised
  // just above the threshold).
  sim::World world;
  std::string error;
  ASSERT_TRUE(sim::makeStandardWorld("urban", 1, &world, &error)) << error;
  sim::SimulatedScan scan;
  sim::simulateVelodyneRevolution(world, world.drivePose(0.5 * world.driveDuration()) * evaluationSensorMount(),
                                  sim::VelodyneModel::hdl64e(sim::NoiseProfile::kDatasheet), 5, &scan);
  PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view, &error)) << error;
  SensorPose pose;
  pose.sensor_to_ground = evaluationSensorMount().cast<float>();
  VerticalScanParams p = verticalScanDefaultParams();
  p.tolerances.obstacle_threshold = 1.f;
  VerticalScanGround model(p);
  GroundClassification out;
  model.classify(view, pose, &out);
  EXPECT_EQ(out.count(kLabelObstacle), 0u);
  for (std::size_t i = 0; i < out.size(); ++i) ASSERT_LE(out.p_obstacle[i], 1.f) << i;
}
