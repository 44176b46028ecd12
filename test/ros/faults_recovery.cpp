// rostest: faults around the perception nodelets, each with a clear answer and no hang.
//  - tf late (the scan waits in the tf filter and is processed when its transform arrives),
//    never (the scan is dropped and counted as missing tf), and jumping back in time (a bag
//    that loops: old scans are dropped and counted, new ones are processed again);
//  - the nodelet manager restarted in the middle of a stream: outputs resume;
//  - the calibration service called with no data, with too little data, with an initial guess
//    far outside the search region or not a rotation: an answer within a time limit.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <thread>

#include <geometry_msgs/TransformStamped.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/Calibrate.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ros/calibration_ros.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/vertical_scan_ground_ros.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using ladar_perception::rostest::waitFor;
using ladar_perception::rostest::Counter;
using ladar_perception::rostest::flatCloud;
using ladar_perception::rostest::cloudMsg;
using ladar_perception::rostest::mountTransform;

class Faults : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    static tf2_ros::StaticTransformBroadcaster statics;
    statics.sendTransform({mountTransform("base_footprint", "velodyne", 1.8, ros::Time::now()),
                           mountTransform("odom", "base_link", 0.0, ros::Time::now()),
                           mountTransform("base_link", "velodyne_ref", 1.8, ros::Time::now()),
                           mountTransform("base_link", "velodyne_target", 1.9, ros::Time::now())});
    static ros::AsyncSpinner spinner(4);
    spinner.start();
  }
};

