// rostest of the DriftMonitor nodelet: two simulated HDL-64Es (datasheet noise) driven back and
// forth along the thesis world at sim time, one scan per sensor every 2 s of driving. The
// monitor stays OK while the target sits on its configured mount and publishes its re-estimate;
// knocked 1.25 cm sideways (between the 1 cm warning and the 1.5 cm error thresholds) it warns
// and does not raise ERROR; knocked to 2.5 cm it reaches ERROR within 30 s of driving, and the
// status names the offset.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "ladar_perception/calibration/experiment.h"

namespace cal = ladar_perception::calibration;
namespace sim = ladar_perception::sim;

namespace {

sensor_msgs::PointCloud2Ptr cloudMessage(const cal::PointVector& points, const std::string& frame,
                                         const ros::Time& stamp) {
  sensor_msgs::PointCloud2Ptr msg(new sensor_msgs::PointCloud2);
  msg->header.frame_id = frame;
  msg->header.stamp = stamp;
  sensor_msgs::PointCloud2Modifier mod(*msg);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(points.size());
  sensor_msgs::PointCloud2Iterator<float> x(*msg, "x"), y(*msg, "y"), z(*msg, "z");
  for (const Eigen::Vector3f& p : points) {
    *x = p.x();
    *y = p.y();
    *z = p.z();
    ++x, ++y, ++z;
  }
  return msg;
}

geometry_msgs::TransformStamped transform(const Eigen::Isometry3d& t, const std::string& parent,
                                          const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped m = tf2::eigenToTransform(t);
  m.header.stamp = stamp;
  m.header.frame_id = parent;
  m.child_frame_id = child;
  return m;
}

struct Observed {
  double time;        // sim time of the status [s]
  std::string level;  // "drift level"
  std::string summary;
};

TEST(DriftMonitorRostest, StaysOkThenWarnsThenReportsABumpAsError) {
  ros::NodeHandle nh;
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  ros::Publisher ref_pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_ref/points", 5);
  ros::Publisher target_pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_target/points", 5);
  std::mutex mutex;
  std::vector<Observed> statuses;
  std::atomic<int> estimates{0};
  std::string estimate_child;
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) {
          if (s.name.find("drift monitor") == std::string::npos) continue;
          Observed o{ros::Time::now().toSec(), "", s.message};
          for (const auto& kv : s.values) {
            if (kv.key == "drift level") o.level = kv.value;
          }
          std::lock_guard<std::mutex> lock(mutex);
          statuses.push_back(o);
        }
      });
  ros::Subscriber estimate_sub = nh.subscribe<geometry_msgs::TransformStamped>(
      "/drift_monitor/estimate", 10, [&](const geometry_msgs::TransformStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        estimate_child = m->child_frame_id;
        ++estimates;
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();

  sim::World world;
  std::string error;
  ASSERT_TRUE(sim::makeStandardWorld("thesis", 2, &world, &error)) << error;
  cal::PairSetup pair;
  ASSERT_TRUE(cal::pairFromName("velodyne-velodyne", &pair, &error)) << error;

  double t = 100.0;  // sim time [s]
  rosgraph_msgs::Clock clock;
  clock.clock.fromSec(t);
  for (int i = 0; i < 20 && clock_pub.getNumSubscribers() == 0; ++i) ros::WallDuration(0.1).sleep();
  clock_pub.publish(clock);
  ros::WallDuration(0.5).sleep();
  // The configured extrinsics, as the vehicle's URDF would give them.
  tf2_ros::StaticTransformBroadcaster statics;
  statics.sendTransform(std::vector<geometry_msgs::TransformStamped>{
      transform(cal::toIsometry(pair.reference.extrinsic), "base_link", "velodyne_ref", ros::Time(t)),
      transform(cal::toIsometry(pair.target.extrinsic), "base_link", "velodyne_target", ros::Time(t))});
  tf2_ros::TransformBroadcaster broadcaster;
  for (int i = 0; i < 50 && (ref_pub.getNumSubscribers() == 0 || target_pub.getNumSubscribers() == 0); ++i) {
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_GT(target_pub.getNumSubscribers(), 0u);

  // Drive time [s]: OK until 24 s, 1.25 cm off until 60 s, then 2.5 cm off.
  const double start = t, bump_at = 24.0, second_bump_at = 60.0, duration = 96.0;
  cal::SensorSetup target = pair.target;
  cal::PointVector points;
  for (int step = 0; step * 2.0 <= duration; ++step) {
    const double drive_t = step * 2.0;
    t = start + drive_t;
    clock.clock.fromSec(t);
    clock_pub.publish(clock);
    const double off = drive_t >= second_bump_at ? 0.025 : drive_t >= bump_at ? 0.0125 : 0.0;
    target.extrinsic = pair.target.extrinsic + cal::makePose(0, off, 0, 0, 0, 0);
    // Back and forth along the world's drive at 1.5 m/s (the unit test's drive).
    const double x = -30.0 + std::fmod(1.5 * drive_t, 60.0);
    const Eigen::Isometry3d vehicle = world.vehiclePose(x, 1.2 * std::sin(0.25 * x), 0.3 * std::cos(0.25 * x));
    broadcaster.sendTransform(transform(vehicle, "odom", "base_link", ros::Time(t)));
    ASSERT_TRUE(cal::simulateSensor(world, pair.reference, vehicle, sim::NoiseProfile::kDatasheet,
                                    100 + step, &points, &error));
    ref_pub.publish(cloudMessage(points, "velodyne_ref", ros::Time(t)));
    ASSERT_TRUE(cal::simulateSensor(world, target, vehicle, sim::NoiseProfile::kDatasheet,
                                    900 + step, &points, &error));
    target_pub.publish(cloudMessage(points, "velodyne_target", ros::Time(t)));
    // Half a second of wall time per 2 s of driving (a check takes ~0.5 s CPU every 4 s),
    // with the clock ticking so that tf and the diagnostics see time pass.
    for (int k = 1; k <= 5; ++k) {
      ros::WallDuration(0.1).sleep();
      clock.clock.fromSec(t + 0.3 * k);
      clock_pub.publish(clock);
    }
  }
  ros::WallDuration(2.0).sleep();

  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_FALSE(statuses.empty()) << "no drift monitor status on /diagnostics";
  EXPECT_GT(estimates.load(), 5);
  EXPECT_EQ(estimate_child, "velodyne_target");
  double first_warn = -1, first_error = -1;
  int ok_before = 0;
  for (const Observed& o : statuses) {
    const double drive_t = o.time - start;
    if (drive_t < bump_at) {
      EXPECT_TRUE(o.level == "OK" || o.level == "UNKNOWN") << "at " << drive_t << " s: " << o.level
                                                           << " (" << o.summary << ")";
      ok_before += o.level == "OK";
    } else if (drive_t < second_bump_at + 2.0) {  // the first check after the second bump
      EXPECT_NE(o.level, "ERROR") << "at " << drive_t << " s, 1.25 cm off: " << o.summary;
      if (o.level == "WARN" && first_warn < 0) {
        first_warn = drive_t;
        EXPECT_NE(o.summary.find("y "), std::string::npos) << o.summary;
      }
    } else if (o.level == "ERROR" && first_error < 0) {
      first_error = drive_t;
      EXPECT_NE(o.summary.find("y "), std::string::npos) << o.summary;
    }
  }
  EXPECT_GT(ok_before, 0) << "the monitor never reached OK before the bump";
  ASSERT_GE(first_warn, 0.0) << "no WARN 1.25 cm off";
  EXPECT_LE(first_warn - bump_at, 30.0);
  ASSERT_GE(first_error, 0.0) << "no ERROR 2.5 cm off";
  EXPECT_LE(first_error - second_bump_at, 30.0);
  std::printf("WARN %.1f s of driving after the 1.25 cm bump, ERROR %.1f s after the 2.5 cm one\n",
              first_warn - bump_at, first_error - second_bump_at);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "drift_monitor_rostest");
  return RUN_ALL_TESTS();
}
