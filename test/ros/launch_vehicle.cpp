// rostest of launch/vehicle.launch: config/sensors.yaml is the one source of the sensor mounts
// (the static transforms the launch publishes equal what the rig parser reads from that file),
// the nodelets are loaded with their topics wired to the launch arguments, and the 3D ladar's
// cloud comes out classified in the ground frame given by the mounts.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <set>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using ladar_perception::rostest::waitFor;

bool advertised(const std::string& topic) {
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return false;
  for (const auto& t : topics) {
    if (t.name == topic) return true;
  }
  return false;
}

}  // namespace

TEST(LaunchVehicle, MountsInTfAreExactlyThoseOfSensorsYaml) {
  lp::sim::SensorRig rig;
  std::string error;
  ASSERT_TRUE(lp::sim::loadSensorRig(std::string(LADAR_SOURCE_DIR) + "/config/sensors.yaml", &rig, &error))
      << error;
  ASSERT_GE(rig.sensors.size(), 5u);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  for (const lp::sim::SensorMount& s : rig.sensors) {
    std::string why;
    ASSERT_TRUE(buffer.canTransform(rig.base_frame, s.frame_id, ros::Time(0), ros::Duration(30.0), &why))
        << s.frame_id << ": " << why;
    const Eigen::Isometry3d t =
        tf2::transformToEigen(buffer.lookupTransform(rig.base_frame, s.frame_id, ros::Time(0)));
    EXPECT_LT((t.translation() - s.base_to_sensor.translation()).norm(), 1e-9) << s.frame_id;
    const Eigen::Quaterniond q(t.linear()), q_rig(s.base_to_sensor.linear());
    EXPECT_LT(q.angularDistance(q_rig), 1e-9) << s.frame_id;
  }
}

TEST(LaunchVehicle, NodeletsLoadedWithTheirTopicsAndServices) {
  EXPECT_TRUE(ros::service::waitForService("/calibration/calibrate", ros::Duration(30.0)));
  EXPECT_TRUE(ros::service::exists("/calibration/reset", false));
  EXPECT_TRUE(ros::service::exists("/calibration/save", false));
  for (const char* topic : {"/vertical_scan_ground/classified", "/vertical_scan_ground/ground",
                            "/vertical_scan_ground/obstacles", "/hough_ground/classified",
                            "/hough_ground/ground_line", "/hough_ground/ground_fit"}) {
    EXPECT_TRUE(waitFor([&] { return advertised(topic); }, 30.0)) << topic << " not advertised";
  }
}

TEST(LaunchVehicle, VelodyneCloudComesOutClassified) {
  ros::NodeHandle nh, pnh("~");
  const std::string points_topic = pnh.param<std::string>("points", "/velodyne_points");
  // Flat ground seen by a 32-laser ladar mounted where config/sensors.yaml puts the Velodyne
  // (frame velodyne, 1.9 m above base_link, which is on the ground).
  lp::sim::SensorRig rig;
  std::string error;
  ASSERT_TRUE(lp::sim::loadSensorRig(std::string(LADAR_SOURCE_DIR) + "/config/sensors.yaml", &rig, &error));
  double height = 0;
  for (const auto& s : rig.sensors) {
    if (s.frame_id == "velodyne") height = s.base_to_sensor.translation().z();
  }
  ASSERT_GT(height, 0.5);
  lp::PackedCloud cloud;
  std::vector<Eigen::Vector3f> pts;
  std::vector<uint16_t> rings;
  for (int ring = 0; ring < 32; ++ring) {
    const double elev = (-24.0 + ring * 0.7) * M_PI / 180.0;
    for (int a = 0; a < 720; ++a) {
      const double az = a * 0.5 * M_PI / 180.0;
      const Eigen::Vector3d dir(std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az), std::sin(elev));
      const double range = height / -dir.z();
      if (range > 60.0) continue;
      pts.push_back((range * dir).cast<float>());
      rings.push_back(static_cast<uint16_t>(ring));
    }
  }
  const lp::CloudLayout layout = lp::velodyneXYZIRTLayout(static_cast<uint32_t>(pts.size()));
  cloud.layout = layout;
  cloud.data.assign(layout.row_step, 0);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    uint8_t* p = cloud.data.data() + i * layout.point_step;
    lp::writeField(p, *lp::findField(layout, "x"), pts[i].x());
    lp::writeField(p, *lp::findField(layout, "y"), pts[i].y());
    lp::writeField(p, *lp::findField(layout, "z"), pts[i].z());
    lp::writeField(p, *lp::findField(layout, "ring"), rings[i]);
  }

  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr classified;
  ros::Subscriber sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "/vertical_scan_ground/classified", 2, [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        classified = m;
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>(points_topic, 2);
  const bool got = waitFor([&] {
    sensor_msgs::PointCloud2Ptr msg = lp::toMessage(cloud);
    msg->header.frame_id = "velodyne";
    msg->header.stamp = ros::Time::now();
    pub.publish(msg);
    ros::WallDuration(0.1).sleep();
    std::lock_guard<std::mutex> lock(mutex);
    return classified != nullptr;
  }, 40.0);
  ASSERT_TRUE(got) << "nothing on /vertical_scan_ground/classified for clouds on " << points_topic;
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(classified->width * classified->height, pts.size());
  lp::CloudLayout out_layout;
  lp::PointCloudView view;
  ASSERT_TRUE(lp::viewOf(*classified, &out_layout, &view, &error)) << error;
  const lp::FieldDesc* label = lp::findField(out_layout, "label");
  ASSERT_NE(label, nullptr);
  std::size_t ground = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ground += classified->data[i * classified->point_step + label->offset] == 0;
  }
  // Flat ground under a correctly mounted sensor: (nearly) all of it is ground.
  EXPECT_GT(static_cast<double>(ground) / pts.size(), 0.95);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "launch_vehicle_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
