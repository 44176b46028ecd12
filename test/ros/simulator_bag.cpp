// A written simulation bag reads back with rosbag and has the expected topics, counts, layouts
// and tf; the ladar_simulate tool writes one from the command line.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/ladar_simulator_messages.h"
#include "ladar_perception/sim/sensor_rig.h"

namespace ladar_perception {
namespace {

std::string tempPath(const std::string& name) {
  return testing::TempDir() + "/simulator_bag_" + std::to_string(::getpid()) + "_" + name;
}

std::map<std::string, std::size_t> topicCounts(rosbag::Bag& bag) {
  std::map<std::string, std::size_t> counts;
  rosbag::View view(bag);
  for (const rosbag::MessageInstance& m : view) ++counts[m.getTopic()];
  return counts;
}

class SimulatorBag : public testing::Test {
 protected:
  void SetUp() override {
    std::string error;
    ASSERT_TRUE(sim::makeStandardWorld("urban", 2, &world_, &error)) << error;
  }
  sim::World world_;
};

TEST_F(SimulatorBag, WrittenBagReadsBackWithTopicsCountsLayoutsAndTf) {
  const sim::SensorRig rig = sim::SensorRig::thesisVehicle();
  const sim::VehicleMotion motion = sim::VehicleMotion::driving(world_, world_.standardDrive());
  const sim::RigSimulator simulator(world_, rig, motion, 2);
  SimulationBagOptions options;
  options.path = tempPath("library.bag");
  options.duration = 1.0;
  SimulationBagSummary summary;
  std::string error;
  ASSERT_TRUE(writeSimulationBag(simulator, options, &summary, &error)) << error;

  rosbag::Bag bag;
  bag.open(options.path, rosbag::bagmode::Read);
  const auto counts = topicCounts(bag);
  const std::map<std::string, std::size_t> expected = {
      {"/tf", 50},
      {"/tf_static", 1},
      {"/velodyne_points", 10},
      {"/velodyne_points_truth", 10},
      {"/sick_front/scan", 75},
      {"/sick_front/scan_truth", 75},
      {"/sick_rear/scan", 75},
      {"/sick_rear/scan_truth", 75},
      {"/sick_vertical/scan", 75},
      {"/sick_vertical/scan_truth", 75},
      {"/stereo/points", 10},
      {"/stereo/points_truth", 10},
  };
  EXPECT_EQ(counts, expected);

  // Velodyne: the driver's packed XYZIRT, truth of the same length, stamps 0.1 s apart.
  std::vector<ros::Time> velodyne_stamps;
  std::vector<uint32_t> velodyne_widths, truth_widths;
  rosbag::View velodyne(bag, rosbag::TopicQuery(std::vector<std::string>{"/velodyne_points", "/velodyne_points_truth"}));
  for (const rosbag::MessageInstance& m : velodyne) {
    sensor_msgs::PointCloud2ConstPtr cloud = m.instantiate<sensor_msgs::PointCloud2>();
    ASSERT_TRUE(cloud);
    EXPECT_EQ(cloud->header.frame_id, "velodyne");
    EXPECT_EQ(cloud->header.stamp, m.getTime());
    if (m.getTopic() == "/velodyne_points") {
      ASSERT_EQ(cloud->fields.size(), 6u);
      EXPECT_EQ(cloud->point_step, 22u);
      EXPECT_EQ(cloud->fields[4].name, "ring");
      EXPECT_EQ(cloud->fields[4].datatype, sensor_msgs::PointField::UINT16);
      EXPECT_EQ(cloud->fields[5].name, "time");
      EXPECT_GT(cloud->width, 80000u);
      CloudLayout layout;
      PointCloudView view;
      ASSERT_TRUE(viewOf(*cloud, &layout, &view, &error)) << error;
      EXPECT_TRUE(view.hasRing());
      velodyne_stamps.push_back(cloud->header.stamp);
      velodyne_widths.push_back(cloud->width);
    } else {
      ASSERT_EQ(cloud->fields.size(), 1u);
      EXPECT_EQ(cloud->fields[0].name, "class");
      EXPECT_EQ(cloud->fields[0].datatype, sensor_msgs::PointField::UINT8);
      EXPECT_EQ(cloud->point_step, 1u);
      truth_widths.push_back(cloud->width);
      for (uint8_t c : cloud->data) ASSERT_LT(c, sim::kNumSurfaceClasses);
    }
  }
  EXPECT_EQ(velodyne_widths, truth_widths);
  ASSERT_EQ(velodyne_stamps.size(), 10u);
  for (std::size_t k = 0; k < velodyne_stamps.size(); ++k) {
    EXPECT_NEAR((velodyne_stamps[k] - options.start).toSec(), 0.1 * k, 1e-6);
  }

  // SICK: LaserScan with 361 beams and per-beam truth.
  rosbag::View sick(bag, rosbag::TopicQuery(std::vector<std::string>{"/sick_front/scan", "/sick_front/scan_truth"}));
  for (const rosbag::MessageInstance& m : sick) {
    if (m.getTopic() == "/sick_front/scan") {
      sensor_msgs::LaserScanConstPtr scan = m.instantiate<sensor_msgs::LaserScan>();
      ASSERT_TRUE(scan);
      EXPECT_EQ(scan->ranges.size(), 361u);
      EXPECT_EQ(scan->header.frame_id, "sick_front");
      EXPECT_NEAR(scan->angle_increment, 0.5 * M_PI / 180.0, 1e-7);
      EXPECT_FLOAT_EQ(scan->range_max, 80.f);
      // Tilted to meet the ground about 10 m ahead: the centre beam returns near there.
      EXPECT_NEAR(scan->ranges[180], std::hypot(10.0, 1.0), 1.0);
    } else {
      sensor_msgs::PointCloud2ConstPtr truth = m.instantiate<sensor_msgs::PointCloud2>();
      ASSERT_TRUE(truth);
      EXPECT_EQ(truth->width, 361u);
    }
  }

  // tf: odom -> base_link follows the drive on the ground; /tf_static holds every mount.
  rosbag::View tf(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}));
  std::set<std::string> static_children;
  double last_x = -1e9;
  for (const rosbag::MessageInstance& m : tf) {
    tf2_msgs::TFMessageConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
    ASSERT_TRUE(msg);
    if (m.getTopic() == "/tf_static") {
      EXPECT_EQ(m.getConnectionHeader()->at("latching"), "1");
      for (const auto& t : msg->transforms) {
        EXPECT_EQ(t.header.frame_id, "base_link");
        static_children.insert(t.child_frame_id);
      }
      continue;
    }
    ASSERT_EQ(msg->transforms.size(), 1u);
    const auto& t = msg->transforms[0];
    EXPECT_EQ(t.header.frame_id, "odom");
    EXPECT_EQ(t.child_frame_id, "base_link");
    const double t_sim = (t.header.stamp - options.start).toSec();
    const Eigen::Isometry3d truth = world_.drivePose(t_sim);
    EXPECT_NEAR(t.transform.translation.x, truth.translation().x(), 1e-9);
    EXPECT_NEAR(t.transform.translation.z, truth.translation().z(), 1e-6);
    EXPECT_GT(t.transform.translation.x, last_x);  // driving east
    last_x = t.transform.translation.x;
  }
  EXPECT_EQ(static_children, (std::set<std::string>{"velodyne", "sick_front", "sick_rear", "sick_vertical", "stereo"}));
  bag.close();
  std::remove(options.path.c_str());
}

