// rostest of the Calibration nodelet end to end: empty-buffer answer, simulated data, a
// calibration within tolerance while a second request is answered busy, progress published, the
// YAML written and loaded by static_transform_publisher, save/reset, and a degenerate (flat) scene
// reported by name.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <thread>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_msgs/String.h>
#include <std_srvs/Trigger.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/Calibrate.h"
#include "ladar_perception/calibration/experiment.h"

#include "rostest_support.h"

namespace cal = ladar_perception::calibration;
namespace sim = ladar_perception::sim;

namespace {

const char* kCalibrate = "/calibration/calibrate";

using ladar_perception::rostest::scanSetCloud;

class CalibrationRostest : public ::testing::Test {
 protected:
  void SetUp() override {
    ref_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/velodyne_ref/points", 20);
    target_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/velodyne_target/points", 20);
    progress_sub_ = nh_.subscribe<std_msgs::String>(
        "/calibration/progress", 100, [this](const std_msgs::String::ConstPtr&) { ++progress_; });
    ASSERT_TRUE(ros::service::waitForService(kCalibrate, ros::Duration(60.0)));
    // The reference's known extrinsic (base_link -> velodyne_ref), as the vehicle's URDF would.
    cal::PairSetup pair;
    ASSERT_TRUE(cal::pairFromName("velodyne-velodyne", &pair, nullptr));
    geometry_msgs::TransformStamped ref =
        tf2::eigenToTransform(cal::toIsometry(pair.reference.extrinsic));
    ref.header.stamp = ros::Time::now();
    ref.header.frame_id = "base_link";
    ref.child_frame_id = "velodyne_ref";
    static_broadcaster_.sendTransform(ref);
    ros::Duration(0.5).sleep();
  }

  // Simulates the thesis experiment on `world` and publishes it like a driving vehicle.
  void publishTrial(const std::string& world_name, uint64_t seed, cal::ExperimentTrial* trial) {
    sim::World world;
    std::string error;
    ASSERT_TRUE(sim::makeStandardWorld(world_name, 1, &world, &error)) << error;
    cal::PairSetup pair;
    ASSERT_TRUE(cal::pairFromName("velodyne-velodyne", &pair, &error));
    cal::ExperimentOptions options;
    ASSERT_TRUE(cal::makeTrial(world, pair, options, seed, trial, &error)) << error;
    for (std::size_t k = 0; k < trial->input.reference.numScans(); ++k) {
      const ros::Time stamp = ros::Time::now();
      geometry_msgs::TransformStamped t =
          tf2::eigenToTransform(trial->input.reference.vehicle_poses[k]);
      t.header.stamp = stamp;
      t.header.frame_id = "odom";
      t.child_frame_id = "base_link";
      broadcaster_.sendTransform(t);
      ref_pub_.publish(scanSetCloud(trial->input.reference, k, "velodyne_ref", stamp));
      target_pub_.publish(scanSetCloud(trial->input.target, k, "velodyne_target", stamp));
      ros::Duration(0.15).sleep();
    }
    // Let the last pose's tf arrive after its scans, then let the nodelet's timer drain them.
    geometry_msgs::TransformStamped last =
        tf2::eigenToTransform(trial->input.reference.vehicle_poses.back());
    last.header.stamp = ros::Time::now();
    last.header.frame_id = "odom";
    last.child_frame_id = "base_link";
    broadcaster_.sendTransform(last);
    ros::Duration(1.5).sleep();
  }

  ladar_perception::Calibrate::Response call(const std::string& method = "") {
    ladar_perception::Calibrate srv;
    srv.request.method = method;
    EXPECT_TRUE(ros::service::call(kCalibrate, srv));
    return srv.response;
  }

