// The network calibration's joint solve (network.h solveNetwork) on hand-made edges with known
// answers, and its YAML and launch output. calibrateNetwork() end to end runs in the rostest
// (test/ros/network_calibration.test) and in calibration_benchmark --network.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "ladar_perception/calibration/network.h"

namespace cal = ladar_perception::calibration;

namespace {

const double kInf = std::numeric_limits<double>::infinity();

// An edge measuring `to` at `estimate`, with `from` placed at from_estimate (-1: the reference).
cal::NetworkEdge edge(int from, int to, const cal::Pose6& from_estimate, const cal::Pose6& estimate,
                      double sd_t, double sd_r) {
  cal::NetworkEdge e;
  e.from = from;
  e.to = to;
  e.from_estimate = from_estimate;
  e.result.extrinsic = estimate;
  e.result.success = true;
  e.result.stddev << sd_t, sd_t, sd_t, sd_r, sd_r, sd_r;
  e.used = true;
  return e;
}

// The thesis vehicle's targets: an LMS-291 ahead, one behind (yaw pi), a stereo camera.
std::vector<cal::Pose6> truth() {
  return {cal::makePose(2.0, 0.0, 1.0, 0.0, 0.0997, 0.0),
          cal::makePose(-2.0, 0.0, 1.0, 0.0, 0.0997, M_PI),
          cal::makePose(1.7, 0.0, 1.5, 0.0, 0.2, 0.0)};
}

// `to`'s estimate through a cross edge when `from` was placed at `placed` instead of its truth:
// the edge measures the relative mount, so `to` moves rigidly with `from`.
cal::Pose6 through(const cal::Pose6& from_truth, const cal::Pose6& placed, const cal::Pose6& to_truth) {
  return cal::fromIsometry(cal::toIsometry(placed) * cal::toIsometry(from_truth).inverse() *
                           cal::toIsometry(to_truth));
}

double maxAbs(const cal::Pose6& d) { return d.cwiseAbs().maxCoeff(); }

}  // namespace

TEST(CalibrationNetwork, ConsistentEdgesGiveTheTruthAndClosedLoops) {
  const std::vector<cal::Pose6> t = truth();
  std::vector<cal::NetworkEdge> edges;
  for (int k = 0; k < 3; ++k) edges.push_back(edge(-1, k, cal::Pose6::Zero(), t[k], 0.01, 0.002));
  // Cross edges measured with `from` placed 3 cm and 0.005 rad off: `to` comes out moved with it,
  // and the joint solve must read only the relative mount from them.
  const cal::Pose6 off = cal::makePose(0.03, -0.02, 0.01, 0.005, 0.0, -0.005);
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      const cal::Pose6 placed = t[i] + off;
      edges.push_back(edge(i, j, placed, through(t[i], placed, t[j]), 0.01, 0.002));
    }
  }
  cal::NetworkParams params;
  std::vector<cal::NetworkSensorResult> sensors;
  double cost = -1;
  cal::solveNetwork(3, params, &edges, &sensors, &cost);
  ASSERT_EQ(sensors.size(), 3u);
  EXPECT_NEAR(cost, 0.0, 1e-9);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(sensors[k].success) << k;
    EXPECT_LT(maxAbs(cal::poseDifference(sensors[k].joint, t[k])), 1e-7) << k;
    // Six edges of 6 DOFs at 1 cm: each sensor is fixed better than by its pairwise edge alone.
    for (int d = 0; d < 3; ++d) EXPECT_LT(sensors[k].stddev[d], 0.0112) << k << " " << d;
  }
  for (const cal::NetworkEdge& e : edges) {
    EXPECT_LT(e.residual_translation, 1e-7);
    EXPECT_LT(e.residual_rotation, 1e-7);
  }
}

