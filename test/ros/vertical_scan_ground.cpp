// rostest for ladar_perception/VerticalScanGround: the nodelet loads in a manager, classifies
// clouds of every layout, reports bad input and missing tf without dying, and hands its outputs
// to in-process subscribers without a copy (zero-copy).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/vertical_scan_ground_ros.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using ladar_perception::rostest::waitFor;
using Latest = ladar_perception::rostest::Latest<sensor_msgs::PointCloud2>;

constexpr double kSensorHeight = 1.8;

// A revolution of a 32-laser ladar over flat ground with a 1.5 m tall box 8-9 m ahead:
// analytic, so the test knows which return is ground (truth 0) and which obstacle (truth 1).
struct Scene {
  lp::PackedCloud cloud;
  std::vector<uint8_t> truth;
};

Scene makeScene(const lp::CloudLayout& base_layout) {
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> rings;
  Scene s;
  for (int ring = 0; ring < 32; ++ring) {
    const double elev = (-24.0 + ring * 0.7) * M_PI / 180.0;  // all below the horizon
    for (int a = 0; a < 720; ++a) {
      const double az = a * 0.5 * M_PI / 180.0;
      const Eigen::Vector3d dir(std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az),
                                std::sin(elev));
      double range = kSensorHeight / -dir.z();
      uint8_t truth = 0;
      // The box's near face is the plane x = 8 for |y| < 1, from the ground to 1.5 m.
      if (dir.x() > 1e-6) {
        const double t = 8.0 / dir.x();
        const Eigen::Vector3d p = t * dir;
        if (t < range && std::fabs(p.y()) < 1.0 && p.z() + kSensorHeight < 1.5) {
          range = t;
          truth = 1;
        }
      }
      if (range > 60.0) continue;
      pts.push_back((range * dir).cast<float>());
      rings.push_back(ring);
      s.truth.push_back(truth);
    }
  }
  lp::CloudLayout layout = base_layout;
  layout.width = static_cast<uint32_t>(pts.size());
  layout.height = 1;
  layout.row_step = layout.width * layout.point_step;
  s.cloud.layout = layout;
  s.cloud.data.assign(layout.row_step, 0);
  const lp::FieldDesc* ring_field = lp::findField(layout, "ring");
  for (std::size_t i = 0; i < pts.size(); ++i) {
    uint8_t* p = s.cloud.data.data() + i * layout.point_step;
    lp::writeField(p, *lp::findField(layout, "x"), pts[i].x());
    lp::writeField(p, *lp::findField(layout, "y"), pts[i].y());
    lp::writeField(p, *lp::findField(layout, "z"), pts[i].z());
    if (ring_field) lp::writeField(p, *ring_field, rings[i]);
  }
  return s;
}

sensor_msgs::PointCloud2Ptr toMsg(const lp::PackedCloud& cloud, const std::string& frame) {
  return ladar_perception::rostest::cloudMsg(cloud, frame, ros::Time::now());
}

class VerticalScanGroundTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    static tf2_ros::StaticTransformBroadcaster broadcaster;
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time::now();
    t.header.frame_id = "base_footprint";
    t.child_frame_id = "velodyne";
    t.transform.translation.z = kSensorHeight;
    t.transform.rotation.w = 1.0;
    broadcaster.sendTransform(t);
  }
};

// Labels of `classified` by the truth of the scene: fraction of truth-ground labelled ground
// and of truth-obstacle labelled obstacle.
void checkClassified(const sensor_msgs::PointCloud2& classified, const Scene& scene,
                     double* ground_recall, double* obstacle_recall) {
  lp::CloudLayout layout;
  lp::PointCloudView view;
  std::string error;
  ASSERT_TRUE(lp::viewOf(classified, &layout, &view, &error)) << error;
  ASSERT_EQ(view.size(), scene.truth.size());
  const lp::FieldAccessor label = view.field("label");
  const lp::FieldAccessor p = view.field("p_obstacle");
  ASSERT_TRUE(label.valid);
  ASSERT_TRUE(p.valid);
  std::size_t g = 0, g_ok = 0, o = 0, o_ok = 0;
  for (std::size_t i = 0; i < view.size(); ++i) {
    const int l = label.read<int>(view.pointData(i));
    const float prob = p.read<float>(view.pointData(i));
    EXPECT_GE(prob, 0.f);
    EXPECT_LE(prob, 1.f);
    if (scene.truth[i] == 0) {
      ++g;
      g_ok += (l == lp::kLabelGround);
    } else {
      ++o;
      o_ok += (l == lp::kLabelObstacle);
    }
  }
  *ground_recall = static_cast<double>(g_ok) / g;
  *obstacle_recall = static_cast<double>(o_ok) / o;
}

