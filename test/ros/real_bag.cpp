// rostest: a rosbag of real KITTI HDL-64E scans with faults between them, played twice with
// `rosbag play --clock` (a looping bag: the clock jumps back) through launch/vehicle.launch on bag
// time. The faults: truncated messages, x of a wrong datatype, NaN and Inf returns, a stamp a
// minute back, and a frame whose tf arrives in the bag after its scan. Every valid scan must be
// answered with the labels the core gives it, every bad one counted in the nodelet's
// diagnostics, and the manager must still be up and answering afterwards.
// The scans are read from $LADAR_KITTI_DIR, else from the data folder beside the package; without
// them the test is skipped. The bag is written to a temporary folder and removed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nodelet/NodeletList.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/kitti.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using lp::rostest::cloudMsg;
using lp::rostest::kittiDir;
using lp::rostest::kittiScans;
using lp::rostest::labelsOf;
using lp::rostest::mountTransform;
using lp::rostest::waitFor;

constexpr float kSensorHeight = 1.73f;  // the static transform of real_bag.test [m]

// The classified clouds of the vertical scan nodelet, checked against the labels expected for
// their stamp as they come.
struct Answers {
  std::mutex mutex;
  std::map<uint64_t, std::vector<uint8_t>> expected;  // by header stamp [ns]
  int answered = 0;
  int wrong_labels = 0;
  int unexpected = 0;
  void callback(const sensor_msgs::PointCloud2ConstPtr& m) {
    const std::vector<uint8_t> labels = labelsOf(*m);
    std::lock_guard<std::mutex> lock(mutex);
    auto it = expected.find(m->header.stamp.toNSec());
    if (it == expected.end()) {
      ++unexpected;
      return;
    }
    ++answered;
    if (labels != it->second) ++wrong_labels;
  }
  int count() {
    std::lock_guard<std::mutex> lock(mutex);
    return answered;
  }
};

// The latest values of the vertical scan nodelet's diagnostic status.
struct Diagnostics {
  std::mutex mutex;
  std::map<std::string, std::string> values;
  void callback(const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
    for (const auto& s : m->status) {
      if (s.name.find("vertical scan ground") == std::string::npos) continue;
      std::lock_guard<std::mutex> lock(mutex);
      values.clear();
      for (const auto& kv : s.values) values[kv.key] = kv.value;
    }
  }
  std::string get(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = values.find(key);
    return it == values.end() ? std::string() : it->second;
  }
};