TEST_F(Faults, TfLateNeverAndJumpingBack) {
  ros::NodeHandle nh("tf_faults"), pnh("tf_faults_private");
  pnh.setParam("queue_size", 3);
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Counter classified;
  ros::Subscriber sub = nh.subscribe("classified", 100, &Counter::callback<sensor_msgs::PointCloud2ConstPtr>, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 100);
  // tf through a plain publisher so the test can wait until the adapter's listener is connected
  // (a transform published before that would be lost, which is not the fault under test).
  ros::Publisher tf_pub = ros::NodeHandle().advertise<tf2_msgs::TFMessage>("/tf", 100);
  struct {
    ros::Publisher* pub;
    void sendTransform(const geometry_msgs::TransformStamped& t) {
      tf2_msgs::TFMessage m;
      m.transforms.push_back(t);
      pub->publish(m);
    }
  } tf{&tf_pub};
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && tf_pub.getNumSubscribers() > 0; }));
  const lp::PackedCloud cloud = flatCloud(1600);

  // Late: the scan arrives before any transform of its (moving) frame; it waits in the tf
  // filter and is processed once the transform around its stamp arrives.
  const ros::Time t = ros::Time::now();
  pub.publish(cloudMsg(cloud, "velodyne_moving", t));
  EXPECT_FALSE(waitFor([&] { return classified.count > 0; }, 0.5));
  tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, t - ros::Duration(0.05)));
  tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, t + ros::Duration(0.05)));
  ASSERT_TRUE(waitFor([&] { return classified.count == 1; })) << "the late scan was lost";
  EXPECT_EQ(adapter.health().errorCount("missing tf"), 0u);

  // Never: scans of a frame nobody publishes are dropped (pushed out of the filter's queue of
  // 3) and counted, and the nodelet goes on with valid scans.
  // Paced on the drop count so the subscriber's own queue (3) never overflows unseen; the first
  // three fill the filter and drop nothing, so nothing observable tells that they left the
  // subscriber's queue: they are given time instead (published back to back, the first could
  // still be in that queue when the fourth arrives, and roscpp would drop it silently).
  for (int i = 0; i < 10; ++i) {
    pub.publish(cloudMsg(cloud, "never_published", t + ros::Duration(0.1 * i)));
    if (i < 3) ros::WallDuration(0.3).sleep();
    const uint64_t expected = i >= 3 ? static_cast<uint64_t>(i - 2) : 0u;
    ASSERT_TRUE(waitFor([&] { return adapter.health().errorCount("missing tf") == expected; }, 10.0))
        << "scan " << i << ": " << adapter.health().errorCount("missing tf") << " dropped";
  }
  EXPECT_EQ(adapter.health().errorCount("missing tf"), 7u);
  pub.publish(cloudMsg(cloud, "velodyne", ros::Time::now()));
  ASSERT_TRUE(waitFor([&] { return classified.count == 2; }));

  // Jumping back in time (a bag looping): transforms and scans a minute older than the buffer's
  // latest. tf2 ignores or accepts the old transforms; either way every scan gets an answer
  // (processed, or dropped and counted) and fresh scans are processed afterwards.
  const ros::Time back = t - ros::Duration(60.0);
  const uint64_t missing_before = adapter.health().errorCount("missing tf");
  // Each publication is paced on its answer (or 2 s) so the subscriber's queue never overflows.
  const auto answered = [&] {
    return static_cast<uint64_t>(classified.count) + adapter.health().errorCount("missing tf");
  };
  for (int i = 0; i < 5; ++i) {
    const ros::Time s = back + ros::Duration(0.1 * i);
    tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, s - ros::Duration(0.05)));
    tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, s + ros::Duration(0.05)));
    const uint64_t before_scan = answered();
    pub.publish(cloudMsg(cloud, "velodyne_moving", s));
    waitFor([&] { return answered() > before_scan; }, 2.0);
  }
  // Push any scan still waiting out of the filter's queue with scans of an absent frame.
  for (int i = 0; i < 4; ++i) {
    const uint64_t before_scan = answered();
    pub.publish(cloudMsg(cloud, "never_published", back));
    waitFor([&] { return answered() > before_scan; }, 2.0);
  }
  EXPECT_TRUE(waitFor([&] {
    return static_cast<uint64_t>(classified.count - 2) +
               (adapter.health().errorCount("missing tf") - missing_before) >= 5u;
  })) << classified.count << " processed, "
      << adapter.health().errorCount("missing tf") - missing_before << " dropped";
  const int before = classified.count;
  const ros::Time fresh = ros::Time::now();
  tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, fresh - ros::Duration(0.05)));
  tf.sendTransform(mountTransform("base_footprint", "velodyne_moving", 1.8, fresh + ros::Duration(0.05)));
  pub.publish(cloudMsg(cloud, "velodyne_moving", fresh));
  pub.publish(cloudMsg(cloud, "velodyne", fresh));
  EXPECT_TRUE(waitFor([&] { return classified.count >= before + 2; }));
}

