// rostest of launch/demo.launch: with no bag and no hardware, the LadarSimulator nodelet feeds
// VerticalScanGround and HoughGround through the launch file's wiring; the outputs carry labels
// and the Hough fit finds the simulated road under the vertical scanner.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/HoughGroundFit.h"
#include "rostest_support.h"

using ladar_perception::rostest::waitFor;

TEST(LaunchDemo, SimulatorDrivesBothGroundNodelets) {
  ros::NodeHandle nh;
  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr classified;
  std::atomic<int> fits{0}, valid_fits{0};
  ladar_perception::HoughGroundFit last_valid;
  ros::Subscriber cloud_sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "/vertical_scan_ground/classified", 2, [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        classified = m;
      });
  ros::Subscriber fit_sub = nh.subscribe<ladar_perception::HoughGroundFit>(
      "/hough_ground/ground_fit", 50, [&](const ladar_perception::HoughGroundFitConstPtr& m) {
        ++fits;
        if (m->valid) {
          std::lock_guard<std::mutex> lock(mutex);
          last_valid = *m;
          ++valid_fits;
        }
      });
  EXPECT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(mutex);
    return classified != nullptr && valid_fits > 10;
  }, 100.0)) << "classified " << (classified != nullptr) << ", fits " << fits << " (valid " << valid_fits << ")";
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_TRUE(classified != nullptr);
  EXPECT_EQ(classified->header.frame_id, "velodyne");
  EXPECT_GT(classified->width * classified->height, 10000u);
  bool has_label = false;
  for (const auto& f : classified->fields) has_label |= f.name == "label";
  EXPECT_TRUE(has_label);
  // base_link is on the road in the simulator: the fitted ground is near height 0, nearly level.
  EXPECT_EQ(last_valid.header.frame_id, "base_link");
  EXPECT_LT(std::fabs(last_valid.ground), 0.3);
  EXPECT_LT(std::fabs(last_valid.slope), 0.1);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "launch_demo_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