TEST_F(VerticalScanGroundTest, NodeletInManagerClassifiesEveryLayout) {
  ros::NodeHandle nh;
  nodelet::Loader manager(false);  // in-process manager, no services
  nodelet::M_string remap;
  remap["points"] = "/vsg/points";
  remap["ground"] = "/vsg/ground";
  remap["obstacles"] = "/vsg/obstacles";
  remap["classified"] = "/vsg/classified";
  ASSERT_TRUE(manager.load("/vsg/vertical_scan_ground", "ladar_perception/VerticalScanGround",
                           remap, nodelet::V_string()));

  Latest ground, obstacles, classified;
  ros::Subscriber s1 = nh.subscribe("/vsg/ground", 5, &Latest::callback, &ground);
  ros::Subscriber s2 = nh.subscribe("/vsg/obstacles", 5, &Latest::callback, &obstacles);
  ros::Subscriber s3 = nh.subscribe("/vsg/classified", 5, &Latest::callback, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/vsg/points", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));

  // Velodyne's packed 22-byte XYZIRT, PCL's 32-byte aligned XYZI, float64 xyz with an Ouster
  // `channel`, and x,y,z only.
  lp::CloudLayout ouster;
  lp::appendField(&ouster, "x", lp::FieldType::kFloat64);
  lp::appendField(&ouster, "y", lp::FieldType::kFloat64);
  lp::appendField(&ouster, "z", lp::FieldType::kFloat64);
  lp::appendField(&ouster, "intensity", lp::FieldType::kUInt16);
  lp::appendField(&ouster, "channel", lp::FieldType::kUInt8);
  lp::CloudLayout xyz_only;
  lp::appendField(&xyz_only, "x", lp::FieldType::kFloat32);
  lp::appendField(&xyz_only, "y", lp::FieldType::kFloat32);
  lp::appendField(&xyz_only, "z", lp::FieldType::kFloat32);
  const std::vector<std::pair<std::string, lp::CloudLayout>> layouts = {
      {"velodyne XYZIRT", lp::velodyneXYZIRTLayout(0)},
      {"PCL XYZI", lp::pclXYZILayout(0)},
      {"float64 + channel", ouster},
      {"xyz only", xyz_only}};
  for (const auto& named : layouts) {
    SCOPED_TRACE(named.first);
    const Scene scene = makeScene(named.second);
    const int before = classified.count.load();
    sensor_msgs::PointCloud2Ptr msg = toMsg(scene.cloud, "velodyne");
    pub.publish(sensor_msgs::PointCloud2ConstPtr(msg));
    ASSERT_TRUE(waitFor([&] { return classified.count.load() > before; }));
    ASSERT_TRUE(waitFor([&] {
      auto g = ground.get();
      auto o = obstacles.get();
      return g && o && g->header.stamp == msg->header.stamp && o->header.stamp == msg->header.stamp;
    }));
    const auto c = classified.get();
    EXPECT_EQ(c->header.frame_id, "velodyne");
    EXPECT_EQ(c->header.stamp, msg->header.stamp);
    double ground_recall = 0, obstacle_recall = 0;
    checkClassified(*c, scene, &ground_recall, &obstacle_recall);
    EXPECT_GT(ground_recall, 0.98);
    EXPECT_GT(obstacle_recall, 0.9);
    // ground + obstacles are the labelled subsets, with the input's layout.
    const auto g = ground.get();
    const auto o = obstacles.get();
    EXPECT_EQ(g->point_step, msg->point_step);
    EXPECT_EQ(g->fields.size(), msg->fields.size());
    EXPECT_LE(g->width + o->width, msg->width);
    EXPECT_GT(g->width, msg->width / 2);
    EXPECT_GT(o->width, 0u);
  }
  manager.clear();
}

TEST_F(VerticalScanGroundTest, ZeroCopyToInProcessSubscribers) {
  ros::NodeHandle nh("zc");
  ros::NodeHandle pnh("zc/vertical_scan_ground");
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Latest classified_a, classified_b;
  ros::Subscriber sa = nh.subscribe("classified", 5, &Latest::callback, &classified_a);
  ros::NodeHandle other("zc");
  ros::Subscriber sb = other.subscribe("classified", 5, &Latest::callback, &classified_b);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));

  const Scene scene = makeScene(lp::velodyneXYZIRTLayout(0));
  sensor_msgs::PointCloud2Ptr msg = toMsg(scene.cloud, "velodyne");
  sensor_msgs::PointCloud2ConstPtr published(msg);
  pub.publish(published);
  ASSERT_TRUE(waitFor([&] { return classified_a.count > 0 && classified_b.count > 0; }));
  // The adapter got the very message we published (no copy on the way in) ...
  EXPECT_EQ(adapter.lastInputAddress(), static_cast<const void*>(published.get()));
  // ... and every in-process subscriber got the very message it published (no serialisation).
  const auto sent = adapter.lastClassified();
  ASSERT_TRUE(sent);
  EXPECT_EQ(classified_a.get().get(), sent.get());
  EXPECT_EQ(classified_b.get().get(), sent.get());
}

