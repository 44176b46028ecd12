// rostest for ladar_perception/HoughGround: the nodelet loads in a manager, fits the ground of
// LaserScans through tf, publishes ground/obstacles/classified clouds, the ground line marker
// and the fit; NaN/Inf scans, bad scan geometry and missing tf are reported without dying.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/Marker.h>

#include "../unit/ground_hough_scene.h"
#include "ladar_perception/HoughGroundFit.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/hough_ground_ros.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using ladar_perception::rostest::waitFor;
using ladar_perception::rostest::Latest;

constexpr double kHeight = 1.2;

// A vertical SICK scan over flat ground with a car 8-12 m ahead (1.4 m tall), truth per beam.
struct Scan {
  sensor_msgs::LaserScanPtr msg;
  std::vector<uint8_t> truth;  // 0 ground, 1 obstacle, 2 no return
  std::vector<float> height;   // of each return above the ground
};

Scan makeScan(const std::string& frame) {
  hough_test::VerticalScene scene;
  scene.sensor_height = kHeight;
  scene.addGroundLine(0.0, 0.0);
  scene.addBox(8.0, 12.0, 0.0, 1.4);
  Scan s;
  s.msg.reset(new sensor_msgs::LaserScan);
  s.msg->header.frame_id = frame;
  s.msg->header.stamp = ros::Time::now();
  s.msg->angle_min = static_cast<float>(-M_PI / 2);
  s.msg->angle_max = static_cast<float>(M_PI / 2);
  s.msg->angle_increment = static_cast<float>(M_PI / 360);
  s.msg->range_min = 0.5f;
  s.msg->range_max = 80.f;
  scene.scan(-M_PI / 2, M_PI / 360, 361, &s.msg->ranges, &s.truth);
  for (int k = 0; k < 361; ++k) {
    const double a = -M_PI / 2 + k * M_PI / 360;
    s.height.push_back(static_cast<float>(kHeight + s.msg->ranges[k] * std::sin(a)));
  }
  return s;
}

class HoughGroundTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    static tf2_ros::StaticTransformBroadcaster broadcaster;
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time::now();
    t.header.frame_id = "base_footprint";
    t.child_frame_id = "sick_vertical";
    t.transform.translation.x = 2.0;  // above the front bumper: the adapter takes the point under it
    t.transform.translation.z = kHeight;
    // Rolled +90 degrees about x: the scan plane is the vertical x-z plane, sensor y up.
    t.transform.rotation.x = std::sin(M_PI / 4);
    t.transform.rotation.w = std::cos(M_PI / 4);
    broadcaster.sendTransform(t);
  }
};

struct Outputs {
  Latest<sensor_msgs::PointCloud2> ground, obstacles, classified;
  Latest<visualization_msgs::Marker> line;
  Latest<lp::HoughGroundFit> fit;
  std::vector<ros::Subscriber> subs;
  void subscribe(ros::NodeHandle& nh, const std::string& ns) {
    subs.push_back(nh.subscribe(ns + "ground", 5, &Latest<sensor_msgs::PointCloud2>::callback, &ground));
    subs.push_back(nh.subscribe(ns + "obstacles", 5, &Latest<sensor_msgs::PointCloud2>::callback, &obstacles));
    subs.push_back(nh.subscribe(ns + "classified", 5, &Latest<sensor_msgs::PointCloud2>::callback, &classified));
    subs.push_back(nh.subscribe(ns + "ground_line", 5, &Latest<visualization_msgs::Marker>::callback, &line));
    subs.push_back(nh.subscribe(ns + "ground_fit", 5, &Latest<lp::HoughGroundFit>::callback, &fit));
  }
};

std::vector<int> labelsOf(const sensor_msgs::PointCloud2& classified) {
  lp::CloudLayout layout;
  lp::PointCloudView view;
  std::string error;
  std::vector<int> labels;
  if (!lp::viewOf(classified, &layout, &view, &error)) return labels;
  const lp::FieldAccessor label = view.field("label");
  const lp::FieldAccessor p = view.field("p_obstacle");
  if (!label.valid || !p.valid) return labels;
  for (std::size_t i = 0; i < view.size(); ++i) labels.push_back(label.read<int>(view.pointData(i)));
  return labels;
}

