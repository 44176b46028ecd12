// rostest of the network calibration through launch/calibrate.launch: an empty-buffer answer,
// then three simulated HDL-64Es (a reference and two targets), ~calibrate_network with and
// without the cross pair, the joint solution within tolerance, the loop's closure reported, the
// one YAML and its launch file written and the YAML published by static_transform_publisher.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/CalibrateNetwork.h"
#include "ladar_perception/calibration/experiment.h"

#include "rostest_support.h"

namespace cal = ladar_perception::calibration;
namespace sim = ladar_perception::sim;

namespace {

const char* kService = "/calibration/calibrate_network";
const char* kYaml = "/tmp/ladar_perception_network_rostest.yaml";
const char* kLaunch = "/tmp/ladar_perception_network_rostest.launch";

using ladar_perception::rostest::scanSetCloud;

cal::NetworkSetup threeVelodynes() {
  cal::NetworkSetup n;
  n.name = "three-velodynes";
  n.reference_name = "velodyne_ref";
  n.reference = {cal::SensorKind::kVelodyne, cal::makePose(0, 0, 2.0, 0, 0, 0)};
  n.target_names = {"velodyne_target", "velodyne_side"};
  n.targets = {{cal::SensorKind::kVelodyne, cal::makePose(1.0, 0, 2.0, 0, 0, 0)},
               {cal::SensorKind::kVelodyne, cal::makePose(0.2, -0.8, 1.7, 0, 0.05, -0.6)}};
  return n;
}

ladar_perception::CalibrateNetwork::Response call(bool reference_only) {
  ladar_perception::CalibrateNetwork srv;
  srv.request.reference_only = reference_only;
  EXPECT_TRUE(ros::service::call(kService, srv));
  return srv.response;
}

TEST(NetworkCalibrationRostest, ThreeSensorsThroughCalibrateLaunch) {
  ros::NodeHandle nh;
  ASSERT_TRUE(ros::service::waitForService(kService, ros::Duration(60.0)));
  const cal::NetworkSetup network = threeVelodynes();
  ros::Publisher ref_pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_ref/points", 20);
  std::vector<ros::Publisher> target_pubs;
  for (const std::string& name : network.target_names) {
    target_pubs.push_back(nh.advertise<sensor_msgs::PointCloud2>("/" + name + "/points", 20));
  }
  tf2_ros::TransformBroadcaster broadcaster;
  tf2_ros::StaticTransformBroadcaster static_broadcaster;
  geometry_msgs::TransformStamped ref = tf2::eigenToTransform(cal::toIsometry(network.reference.extrinsic));
  ref.header.stamp = ros::Time::now();
  ref.header.frame_id = "base_link";
  ref.child_frame_id = "velodyne_ref";
  static_broadcaster.sendTransform(ref);
  ros::Duration(1.0).sleep();

  // 1. Nothing buffered: a clear answer.
  ladar_perception::CalibrateNetwork::Response r = call(false);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no data"), std::string::npos) << r.message;

  // 2. The sensors scan at the thesis experiment's ten poses.
  sim::World world;
  std::string error;
  ASSERT_TRUE(sim::makeStandardWorld("thesis", 1, &world, &error)) << error;
  cal::NetworkTrial trial;
  ASSERT_TRUE(cal::makeNetworkTrial(world, network, cal::ExperimentOptions(), 11, &trial, &error))
      << error;
  const std::size_t scans = trial.input.reference.numScans();
  for (std::size_t k = 0; k < scans; ++k) {
    const ros::Time stamp = ros::Time::now();
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(trial.input.reference.vehicle_poses[k]);
    t.header.stamp = stamp;
    t.header.frame_id = "odom";
    t.child_frame_id = "base_link";
    broadcaster.sendTransform(t);
    ref_pub.publish(scanSetCloud(trial.input.reference, k, "velodyne_ref", stamp));
    for (std::size_t s = 0; s < target_pubs.size(); ++s) {
      target_pubs[s].publish(scanSetCloud(trial.input.targets[s].scans, k, network.target_names[s], stamp));
    }
    ros::Duration(0.2).sleep();
  }
  geometry_msgs::TransformStamped last = tf2::eigenToTransform(trial.input.reference.vehicle_poses.back());
  last.header.stamp = ros::Time::now();
  last.header.frame_id = "odom";
  last.child_frame_id = "base_link";
  broadcaster.sendTransform(last);
  ros::Duration(1.5).sleep();

  // 3. The network: two edges to the reference and the cross pair, solved jointly.
  std::remove(kYaml);
  std::remove(kLaunch);
  r = call(false);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.transforms.size(), 2u);
  ASSERT_EQ(r.pairwise.size(), 2u);
  ASSERT_EQ(r.stddev.size(), 12u);
  ASSERT_EQ(r.edges.size(), 3u);
  EXPECT_TRUE(r.unobservable.empty());
  for (std::size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(r.transforms[s].header.frame_id, "base_link");
    EXPECT_EQ(r.transforms[s].child_frame_id, network.target_names[s]);
    const cal::Pose6 err = cal::poseDifference(
        cal::fromIsometry(tf2::transformToEigen(r.transforms[s])), trial.truth[s]);
    for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.03) << network.target_names[s] << " " << cal::dofName(i);
    for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.005) << network.target_names[s] << " " << cal::dofName(i);
    for (int i = 0; i < 6; ++i) EXPECT_TRUE(std::isfinite(r.stddev[6 * s + i]));
  }
  EXPECT_EQ(r.edges[0], "velodyne_target <- reference");
  EXPECT_EQ(r.edges[1], "velodyne_side <- reference");
  for (bool used : r.edge_used) EXPECT_TRUE(used);
  // The cross edge closes the loop reference -> target -> side -> reference within centimetres.
  EXPECT_EQ(r.loop_translation[0], 0.0);
  EXPECT_LT(r.loop_translation[2], 0.05);
  EXPECT_LT(r.loop_rotation[2], 0.01);
  EXPECT_EQ(r.output_file, kYaml);
  EXPECT_EQ(r.launch_file, kLaunch);

  // 4. The launch file starts a publisher per sensor from the YAML; do what it does for one.
  std::ifstream launch_in(kLaunch);
  ASSERT_TRUE(launch_in.good());
  std::stringstream launch;
  launch << launch_in.rdbuf();
  EXPECT_NE(launch.str().find("file=\"" + std::string(kYaml) + "\" ns=\"ladar_calibration_network\""),
            std::string::npos) << launch.str();
  EXPECT_NE(launch.str().find("args=\"/ladar_calibration_network/velodyne_side\""), std::string::npos);
  ASSERT_EQ(std::system((std::string("rosparam load ") + kYaml + " /ladar_calibration_network").c_str()), 0);
  const pid_t child = fork();
  if (child == 0) {
    execl("/usr/lib/tf2_ros/static_transform_publisher", "static_transform_publisher",
          "/ladar_calibration_network/velodyne_side", "__name:=network_rostest_stp",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(child, 0);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  std::string why;
  const bool found = buffer.canTransform("base_link", "velodyne_side", ros::Time(0), ros::Duration(15.0), &why);
  EXPECT_TRUE(found) << why;
  if (found) {
    const cal::Pose6 published = cal::fromIsometry(
        tf2::transformToEigen(buffer.lookupTransform("base_link", "velodyne_side", ros::Time(0))));
    const cal::Pose6 answered = cal::fromIsometry(tf2::transformToEigen(r.transforms[1]));
    EXPECT_LT(cal::poseDifference(published, answered).norm(), 1e-6);
  }
  kill(child, SIGINT);
  waitpid(child, nullptr, 0);

  // 5. Each target against the reference alone: two edges, the joint solution is the pairwise.
  r = call(true);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.edges.size(), 2u);
  for (std::size_t s = 0; s < 2; ++s) {
    const cal::Pose6 joint = cal::fromIsometry(tf2::transformToEigen(r.transforms[s]));
    const cal::Pose6 pairwise = cal::fromIsometry(tf2::transformToEigen(r.pairwise[s]));
    EXPECT_LT(cal::poseDifference(joint, pairwise).cwiseAbs().maxCoeff(), 1e-6);
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "network_calibration_rostest");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