TEST_F(VerticalScanGroundTest, MissingTfIsReportedNotFatal) {
  ros::NodeHandle nh("tf_missing");
  ros::NodeHandle pnh("tf_missing/vertical_scan_ground");
  pnh.setParam("tf_tolerance", 0.05);
  pnh.setParam("queue_size", 3);
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Latest classified;
  ros::Subscriber s = nh.subscribe("classified", 5, &Latest::callback, &classified);
  std::mutex diag_mutex;
  std::string diag_text;
  ros::Subscriber d = ros::NodeHandle().subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 20, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(diag_mutex);
        for (const auto& st : m->status) {
          for (const auto& kv : st.values) {
            if (kv.key == "errors: missing tf") diag_text = kv.value;
          }
        }
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));
  const Scene scene = makeScene(lp::velodyneXYZIRTLayout(0));
  // A stream of scans whose frame tf never knows: each one that falls out of the tf filter's
  // queue (queue_size 3) is counted and reported.
  for (int i = 0; i < 6; ++i) {
    pub.publish(sensor_msgs::PointCloud2ConstPtr(toMsg(scene.cloud, "no_such_frame")));
    ros::WallDuration(0.05).sleep();
  }
  EXPECT_TRUE(waitFor([&] { return adapter.health().errorCount("missing tf") >= 1; }));
  EXPECT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(diag_mutex);
    return !diag_text.empty() && diag_text != "0";
  }));
  EXPECT_EQ(classified.count.load(), 0);
  // A valid scan afterwards is still processed.
  pub.publish(sensor_msgs::PointCloud2ConstPtr(toMsg(scene.cloud, "velodyne")));
  EXPECT_TRUE(waitFor([&] { return classified.count.load() == 1; }));
}

TEST_F(VerticalScanGroundTest, BadCloudsAreRejectedAndValidOnesStillProcessed) {
  ros::NodeHandle nh("bad");
  ros::NodeHandle pnh("bad/vertical_scan_ground");
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Latest classified;
  ros::Subscriber s = nh.subscribe("classified", 50, &Latest::callback, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 50);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));
  const Scene scene = makeScene(lp::velodyneXYZIRTLayout(0));

  auto truncated = toMsg(scene.cloud, "velodyne");
  truncated->data.resize(truncated->data.size() / 2);
  auto small_step = toMsg(scene.cloud, "velodyne");
  small_step->point_step = 8;
  auto no_z = toMsg(scene.cloud, "velodyne");
  no_z->fields.erase(no_z->fields.begin() + 2);
  auto int_x = toMsg(scene.cloud, "velodyne");
  int_x->fields[0].datatype = sensor_msgs::PointField::INT32;
  int bad = 0;
  for (const auto& m : {truncated, small_step, no_z, int_x}) {
    pub.publish(sensor_msgs::PointCloud2ConstPtr(m));
    ++bad;
    ros::WallDuration(0.02).sleep();
  }
  // Each kind is counted under its own name (so each is reported once per throttle period).
  EXPECT_TRUE(waitFor([&] { return adapter.health().errorCount() == static_cast<uint64_t>(bad); }));
  EXPECT_EQ(adapter.health().errorCount("unreadable cloud (truncated data)"), 1u);
  EXPECT_EQ(adapter.health().errorCount("unreadable cloud (field outside point_step)"), 1u);
  EXPECT_EQ(adapter.health().errorCount("unreadable cloud (missing x/y/z)"), 1u);
  EXPECT_EQ(adapter.health().errorCount("unreadable cloud (bad x/y/z datatype)"), 1u);

  // Empty, NaN-only and organised clouds with NaN are valid input: labelled, published.
  lp::PackedCloud empty;
  empty.layout = lp::velodyneXYZIRTLayout(0);
  auto empty_msg = toMsg(empty, "velodyne");
  lp::PackedCloud nan_cloud = scene.cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < nan_cloud.size(); ++i) {
    lp::writeField(nan_cloud.data.data() + i * nan_cloud.layout.point_step,
                   *lp::findField(nan_cloud.layout, "x"), nan);
  }
  auto nan_msg = toMsg(nan_cloud, "velodyne");
  lp::PackedCloud organised = scene.cloud;
  organised.layout.width = 720;
  organised.layout.height = static_cast<uint32_t>(scene.cloud.size() / 720);
  organised.layout.row_step = 720 * organised.layout.point_step;
  organised.data.resize(static_cast<std::size_t>(organised.layout.row_step) * organised.layout.height);
  for (std::size_t i = 0; i < organised.size(); i += 7) {
    lp::writeField(organised.data.data() + i * organised.layout.point_step,
                   *lp::findField(organised.layout, "z"), nan);
  }
  auto organised_msg = toMsg(organised, "velodyne");
  const int before = classified.count.load();
  for (const auto& m : {empty_msg, nan_msg, organised_msg}) {
    pub.publish(sensor_msgs::PointCloud2ConstPtr(m));
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return classified.count.load() == before + 3; }));
  const auto last = classified.get();
  EXPECT_EQ(last->width, 720u);
  EXPECT_EQ(last->height, organised.layout.height);
  lp::CloudLayout layout;
  lp::PointCloudView view;
  std::string error;
  ASSERT_TRUE(lp::viewOf(*last, &layout, &view, &error)) << error;
  const lp::FieldAccessor label = view.field("label");
  for (std::size_t i = 0; i < view.size(); i += 7) {
    EXPECT_EQ(label.read<int>(view.pointData(i)), lp::kLabelUnknown) << i;  // NaN returns
  }
}