TEST_F(HoughGroundTest, NodeletFitsTheGroundThroughTf) {
  ros::NodeHandle nh;
  nodelet::Loader manager(false);
  nodelet::M_string remap;
  for (const char* topic : {"scan", "ground", "obstacles", "classified", "ground_line", "ground_fit"}) {
    remap[topic] = std::string("/hg/") + topic;
  }
  ASSERT_TRUE(manager.load("/hg/hough_ground", "ladar_perception/HoughGround", remap, nodelet::V_string()));
  Outputs out;
  out.subscribe(nh, "/hg/");
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("/hg/scan", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));

  const Scan scan = makeScan("sick_vertical");
  pub.publish(sensor_msgs::LaserScanConstPtr(scan.msg));
  ASSERT_TRUE(waitFor([&] {
    return out.classified.count > 0 && out.ground.count > 0 && out.obstacles.count > 0 &&
           out.fit.count > 0 && out.line.count > 0;
  }));
  const auto fit = out.fit.get();
  EXPECT_EQ(fit->header.frame_id, "base_footprint");
  EXPECT_EQ(fit->header.stamp, scan.msg->header.stamp);
  EXPECT_EQ(fit->scan_frame, "sick_vertical");
  ASSERT_TRUE(fit->valid);
  EXPECT_NEAR(fit->ground, 0.0, 1e-3);
  EXPECT_NEAR(fit->slope, 0.0, 1e-4);
  EXPECT_NEAR(fit->direction.x, 1.0, 1e-6);
  EXPECT_GT(fit->inliers, 50);
  EXPECT_GT(fit->margin, 0.5);
  EXPECT_GT(fit->obstacle_returns, 5);

  const auto classified = out.classified.get();
  EXPECT_EQ(classified->header.frame_id, "sick_vertical");
  EXPECT_EQ(classified->width, 361u);
  const std::vector<int> labels = labelsOf(*classified);
  ASSERT_EQ(labels.size(), 361u);
  int car = 0;
  for (int k = 0; k < 361; ++k) {
    if (scan.truth[k] == 2) {
      EXPECT_EQ(labels[k], lp::kLabelUnknown) << k;
    }
    if (scan.truth[k] == 0) {
      EXPECT_EQ(labels[k], lp::kLabelGround) << k;
    }
    if (scan.truth[k] == 1 && scan.height[k] > 0.25f) {
      EXPECT_EQ(labels[k], lp::kLabelObstacle) << k;
      ++car;
    }
  }
  EXPECT_GT(car, 5);
  EXPECT_EQ(static_cast<int>(out.ground.get()->width), fit->ground_returns);
  EXPECT_EQ(static_cast<int>(out.obstacles.get()->width), fit->obstacle_returns);

  const auto line = out.line.get();
  EXPECT_EQ(line->header.frame_id, "base_footprint");
  EXPECT_EQ(line->type, visualization_msgs::Marker::LINE_STRIP);
  EXPECT_EQ(line->action, visualization_msgs::Marker::ADD);
  ASSERT_EQ(line->points.size(), 2u);
  EXPECT_NEAR(line->points[0].z, 0.0, 1e-3);
  EXPECT_LT(line->points[0].x, line->points[1].x);

  // A scan without a single usable return: every return unknown, no line, still published.
  sensor_msgs::LaserScanPtr empty(new sensor_msgs::LaserScan(*scan.msg));
  empty->header.stamp = ros::Time::now();
  const float inf = std::numeric_limits<float>::infinity();
  for (std::size_t k = 0; k < empty->ranges.size(); ++k) {
    empty->ranges[k] = k % 3 == 0 ? std::numeric_limits<float>::quiet_NaN()
                                  : (k % 3 == 1 ? inf : 100.f);  // beyond range_max
  }
  const int before = out.fit.count;
  pub.publish(sensor_msgs::LaserScanConstPtr(empty));
  ASSERT_TRUE(waitFor([&] { return out.fit.count > before && out.fit.get()->header.stamp == empty->header.stamp; }));
  EXPECT_FALSE(out.fit.get()->valid);
  EXPECT_EQ(out.fit.get()->unknown_returns, 361);
  ASSERT_TRUE(waitFor([&] { return out.line.get()->header.stamp == empty->header.stamp; }));
  EXPECT_EQ(out.line.get()->action, visualization_msgs::Marker::DELETE);
  manager.clear();
}