TEST(RealBag, EveryValidScanOfALoopingBagWithFaultsIsAnsweredThroughTheVehicleLaunch) {
  const std::vector<std::string> files = kittiScans();
  if (files.empty()) GTEST_SKIP() << "no KITTI scans in " << kittiDir();

  ros::AsyncSpinner spinner(2);
  spinner.start();
  ros::NodeHandle nh;
  Answers answers;
  Diagnostics diagnostics;
  ros::Subscriber sub = nh.subscribe("/vertical_scan_ground/classified", 100, &Answers::callback, &answers);
  ros::Subscriber diag_sub = nh.subscribe("/diagnostics", 100, &Diagnostics::callback, &diagnostics);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 10);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 60.0))
      << "vehicle.launch's VerticalScanGround did not come up";

  // The scans and the labels the core gives them.
  lp::VerticalScanGround core(lp::verticalScanDefaultParams());
  auto coreLabels = [&](const lp::PackedCloud& c) {
    lp::PointCloudView view;
    EXPECT_TRUE(c.view(&view));
    lp::GroundClassification out;
    core.classify(view, lp::SensorPose::fromHeight(kSensorHeight), &out);
    return std::vector<uint8_t>(out.labels.begin(), out.labels.end());
  };
  std::vector<lp::PackedCloud> scans;
  std::vector<std::vector<uint8_t>> labels;
  for (const std::string& f : files) {
    lp::PackedCloud c;
    std::string error;
    ASSERT_TRUE(lp::readKittiBin(f, &c, &error)) << error;
    labels.push_back(coreLabels(c));
    scans.push_back(std::move(c));
  }

  // The bag: one slot of 0.1 s per scan, each valid scan followed by a truncated copy and a copy
  // with x as uint8; then the first scan with NaN and Inf returns, a scan in a frame whose tf
  // comes 0.3 s later, and a scan stamped a minute back.
  char dir_template[] = "/tmp/ladar_real_bag_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  const std::string path = dir + "/kitti_faults.bag";
  int valid_per_play = 0, bad_per_play = 0;
  {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Write);
    const ros::Time t0(1000.0);
    auto slot = [&](std::size_t k) { return t0 + ros::Duration(0.5 + 0.1 * static_cast<double>(k)); };
    auto valid = [&](const lp::PackedCloud& c, const std::string& frame, ros::Time stamp, ros::Time at,
                     const std::vector<uint8_t>& expected) {
      bag.write("/velodyne_points", at, cloudMsg(c, frame, stamp));
      answers.expected[stamp.toNSec()] = expected;
      ++valid_per_play;
    };
    const std::size_t n = scans.size();
    for (std::size_t k = 0; k < n; ++k) {
      valid(scans[k], "velodyne", slot(k), slot(k), labels[k]);
      const ros::Time t_truncated = slot(k) + ros::Duration(0.02);
      auto truncated = cloudMsg(scans[k], "velodyne", t_truncated);
      truncated->data.resize(truncated->data.size() / 2);
      bag.write("/velodyne_points", t_truncated, truncated);
      const ros::Time t_wrong = slot(k) + ros::Duration(0.04);
      auto wrong = cloudMsg(scans[k], "velodyne", t_wrong);
      wrong->fields[0].datatype = sensor_msgs::PointField::UINT8;
      bag.write("/velodyne_points", t_wrong, wrong);
      bad_per_play += 2;
    }
    {  // NaN and Inf returns: those are unknown, the rest labelled as the core labels the cloud.
      lp::PackedCloud c = scans[0];
      const lp::FieldDesc& fx = *lp::findField(c.layout, "x");
      for (std::size_t i = 0; i < c.size(); i += 97) {
        lp::writeField(c.data.data() + i * c.layout.point_step, fx,
                       (i / 97) % 2 ? std::numeric_limits<double>::quiet_NaN()
                                    : std::numeric_limits<double>::infinity());
      }
      valid(c, "velodyne", slot(n), slot(n), coreLabels(c));
    }
    {  // A frame with no tf yet: the scan waits in the nodelet's tf filter until the bag brings it.
      const ros::Time stamp = slot(n + 1);
      valid(scans[1], "velodyne_late", stamp, stamp, labels[1]);
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(mountTransform("base_link", "velodyne_late", kSensorHeight, stamp - ros::Duration(0.05)));
      tf.transforms.push_back(mountTransform("base_link", "velodyne_late", kSensorHeight, stamp + ros::Duration(0.05)));
      bag.write("/tf", stamp + ros::Duration(0.3), tf);
    }
    // A stamp a minute behind the bag's clock.
    valid(scans[2], "velodyne", slot(n + 2) - ros::Duration(60.0), slot(n + 2), labels[2]);
    bag.close();
  }

  // Played twice, as `rosbag play --loop` does: the second play takes the clock back 1.5 s.
  for (int play = 1; play <= 2; ++play) {
    const std::string command = "rosbag play --clock -q -d 2 -r 0.5 " + path + " > /dev/null";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    EXPECT_TRUE(waitFor([&] { return answers.count() >= play * valid_per_play; }, 60.0))
        << "play " << play << ": " << answers.count() << " of " << play * valid_per_play << " valid scans answered";
  }

  // The manager is still up, hosts the nodelets and answers a scan published afterwards.
  nodelet::NodeletList list;
  ASSERT_TRUE(ros::service::call("/ladar_manager/list", list));
  EXPECT_NE(std::find(list.response.nodelets.begin(), list.response.nodelets.end(), "/vertical_scan_ground"),
            list.response.nodelets.end());
  {
    const ros::Time stamp(2000.0);
    {
      std::lock_guard<std::mutex> lock(answers.mutex);
      answers.expected[stamp.toNSec()] = labels[0];
    }
    pub.publish(cloudMsg(scans[0], "velodyne", stamp));
    EXPECT_TRUE(waitFor([&] { return answers.count() >= 2 * valid_per_play + 1; }, 30.0))
        << "no answer after the bag";
  }

  {
    std::lock_guard<std::mutex> lock(answers.mutex);
    EXPECT_EQ(answers.answered, 2 * valid_per_play + 1);
    EXPECT_EQ(answers.wrong_labels, 0);
    EXPECT_EQ(answers.unexpected, 0);
  }
  // The nodelet's diagnostics count every processed scan and every bad one, and no drop.
  const std::string processed = std::to_string(2 * valid_per_play + 1);
  EXPECT_TRUE(waitFor([&] { return diagnostics.get("scans processed") == processed; }, 10.0))
      << "scans processed: " << diagnostics.get("scans processed") << ", expected " << processed;
  EXPECT_EQ(diagnostics.get("errors total"), std::to_string(2 * bad_per_play));
  EXPECT_EQ(diagnostics.get("scans dropped"), "0");

  std::remove(path.c_str());
  rmdir(dir.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "real_bag_test");
  ros::NodeHandle nh;
  const int rc = RUN_ALL_TESTS();
  ros::shutdown();
  return rc;
}