// dynamic_reconfigure: a threshold given as a parameter at start-up survives the method's
// settings; a new threshold takes effect on the next scan; choosing another method loads that
// method's settings into every threshold.
double reconfigure(const std::string& node, const std::string& name, double value, bool set,
                   const std::string& method = "") {
  dynamic_reconfigure::Reconfigure srv;
  if (set) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.doubles.push_back(p);
  }
  if (!method.empty()) {
    dynamic_reconfigure::StrParameter m;
    m.name = "method";
    m.value = method;
    srv.request.config.strs.push_back(m);
  }
  EXPECT_TRUE(ros::service::call(node + "/set_parameters", srv));
  for (const auto& d : srv.response.config.doubles) {
    if (d.name == name) return d.value;
  }
  ADD_FAILURE() << name << " not in the reconfigure response";
  return NAN;
}

TEST_F(VerticalScanGroundTest, DynamicReconfigureTakesEffectOnTheNextScan) {
  ros::NodeHandle nh;
  const std::string node = "/dyn/vertical_scan_ground";
  ros::param::set(node + "/gnd_error_max_base", 0.27);  // explicit at start-up (the default is 0.22)
  nodelet::Loader manager(false);
  nodelet::M_string remap;
  remap["points"] = "/dyn/points";
  remap["obstacles"] = "/dyn/obstacles";
  remap["classified"] = "/dyn/classified";
  ASSERT_TRUE(manager.load(node, "ladar_perception/VerticalScanGround", remap, nodelet::V_string()));
  ASSERT_TRUE(ros::service::waitForService(node + "/set_parameters", 10000));
  EXPECT_DOUBLE_EQ(reconfigure(node, "gnd_error_max_base", 0, false), 0.27);

  Latest obstacles;
  ros::Subscriber s = nh.subscribe("/dyn/obstacles", 5, &Latest::callback, &obstacles);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/dyn/points", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && s.getNumPublishers() > 0; }));
  const Scene scene = makeScene(lp::velodyneXYZIRTLayout(0));
  const auto obstaclesOfOneScan = [&]() -> std::size_t {
    const int before = obstacles.count.load();
    pub.publish(sensor_msgs::PointCloud2ConstPtr(toMsg(scene.cloud, "velodyne")));
    if (!waitFor([&] { return obstacles.count.load() > before; })) return 0;
    const auto m = obstacles.get();
    return static_cast<std::size_t>(m->width) * m->height;
  };
  EXPECT_GT(obstaclesOfOneScan(), 100u);
  // P(obstacle) never exceeds 1: with that threshold nothing is an obstacle.
  EXPECT_DOUBLE_EQ(reconfigure(node, "obstacle_threshold", 1.0, true), 1.0);
  EXPECT_EQ(obstaclesOfOneScan(), 0u);
  EXPECT_DOUBLE_EQ(reconfigure(node, "obstacle_threshold", 0.5, true), 0.5);
  EXPECT_GT(obstaclesOfOneScan(), 100u);
  // Another method: its settings replace every threshold, the explicit one too.
  const double thesis_base = lp::verticalScanThesisParams().tolerances.gnd_error_max_base;
  ASSERT_NE(thesis_base, 0.27);
  EXPECT_NEAR(reconfigure(node, "gnd_error_max_base", 0, false, "thesis"), thesis_base, 1e-6);
  EXPECT_GT(obstaclesOfOneScan(), 100u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vertical_scan_ground_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