TEST_F(SimulatorBag, BadOptionsAreErrorsNotCrashes) {
  const sim::SensorRig rig = sim::SensorRig::thesisVehicle();
  const sim::VehicleMotion motion = sim::VehicleMotion::driving(world_, world_.standardDrive());
  const sim::RigSimulator simulator(world_, rig, motion, 2);
  SimulationBagOptions options;
  options.path = "/nonexistent-dir/x.bag";
  options.duration = 0.5;
  std::string error;
  EXPECT_FALSE(writeSimulationBag(simulator, options, nullptr, &error));
  EXPECT_FALSE(error.empty());
  options.path = tempPath("zero.bag");
  options.duration = 0.0;
  EXPECT_FALSE(writeSimulationBag(simulator, options, nullptr, &error));
}

// The command-line tool: the example, shortened, plus the extrinsics YAML and PNG.
TEST(SimulatorTool, LadarSimulateWritesBagExtrinsicsAndPicture) {
  char exe[4096] = {0};
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  ASSERT_GT(n, 0);
  std::string dir(exe, static_cast<std::size_t>(n));
  dir = dir.substr(0, dir.rfind('/'));
  const std::string tool = dir + "/ladar_simulate";
  if (::access(tool.c_str(), X_OK) != 0) GTEST_SKIP() << "ladar_simulate not built next to the test: " << tool;
  const std::string bag_path = tempPath("tool.bag");
  const std::string png = tempPath("tool.png");
  const std::string cmd = tool + " --world urban --duration 0.5 --noise datasheet --out " + bag_path +
                          " --png " + png + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  rosbag::Bag bag;
  bag.open(bag_path, rosbag::bagmode::Read);
  const auto counts = topicCounts(bag);
  EXPECT_EQ(counts.at("/velodyne_points"), 5u);
  EXPECT_EQ(counts.at("/tf"), 25u);
  bag.close();
  const std::string extrinsics = tempPath("tool.extrinsics.yaml");
  sim::SensorRig rig;
  std::string error;
  ASSERT_TRUE(sim::loadSensorRig(extrinsics, &rig, &error)) << error;
  EXPECT_EQ(rig.sensors.size(), 5u);
  EXPECT_NEAR(rig.sensors[0].base_to_sensor.translation().z(), 1.9, 1e-12);
  EXPECT_DOUBLE_EQ(rig.sensors[0].velodyne.noise_sigma, 0.02);
  std::ifstream picture(png, std::ios::binary);
  EXPECT_TRUE(picture.good());
  // Bad arguments: a clear error and a non-zero exit.
  EXPECT_NE(std::system((tool + " --world moon --out " + bag_path + " 2> /dev/null").c_str()), 0);
  EXPECT_NE(std::system((tool + " --world urban --duration -1 --out " + bag_path + " 2> /dev/null").c_str()), 0);
  std::remove(bag_path.c_str());
  std::remove(extrinsics.c_str());
  std::remove(png.c_str());
}

}  // namespace
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::Time::init();
  return RUN_ALL_TESTS();
}
