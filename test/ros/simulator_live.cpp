// The LadarSimulator nodelet, live: the Velodyne cloud in the driver's XYZIRT layout with its
// truth, the SICK LaserScans, tf odom -> base_link -> sensors, and the true extrinsics param.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <mutex>

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "rostest_support.h"

namespace ladar_perception {
namespace {

using ladar_perception::rostest::waitFor;

struct Inbox {
  std::mutex mutex;
  std::map<ros::Time, sensor_msgs::PointCloud2ConstPtr> clouds, truths;
  std::vector<sensor_msgs::LaserScanConstPtr> scans;
};

TEST(SimulatorLive, PublishesScansTruthAndTf) {
  ros::NodeHandle nh;
  Inbox inbox;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  auto cloud_sub = nh.subscribe<sensor_msgs::PointCloud2>("velodyne_points", 5,
      [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.clouds[m->header.stamp] = m;
      });
  auto truth_sub = nh.subscribe<sensor_msgs::PointCloud2>("velodyne_points_truth", 5,
      [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.truths[m->header.stamp] = m;
      });
  auto scan_sub = nh.subscribe<sensor_msgs::LaserScan>("sick_front/scan", 20,
      [&](const sensor_msgs::LaserScanConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.scans.push_back(m);
      });
  // A Velodyne revolution and its truth with the same stamp; the newest one after the tf
  // listener has been filling for a while, so tf covers its stamp.
  ros::WallDuration(2.0).sleep();
  sensor_msgs::PointCloud2ConstPtr cloud, truth;
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    for (auto r = inbox.clouds.rbegin(); r != inbox.clouds.rend(); ++r) {
      const auto& kv = *r;
      auto it = inbox.truths.find(kv.first);
      if (it != inbox.truths.end()) {
        cloud = kv.second;
        truth = it->second;
        return true;
      }
    }
    return false;
  }, 60.0)) << "no velodyne_points with matching velodyne_points_truth";
  EXPECT_EQ(cloud->header.frame_id, "velodyne");
  EXPECT_EQ(cloud->point_step, 22u);
  ASSERT_EQ(cloud->fields.size(), 6u);
  EXPECT_EQ(cloud->fields[4].name, "ring");
  EXPECT_EQ(truth->width, cloud->width);
  CloudLayout layout;
  PointCloudView view;
  std::string error;
  ASSERT_TRUE(viewOf(*cloud, &layout, &view, &error)) << error;
  ASSERT_GT(view.size(), 50000u);
  for (std::size_t i = 0; i < view.size(); i += 101) {
    EXPECT_NEAR(view.xyz(i).z(), -1.9f, 1e-4f);  // flat ground, noise off, roof mount 1.9 m
    EXPECT_EQ(truth->data[i], static_cast<uint8_t>(sim::SurfaceClass::kRoad));
  }

  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    return !inbox.scans.empty();
  }, 10.0));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_EQ(inbox.scans.front()->ranges.size(), 361u);
    EXPECT_EQ(inbox.scans.front()->header.frame_id, "sick_front");
  }

  // tf at the scan's stamp: the sensor 1.9 m above flat ground.
  std::string tf_error;
  ASSERT_TRUE(buffer.canTransform("odom", "velodyne", cloud->header.stamp, ros::Duration(5.0), &tf_error))
      << tf_error;
  const auto t = buffer.lookupTransform("odom", "velodyne", cloud->header.stamp);
  EXPECT_NEAR(t.transform.translation.z, 1.9, 1e-6);

  std::string extrinsics;
  ASSERT_TRUE(ros::param::get("/simulator/true_extrinsics", extrinsics));
  sim::SensorRig rig;
  ASSERT_TRUE(sim::parseSensorRig(extrinsics, &rig, &error)) << error;
  EXPECT_EQ(rig.sensors.size(), 5u);
}

}  // namespace
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "simulator_live_test");
  return RUN_ALL_TESTS();
}
