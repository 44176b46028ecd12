// rostest: one VerticalScanGround nodelet per lidar family in one manager (sensor_families.test):
// a VLP-16 with a ring field, an Ouster OS1-64 with organised clouds, rows counted from the top
// and a `channel` field on a tilted mount, and an HDL-32E cloud with no ring field. Each is
// fed a simulated scan of its sensor and must answer with the core's labels for that sensor
// and mount; a cloud of the wrong sensor is still answered (and reported).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/cloud/lidar_models.h"
#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "rostest_support.h"

namespace lp = ladar_perception;
using lp::rostest::waitFor;
using Latest = lp::rostest::Latest<sensor_msgs::PointCloud2>;

namespace {

// A scan of `sensor` in the urban world, `height` above base_link, rolled and pitched [deg] as
// the .test file's static transforms mount it.
lp::sim::SimulatedScan simulate(const std::string& sensor_name, double height, double roll_deg, double pitch_deg,
                                lp::SensorPose* pose) {
  lp::EvaluationSensor sensor;
  std::string error;
  EXPECT_TRUE(lp::makeEvaluationSensor(sensor_name, lp::sim::NoiseProfile::kDatasheet, &sensor, &error)) << error;
  sensor.tilt(roll_deg, pitch_deg);
  sensor.mount.translation() = Eigen::Vector3d(0.0, 0.0, height);
  lp::sim::World world;
  EXPECT_TRUE(lp::sim::makeStandardWorld("urban", 1, &world, &error)) << error;
  lp::sim::SimulatedScan scan;
  lp::sim::simulateVelodyneRevolution(world, world.drivePose(0.4 * world.driveDuration()) * sensor.mount,
                                      sensor.model, 3, &scan);
  pose->sensor_to_ground = sensor.mount.cast<float>();
  return scan;
}

// The labels the core gives the cloud for that sensor and pose.
std::vector<uint8_t> coreLabels(const lp::PackedCloud& cloud, const std::string& sensor, const lp::SensorPose& pose) {
  lp::PointCloudView view;
  EXPECT_TRUE(cloud.view(&view));
  lp::VerticalScanGround model;
  model.setLidarModel(*lp::findLidarModel(sensor));
  lp::GroundClassification result;
  model.classify(view, pose, &result);
  return std::vector<uint8_t>(result.labels.begin(), result.labels.end());
}

// Publishes `cloud` on `ns`/points in `frame` and returns the labels of `ns`/classified.
std::vector<uint8_t> classifyThroughNodelet(ros::NodeHandle& nh, const std::string& ns, const lp::PackedCloud& cloud,
                                            const std::string& frame) {
  Latest out;
  ros::Subscriber sub = nh.subscribe(ns + "/classified", 2, &Latest::callback, &out);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>(ns + "/points", 2);
  EXPECT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 30.0))
      << ns << ": the nodelet did not connect";
  // The first scan may arrive before the static transforms: publish until one is answered.
  for (int attempt = 0; attempt < 20 && out.count == 0; ++attempt) {
    pub.publish(lp::rostest::cloudMsg(cloud, frame, ros::Time::now()));
    waitFor([&] { return out.count > 0; }, 1.5);
  }
  const auto msg = out.get();
  EXPECT_TRUE(msg) << ns << ": no classified cloud";
  if (!msg) return {};
  EXPECT_EQ(msg->width * msg->height, cloud.layout.width * cloud.layout.height);
  return lp::rostest::labelsOf(*msg);
}

// Labels that agree; tf's quaternion and the test's rotation matrix differ in the last bits, which
// may move a return across a threshold.
double agreement(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  if (a.size() != b.size() || a.empty()) return 0.0;
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.size(); ++i) same += a[i] == b[i];
  return static_cast<double>(same) / a.size();
}

}  // namespace

TEST(SensorFamilies, VelodyneWithRingField) {
  ros::NodeHandle nh;
  lp::SensorPose pose;
  const lp::sim::SimulatedScan scan = simulate("vlp16", 1.0, 0.0, 0.0, &pose);
  ASSERT_NE(lp::findField(scan.cloud.layout, "ring"), nullptr);
  const std::vector<uint8_t> labels = classifyThroughNodelet(nh, "vlp16", scan.cloud, "vlp16");
  EXPECT_GE(agreement(labels, coreLabels(scan.cloud, "vlp16", pose)), 0.999);
}

TEST(SensorFamilies, OusterOrganisedWithChannelFieldOnATiltedMount) {
  ros::NodeHandle nh;
  lp::SensorPose pose;
  lp::sim::SimulatedScan scan = simulate("os1_64", 1.8, 2.0, 4.0, &pose);
  ASSERT_EQ(scan.cloud.layout.height, 64u);
  for (lp::FieldDesc& f : scan.cloud.layout.fields) {
    if (f.name == "ring") f.name = "channel";
  }
  const std::vector<uint8_t> labels = classifyThroughNodelet(nh, "ouster", scan.cloud, "os_sensor");
  const std::vector<uint8_t> core = coreLabels(scan.cloud, "os1_64", pose);
  EXPECT_GE(agreement(labels, core), 0.999);
  // The ground is found on the tilted mount: most true ground returns are labelled ground.
  std::size_t ground = 0, ground_ok = 0;
  for (std::size_t i = 0; i < scan.truth.size() && i < labels.size(); ++i) {
    if (!lp::sim::isGroundClass(static_cast<lp::sim::SurfaceClass>(scan.truth[i]))) continue;
    ++ground;
    ground_ok += labels[i] == lp::kLabelGround;
  }
  ASSERT_GT(ground, 10000u);
  EXPECT_GT(static_cast<double>(ground_ok) / ground, 0.95);
}

TEST(SensorFamilies, CloudWithoutRing) {
  ros::NodeHandle nh;
  lp::SensorPose pose;
  const lp::sim::SimulatedScan scan = simulate("hdl32e", 1.8, 0.0, 0.0, &pose);
  // x, y, z, intensity only (KITTI's layout): rows from the HDL-32E's elevation table.
  lp::PackedCloud plain;
  plain.layout = lp::xyziLayout(scan.cloud.layout.width);
  plain.data.assign(static_cast<std::size_t>(plain.layout.row_step), 0);
  lp::PointCloudView view;
  ASSERT_TRUE(scan.cloud.view(&view));
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    std::memcpy(plain.data.data() + i * plain.layout.point_step, p.data(), 12);
  }
  const std::vector<uint8_t> labels = classifyThroughNodelet(nh, "hdl32e", plain, "hdl32e");
  EXPECT_GE(agreement(labels, coreLabels(plain, "hdl32e", pose)), 0.999);

  // A VLP-16 cloud sent to the HDL-32E nodelet: answered all the same (the mismatch is a
  // throttled error, not a dropped scan).
  lp::SensorPose vlp_pose;
  const lp::sim::SimulatedScan vlp16 = simulate("vlp16", 1.8, 0.0, 0.0, &vlp_pose);
  EXPECT_EQ(classifyThroughNodelet(nh, "hdl32e", vlp16.cloud, "hdl32e").size(), vlp16.cloud.layout.width);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sensor_families_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