TEST(CalibrationNetwork, ACrossEdgeFixesWhatTheReferenceCannot) {
  const std::vector<cal::Pose6> t = truth();
  std::vector<cal::NetworkEdge> edges;
  edges.push_back(edge(-1, 0, cal::Pose6::Zero(), t[0], 0.005, 0.001));
  // The rear ladar against the reference: pitch unobservable, its value wrong.
  cal::Pose6 rear = t[1];
  rear[cal::kPitch] += 0.2;
  cal::NetworkEdge partial = edge(-1, 1, cal::Pose6::Zero(), rear, 0.005, 0.001);
  partial.result.success = false;
  partial.result.partial = true;
  partial.result.stddev[cal::kPitch] = kInf;
  partial.result.unobservable = {"pitch"};
  edges.push_back(partial);
  // ... and against the front ladar, where every DOF is fixed.
  edges.push_back(edge(0, 1, t[0], t[1], 0.01, 0.002));
  cal::NetworkParams params;
  std::vector<cal::NetworkSensorResult> sensors;
  cal::solveNetwork(2, params, &edges, &sensors, nullptr);
  ASSERT_EQ(sensors.size(), 2u);
  EXPECT_TRUE(sensors[1].success);
  EXPECT_TRUE(sensors[1].unobservable.empty());
  EXPECT_NEAR(sensors[1].joint[cal::kPitch], t[1][cal::kPitch], 1e-6);
  EXPECT_LT(maxAbs(cal::poseDifference(sensors[1].joint, t[1])), 1e-6);

  // Without the cross edge the pitch stays unobservable and is said so.
  edges.pop_back();
  cal::solveNetwork(2, params, &edges, &sensors, nullptr);
  EXPECT_FALSE(sensors[1].success);
  ASSERT_EQ(sensors[1].unobservable.size(), 1u);
  EXPECT_EQ(sensors[1].unobservable[0], "pitch");
  EXPECT_TRUE(std::isinf(sensors[1].stddev[cal::kPitch]));
  EXPECT_TRUE(sensors[0].success);
}

TEST(CalibrationNetwork, AnInconsistentCrossEdgeShowsInItsResidualNotInTheSensors) {
  const std::vector<cal::Pose6> t = truth();
  std::vector<cal::NetworkEdge> edges;
  for (int k = 0; k < 3; ++k) edges.push_back(edge(-1, k, cal::Pose6::Zero(), t[k], 0.005, 0.001));
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) edges.push_back(edge(i, j, t[i], t[j], 0.005, 0.001));
  }
  // The rear ladar against the front one: 12 cm off in x while claiming 5 mm.
  edges[3].result.extrinsic[cal::kX] += 0.12;
  cal::NetworkParams params;
  std::vector<cal::NetworkSensorResult> sensors;
  cal::solveNetwork(3, params, &edges, &sensors, nullptr);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(cal::poseDifference(sensors[k].joint, t[k]).head<3>().cwiseAbs().maxCoeff(), 0.03) << k;
  }
  EXPECT_GT(edges[3].residual_translation, 0.09);
  EXPECT_LT(edges[4].residual_translation, 0.03);

  // Plain least squares at the reported deviations spreads the error over the sensors.
  params.variance_components = false;
  params.robust_threshold = 0;
  cal::solveNetwork(3, params, &edges, &sensors, nullptr);
  EXPECT_GT(std::abs(sensors[1].joint[cal::kX] - t[1][cal::kX]), 0.03);
}

TEST(CalibrationNetwork, OneYamlAndALaunchFileForEverySensor) {
  cal::NetworkResult r;
  r.success = false;
  r.message = "2 of 3 sensors calibrated";
  const std::vector<cal::Pose6> t = truth();
  const char* names[] = {"sick_front", "sick/rear", "stereo"};
  for (int k = 0; k < 3; ++k) {
    cal::NetworkSensorResult s;
    s.name = names[k];
    s.joint = t[k];
    s.pairwise = t[k];
    s.success = k != 2;
    s.stddev << 0.01, 0.01, 0.01, 0.001, 0.001, k == 2 ? kInf : 0.001;
    r.sensors.push_back(s);
  }
  r.edges.push_back(edge(-1, 0, cal::Pose6::Zero(), t[0], 0.01, 0.001));
  r.edges.push_back(edge(0, 1, t[0], t[1], 0.01, 0.001));
  const std::string yaml = cal::networkYaml("base_link", r);
  EXPECT_NE(yaml.find("\nsick_front:\n  header:\n    frame_id: \"base_link\"\n  child_frame_id: \"sick_front\""),
            std::string::npos) << yaml;
  EXPECT_NE(yaml.find("\nsick_rear:\n"), std::string::npos);
  EXPECT_NE(yaml.find("child_frame_id: \"sick/rear\""), std::string::npos);
  EXPECT_NE(yaml.find("# stereo: NOT calibrated"), std::string::npos);
  EXPECT_NE(yaml.find("unobservable"), std::string::npos);
  // The rear ladar's yaw of pi as a quaternion about z (w ~ 0, z ~ +-1).
  EXPECT_NE(yaml.find("sick_rear:\n  header"), std::string::npos);
  const std::string launch = cal::networkLaunch("/tmp/network.yaml", r);
  EXPECT_NE(launch.find("<rosparam command=\"load\" file=\"/tmp/network.yaml\" ns=\"ladar_calibration_network\"/>"),
            std::string::npos) << launch;
  EXPECT_NE(launch.find("args=\"/ladar_calibration_network/sick_rear\""), std::string::npos);
  EXPECT_NE(launch.find("<!-- stereo was NOT calibrated -->"), std::string::npos);
  EXPECT_EQ(cal::networkKey("3d/lidar"), "sensor_3d_lidar");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