TEST_F(HoughGroundTest, BadScansAreReportedAndValidOnesStillProcessed) {
  ros::NodeHandle nh("bad");
  ros::NodeHandle pnh("bad/hough_ground");
  lp::HoughGroundRos adapter(nh, pnh);
  Outputs out;
  out.subscribe(nh, "");
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("scan", 20);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));
  const Scan scan = makeScan("sick_vertical");
  auto nan_increment = boost::make_shared<sensor_msgs::LaserScan>(*scan.msg);
  nan_increment->angle_increment = std::numeric_limits<float>::quiet_NaN();
  auto bad_limits = boost::make_shared<sensor_msgs::LaserScan>(*scan.msg);
  bad_limits->range_min = 10.f;
  bad_limits->range_max = 1.f;
  auto spinning = boost::make_shared<sensor_msgs::LaserScan>(*scan.msg);
  spinning->angle_increment = 0.5f;  // 180 rad
  auto short_intensities = boost::make_shared<sensor_msgs::LaserScan>(*scan.msg);
  short_intensities->intensities.assign(10, 1.f);  // ignored, not read out of bounds
  for (const auto& m : {nan_increment, bad_limits, spinning}) {
    pub.publish(sensor_msgs::LaserScanConstPtr(m));
    ros::WallDuration(0.02).sleep();
  }
  EXPECT_TRUE(waitFor([&] { return adapter.health().errorCount("unreadable scan") == 3u; }));
  EXPECT_EQ(out.classified.count.load(), 0);
  pub.publish(sensor_msgs::LaserScanConstPtr(short_intensities));
  ASSERT_TRUE(waitFor([&] { return out.classified.count.load() == 1 && out.fit.count.load() == 1; }));
  EXPECT_TRUE(out.fit.get()->valid);
  EXPECT_EQ(adapter.lastClassified().get(), out.classified.get().get());  // in-process: no copy
}

TEST_F(HoughGroundTest, MissingTfIsReportedNotFatal) {
  ros::NodeHandle nh("tf_missing");
  ros::NodeHandle pnh("tf_missing/hough_ground");
  pnh.setParam("tf_tolerance", 0.05);
  lp::HoughGroundRos adapter(nh, pnh);
  Outputs out;
  out.subscribe(nh, "");
  std::mutex diag_mutex;
  std::string diag_text;
  ros::Subscriber d = ros::NodeHandle().subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 20, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(diag_mutex);
        for (const auto& st : m->status) {
          if (st.name.find("hough ground") == std::string::npos) continue;
          for (const auto& kv : st.values) {
            if (kv.key == "errors: missing tf") diag_text = kv.value;
          }
        }
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("scan", 20);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));
  // The tf filter holds scans waiting for their transform and drops the oldest when its queue
  // (queue_size, 15) overflows: at 75 Hz a scan waits at most 0.2 s.
  for (int i = 0; i < 18; ++i) {
    pub.publish(sensor_msgs::LaserScanConstPtr(makeScan("no_such_frame").msg));
    ros::WallDuration(0.05).sleep();
  }
  EXPECT_TRUE(waitFor([&] { return adapter.health().errorCount("missing tf") >= 1; }));
  EXPECT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(diag_mutex);
    return !diag_text.empty() && diag_text != "0";
  }));
  EXPECT_EQ(out.classified.count.load(), 0);
  pub.publish(sensor_msgs::LaserScanConstPtr(makeScan("sick_vertical").msg));
  EXPECT_TRUE(waitFor([&] { return out.classified.count.load() == 1; }));
}

// The thesis settings by name at start-up: the line is an accumulator cell centre (no
// refinement), a threshold given explicitly still overrides the method's.
TEST_F(HoughGroundTest, ThesisMethodByParameter) {
  ros::NodeHandle nh("thesis");
  ros::NodeHandle pnh("thesis/hough_ground");
  pnh.setParam("method", "thesis");
  pnh.setParam("min_inliers", 7);
  lp::HoughGroundRos adapter(nh, pnh);
  Outputs out;
  out.subscribe(nh, "");
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("scan", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));
  hough_test::VerticalScene scene;
  scene.sensor_height = kHeight;
  scene.addGroundLine(0.0173, 0.0);
  sensor_msgs::LaserScanPtr msg(new sensor_msgs::LaserScan(*makeScan("sick_vertical").msg));
  std::vector<uint8_t> truth;
  scene.scan(-M_PI / 2, M_PI / 360, 361, &msg->ranges, &truth);
  pub.publish(sensor_msgs::LaserScanConstPtr(msg));
  ASSERT_TRUE(waitFor([&] { return out.fit.count.load() == 1; }));
  const auto fit = out.fit.get();
  ASSERT_TRUE(fit->valid);
  // A cell centre of the default grid (-1 m + k * 0.04 m), not the exact 0.0173.
  const double k = (fit->ground + 1.0) / 0.04;
  EXPECT_NEAR(k, std::round(k), 1e-3);
  // The explicit threshold survived the method's settings.
  int min_inliers = 0;
  ASSERT_TRUE(pnh.getParam("min_inliers", min_inliers));
  EXPECT_EQ(min_inliers, 7);
  bool refine = true;
  ASSERT_TRUE(pnh.getParam("refine", refine));
  EXPECT_FALSE(refine);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "hough_ground_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
