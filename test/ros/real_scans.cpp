// rostest: real KITTI HDL-64E scans through VerticalScanGround, hosted in this process as a
// nodelet manager hosts it, with faults between them: truncated messages, a wrong field type,
// NaN and Inf returns, stamps going back a minute (a looping bag), a frame whose tf is missing
// and then arrives. Every valid scan must be answered, with the labels the core gives the same
// scan; every bad one is counted and the adapter keeps going.
// The scans are read from $LADAR_KITTI_DIR, else from the data folder beside the package
// (../shared/data/kitti_hdl64); without them the test is skipped. The data are not part of the
// package.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/kitti.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/vertical_scan_ground_ros.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using lp::rostest::Latest;
using lp::rostest::cloudMsg;
using lp::rostest::kittiDir;
using lp::rostest::kittiScans;
using lp::rostest::labelsOf;
using lp::rostest::mountTransform;
using lp::rostest::waitFor;

constexpr float kSensorHeight = 1.73f;  // KITTI's Velodyne above the road [m]

TEST(RealScans, EveryValidScanAnsweredWithTheCoreLabelsBetweenFaults) {
  const std::vector<std::string> files = kittiScans();
  if (files.empty()) GTEST_SKIP() << "no KITTI scans in " << kittiDir();

  ros::AsyncSpinner spinner(4);
  spinner.start();
  ros::NodeHandle nh("real_scans"), pnh("real_scans_private");
  pnh.setParam("queue_size", 3);
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Latest<sensor_msgs::PointCloud2> classified;
  ros::Subscriber sub = nh.subscribe("classified", 10, &Latest<sensor_msgs::PointCloud2>::callback, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 10);
  ros::Publisher tf_pub = ros::NodeHandle().advertise<tf2_msgs::TFMessage>("/tf_static", 10, true);
  ros::Publisher tf_dyn = ros::NodeHandle().advertise<tf2_msgs::TFMessage>("/tf", 10);
  tf2_msgs::TFMessage statics;
  statics.transforms.push_back(mountTransform("base_footprint", "velodyne", kSensorHeight, ros::Time(0)));
  tf_pub.publish(statics);
  ASSERT_TRUE(waitFor([&] {
    return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0 && tf_dyn.getNumSubscribers() > 0;
  }));

  // The core's labels of each scan, as the nodelet must give them.
  lp::VerticalScanGround core(lp::verticalScanDefaultParams());
  std::vector<lp::PackedCloud> scans;
  std::vector<std::vector<uint8_t>> expected;
  for (const std::string& f : files) {
    lp::PackedCloud c;
    std::string error;
    ASSERT_TRUE(lp::readKittiBin(f, &c, &error)) << error;
    lp::PointCloudView view;
    ASSERT_TRUE(c.view(&view, &error)) << error;
    lp::GroundClassification out;
    core.classify(view, lp::SensorPose::fromHeight(kSensorHeight), &out);
    expected.emplace_back(out.labels.begin(), out.labels.end());
    scans.push_back(std::move(c));
  }

  int answered = 0;
  // A valid scan: published, answered, and labelled as the core labels it.
  auto valid = [&](const sensor_msgs::PointCloud2Ptr& m, const std::vector<uint8_t>& labels,
                   const std::string& what) {
    const int before = classified.count;
    pub.publish(m);
    ASSERT_TRUE(waitFor([&] { return classified.count > before; }, 30.0)) << what << ": no answer";
    ++answered;
    const auto out = classified.get();
    ASSERT_TRUE(out);
    EXPECT_EQ(out->header.stamp, m->header.stamp) << what;
    EXPECT_EQ(labelsOf(*out), labels) << what;
  };
  // A bad message: counted as an error, no output.
  auto bad = [&](const sensor_msgs::PointCloud2Ptr& m, const std::string& what) {
    const uint64_t before = adapter.health().errorCount();
    const int out_before = classified.count;
    pub.publish(m);
    ASSERT_TRUE(waitFor([&] { return adapter.health().errorCount() > before; }, 30.0))
        << what << ": not counted";
    EXPECT_EQ(classified.count, out_before) << what;
  };

  ros::Time stamp = ros::Time::now();
  for (int loop = 0; loop < 2; ++loop) {
    // The second loop goes back a minute, as a looping bag does.
    if (loop == 1) stamp = stamp - ros::Duration(60.0);
    for (std::size_t k = 0; k < scans.size(); ++k) {
      stamp += ros::Duration(0.1);
      const std::string name = files[k] + (loop ? " (looped)" : "");
      valid(cloudMsg(scans[k], "velodyne", stamp), expected[k], name);

      // Truncated: data shorter than width x height x point_step.
      auto truncated = cloudMsg(scans[k], "velodyne", stamp);
      truncated->data.resize(truncated->data.size() / 2);
      bad(truncated, name + " truncated");

      // x of another datatype (uint8 where float32 was).
      auto wrong = cloudMsg(scans[k], "velodyne", stamp);
      wrong->fields[0].datatype = sensor_msgs::PointField::UINT8;
      wrong->fields[0].name = "x";
      bad(wrong, name + " with x as uint8");
    }
  }

  // NaN and Inf returns in a real scan: those returns are unknown, the rest labelled as the
  // core labels the same cloud.
  {
    lp::PackedCloud c = scans[0];
    const lp::FieldDesc& fx = *lp::findField(c.layout, "x");
    for (std::size_t i = 0; i < c.size(); i += 97) {
      lp::writeField(c.data.data() + i * c.layout.point_step, fx,
                     (i / 97) % 2 ? std::numeric_limits<double>::quiet_NaN()
                                  : std::numeric_limits<double>::infinity());
    }
    lp::PointCloudView view;
    ASSERT_TRUE(c.view(&view));
    lp::GroundClassification out;
    core.classify(view, lp::SensorPose::fromHeight(kSensorHeight), &out);
    const std::vector<uint8_t> labels(out.labels.begin(), out.labels.end());
    for (std::size_t i = 0; i < c.size(); i += 97) EXPECT_EQ(labels[i], lp::kLabelUnknown);
    stamp += ros::Duration(0.1);
    valid(cloudMsg(c, "velodyne", stamp), labels, "scan with NaN and Inf returns");
  }

  // tf missing, then arriving: the scan waits in the tf filter and is answered once its frame's
  // transform around its stamp comes.
  {
    stamp += ros::Duration(0.1);
    const int before = classified.count;
    auto m = cloudMsg(scans[1], "velodyne_late", stamp);
    pub.publish(m);
    EXPECT_FALSE(waitFor([&] { return classified.count > before; }, 0.5));
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(mountTransform("base_footprint", "velodyne_late", kSensorHeight, stamp - ros::Duration(0.05)));
    tf.transforms.push_back(mountTransform("base_footprint", "velodyne_late", kSensorHeight, stamp + ros::Duration(0.05)));
    tf_dyn.publish(tf);
    ASSERT_TRUE(waitFor([&] { return classified.count > before; }, 30.0)) << "the late scan was lost";
    ++answered;
    EXPECT_EQ(labelsOf(*classified.get()), expected[1]);
  }

  EXPECT_EQ(answered, 2 * static_cast<int>(scans.size()) + 2);
  EXPECT_EQ(adapter.health().processedCount(), static_cast<uint64_t>(answered));
  EXPECT_EQ(adapter.health().errorCount(), 4u * scans.size());
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "real_scans_test");
  ros::NodeHandle nh;
  const int rc = RUN_ALL_TESTS();
  ros::shutdown();
  return rc;
}