  ros::NodeHandle nh_;
  ros::Publisher ref_pub_, target_pub_;
  ros::Subscriber progress_sub_;
  tf2_ros::TransformBroadcaster broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  std::atomic<int> progress_{0};
};

TEST_F(CalibrationRostest, EndToEnd) {
  // 1. Nothing buffered yet: a clear answer, no crash.
  ladar_perception::Calibrate::Response r = call();
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no data"), std::string::npos) << r.message;

  // 2. Simulated data of the thesis world, then a calibration; a second request is busy.
  cal::ExperimentTrial trial;
  publishTrial("thesis", 5, &trial);
  std::remove("/tmp/ladar_perception_calibration_rostest.yaml");
  ladar_perception::Calibrate::Response first;
  std::thread worker([&]() { first = call(); });
  ros::Duration(1.0).sleep();
  const ladar_perception::Calibrate::Response busy = call();
  EXPECT_FALSE(busy.success);
  EXPECT_NE(busy.message.find("busy"), std::string::npos) << busy.message;
  worker.join();
  ASSERT_TRUE(first.success) << first.message;
  const cal::Pose6 got = cal::fromIsometry(tf2::transformToEigen(first.transform));
  const cal::Pose6 err = cal::poseDifference(got, trial.truth);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(err[i]), 0.03) << cal::dofName(i);
  for (int i = 3; i < 6; ++i) EXPECT_LT(std::abs(err[i]), 0.005) << cal::dofName(i);
  EXPECT_EQ(first.transform.header.frame_id, "base_link");
  EXPECT_EQ(first.transform.child_frame_id, "velodyne_target");
  ASSERT_EQ(first.stddev.size(), 6u);
  for (double s : first.stddev) EXPECT_TRUE(std::isfinite(s));
  EXPECT_TRUE(first.unobservable.empty());
  EXPECT_GT(first.elapsed, 0.0);
  EXPECT_NE(first.launch_line.find("static_transform_publisher"), std::string::npos);
  ros::Duration(0.5).sleep();
  EXPECT_GT(progress_.load(), 0);

  // 3. The YAML loads as a parameter that static_transform_publisher publishes.
  const std::string yaml = "/tmp/ladar_perception_calibration_rostest.yaml";
  ASSERT_TRUE(std::ifstream(yaml).good());
  ASSERT_EQ(std::system(("rosparam load " + yaml + " /calibration_rostest_tf").c_str()), 0);
  const pid_t child = fork();
  if (child == 0) {
    execl("/usr/lib/tf2_ros/static_transform_publisher", "static_transform_publisher",
          "/calibration_rostest_tf", "__name:=calibration_rostest_stp", static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(child, 0);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  std::string why;
  const bool found = buffer.canTransform("base_link", "velodyne_target", ros::Time(0),
                                         ros::Duration(15.0), &why);
  EXPECT_TRUE(found) << why;
  if (found) {
    const cal::Pose6 published = cal::fromIsometry(tf2::transformToEigen(
        buffer.lookupTransform("base_link", "velodyne_target", ros::Time(0))));
    EXPECT_LT(cal::poseDifference(published, got).norm(), 1e-6);
  }
  kill(child, SIGINT);
  waitpid(child, nullptr, 0);

  // 4. save writes the last result again; reset empties the buffers.
  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::call("/calibration/save", trigger));
  EXPECT_TRUE(trigger.response.success) << trigger.response.message;
  ASSERT_TRUE(ros::service::call("/calibration/reset", trigger));
  EXPECT_TRUE(trigger.response.success);
  r = call();
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no data"), std::string::npos) << r.message;

  // 5. A degenerate scene (flat ground): x, y and yaw are reported, success is false.
  cal::ExperimentTrial flat;
  publishTrial("flat", 7, &flat);
  r = call("refine");
  EXPECT_FALSE(r.success) << r.message;
  EXPECT_EQ(r.unobservable, (std::vector<std::string>{"x", "y", "yaw"})) << r.message;
  r = call("no_such_method");
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("unknown method"), std::string::npos);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "calibration_rostest");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  return rc;
}