TEST_F(Faults, ManagerRestartedMidStream) {
  ros::NodeHandle nh;
  Counter classified;
  ros::Subscriber sub = nh.subscribe("/restart/classified", 100, &Counter::callback<sensor_msgs::PointCloud2ConstPtr>, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/restart/points", 10);
  const lp::PackedCloud cloud = flatCloud(1600);
  // The bag keeps playing at 20 Hz while the manager goes down and comes back.
  std::atomic<bool> playing{true};
  std::thread player([&] {
    ros::WallRate rate(20.0);
    while (playing && ros::ok()) {
      pub.publish(cloudMsg(cloud, "velodyne", ros::Time::now()));
      rate.sleep();
    }
  });
  nodelet::M_string remap;
  remap["points"] = "/restart/points";
  remap["classified"] = "/restart/classified";
  remap["ground"] = "/restart/ground";
  remap["obstacles"] = "/restart/obstacles";
  for (int run = 0; run < 3; ++run) {
    SCOPED_TRACE(run);
    auto manager = std::make_unique<nodelet::Loader>(false);
    ASSERT_TRUE(manager->load("/restart/vertical_scan_ground", "ladar_perception/VerticalScanGround",
                              remap, nodelet::V_string()));
    const int before = classified.count;
    EXPECT_TRUE(waitFor([&] { return classified.count >= before + 5; }))
        << "no output after (re)start " << run;
    manager.reset();  // the manager goes down in the middle of the stream
  }
  playing = false;
  player.join();
}

ladar_perception::Calibrate::Response callWithin(const std::string& service,
                                                 ladar_perception::Calibrate::Request req,
                                                 double seconds, bool* answered) {
  auto f = std::async(std::launch::async, [service, req]() {
    ladar_perception::Calibrate srv;
    srv.request = req;
    ros::service::call(service, srv);
    return srv.response;
  });
  *answered = f.wait_for(std::chrono::duration<double>(seconds)) == std::future_status::ready;
  return *answered ? f.get() : ladar_perception::Calibrate::Response();
}

TEST_F(Faults, CalibrationServiceAnswersEveryBadRequest) {
  ros::NodeHandle nh("cal_faults"), pnh("cal_faults/calibration");
  pnh.setParam("reference_frame", "velodyne_ref");
  pnh.setParam("target_frame", "velodyne_target");
  pnh.setParam("output_file", "/tmp/ladar_perception_faults_calibration.yaml");
  lp::CalibrationRos adapter(nh, pnh);
  const std::string service = "/cal_faults/calibration/calibrate";
  ASSERT_TRUE(ros::service::waitForService(service, 30000));

  // No data at all.
  bool answered = false;
  ladar_perception::Calibrate::Request req;
  auto res = callWithin(service, req, 60.0, &answered);
  ASSERT_TRUE(answered) << "no answer without data";
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.message.rfind("no data", 0), 0u) << res.message;

  // Too little data: one scan of each sensor.
  ros::Publisher ref = nh.advertise<sensor_msgs::PointCloud2>("reference", 10);
  ros::Publisher tgt = nh.advertise<sensor_msgs::PointCloud2>("target", 10);
  ASSERT_TRUE(waitFor([&] { return ref.getNumSubscribers() > 0 && tgt.getNumSubscribers() > 0; }));
  const lp::PackedCloud cloud = flatCloud(800);
  ref.publish(cloudMsg(cloud, "velodyne_ref", ros::Time::now()));
  tgt.publish(cloudMsg(cloud, "velodyne_target", ros::Time::now()));
  ASSERT_TRUE(waitFor([&] { return adapter.bufferedScans(false) == 1 && adapter.bufferedScans(true) == 1; }));
  res = callWithin(service, req, 90.0, &answered);
  ASSERT_TRUE(answered) << "no answer with one scan each";
  EXPECT_FALSE(res.message.empty());
  // A flat ground alone fixes z, roll and pitch only: whatever the verdict, the answer must
  // say so rather than claim a full calibration.
  if (res.success) {
    EXPECT_FALSE(res.unobservable.empty()) << res.message;
  }

  // An initial guess that is not a rotation.
  req.initial_guess.translation.x = 1.0;
  req.initial_guess.rotation.x = std::nan("");
  res = callWithin(service, req, 60.0, &answered);
  ASSERT_TRUE(answered);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("rotation"), std::string::npos) << res.message;

  // An initial guess a kilometre outside any plausible mount, with a tight search region.
  req.initial_guess = geometry_msgs::Transform();
  req.initial_guess.translation.x = 1000.0;
  req.initial_guess.rotation.w = 1.0;
  req.spread = {0.1, 0.1, 0.1, 0.01, 0.01, 0.01};
  res = callWithin(service, req, 120.0, &answered);
  ASSERT_TRUE(answered) << "no answer for a guess outside the search region";
  EXPECT_FALSE(res.message.empty());

  // A malformed spread.
  req.spread = {1.0, 2.0};
  res = callWithin(service, req, 60.0, &answered);
  ASSERT_TRUE(answered);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("spread"), std::string::npos) << res.message;
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "faults_recovery_test");
  ros::NodeHandle nh;
  const int rc = RUN_ALL_TESTS();
  ros::shutdown();
  return rc;
}
