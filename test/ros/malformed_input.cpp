// rostest: each perception nodelet's adapter (VerticalScanGround, HoughGround, Calibration),
// hosted in this process as a nodelet manager hosts it (multi-threaded spinner), receives more
// than 1,000 malformed messages interleaved with valid ones. The process must stay up, every
// valid scan must still produce its outputs, each kind of bad input must be logged at most once
// per throttle period with the reason, and diagnostics must carry the error counts.
// Pacing waits on the adapters' counters (never on fixed sleeps), so the subscriber queues never
// overflow and every message is accounted for.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <rosgraph_msgs/Log.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ros/calibration_ros.h"
#include "ladar_perception/ros/cloud_conversion.h"
#include "ladar_perception/ros/hough_ground_ros.h"
#include "ladar_perception/ros/vertical_scan_ground_ros.h"
#include "rostest_support.h"

namespace lp = ladar_perception;

namespace {

using ladar_perception::rostest::waitFor;
using ladar_perception::rostest::Counter;
using ladar_perception::rostest::flatCloud;
using ladar_perception::rostest::cloudMsg;

constexpr double kPacingPoll = 0.0005;  // [s] between checks while pacing the message stream
constexpr double kThrottle = 5.0;  // InputHealth's and the calibration's throttle period [s]

// Every /rosout line of this process (the adapters log through it).
struct LogCollector {
  std::mutex mutex;
  std::vector<rosgraph_msgs::Log> lines;
  void callback(const rosgraph_msgs::Log::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    lines.push_back(*m);
  }
  std::vector<std::string> matching(const std::string& needle) {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<std::string> out;
    for (const auto& l : lines) {
      if (l.msg.find(needle) != std::string::npos) out.push_back(l.msg);
    }
    return out;
  }
};

// The latest value of every diagnostics key, by status name.
struct DiagnosticsCollector {
  std::mutex mutex;
  std::map<std::string, std::map<std::string, std::string>> values;
  void callback(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& st : m->status) {
      for (const auto& kv : st.values) values[st.name][kv.key] = kv.value;
    }
  }
  std::string value(const std::string& status_part, const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& st : values) {
      if (st.first.find(status_part) == std::string::npos) continue;
      auto it = st.second.find(key);
      if (it != st.second.end()) return it->second;
    }
    return "";
  }
  // The sum of every key that starts with `key_prefix` (per-kind error counts), or -1 if none.
  long long sum(const std::string& status_part, const std::string& key_prefix) {
    std::lock_guard<std::mutex> lock(mutex);
    long long total = -1;
    for (const auto& st : values) {
      if (st.first.find(status_part) == std::string::npos) continue;
      for (const auto& kv : st.second) {
        if (kv.first.compare(0, key_prefix.size(), key_prefix) != 0) continue;
        total = std::max(total, 0LL) + std::stoll(kv.second);
      }
    }
    return total;
  }
};

// Log lines "<prefix> (<kind>): ..." grouped by kind: how many lines each kind logged.
std::map<std::string, int> linesPerKind(const std::vector<std::string>& lines,
                                        const std::string& prefix) {
  std::map<std::string, int> kinds;
  for (const std::string& l : lines) {
    const std::size_t at = l.find(prefix + " (");
    const std::size_t open = at == std::string::npos ? at : at + prefix.size() + 1;
    const std::size_t close = open == std::string::npos ? open : l.find(')', open);
    ++kinds[close == std::string::npos ? std::string("?") : l.substr(open + 1, close - open - 1)];
  }
  return kinds;
}

enum class CloudFault {
  kPointStepTooSmall,
  kDataTooShort,
  kMissingX,
  kXAsUInt8,
  kZAsUnknownType,
  kRowStepTooSmall,
  kBigEndian,
  kHugeWidthNoData,
  kCount
};
const char* faultName(CloudFault f) {
  static const char* names[] = {"point_step smaller than the fields", "data too short",
                                "x missing", "x of datatype uint8", "z of unknown datatype",
                                "row_step too small", "big-endian", "4e9 points, no data"};
  return names[static_cast<int>(f)];
}

sensor_msgs::PointCloud2Ptr malformedCloud(CloudFault f, const lp::PackedCloud& valid,
                                           const std::string& frame, ros::Time stamp) {
  sensor_msgs::PointCloud2Ptr m = cloudMsg(valid, frame, stamp);
  switch (f) {
    case CloudFault::kPointStepTooSmall: m->point_step = 8; m->row_step = m->width * 8; break;
    case CloudFault::kDataTooShort: m->data.resize(m->data.size() / 2); break;
    case CloudFault::kMissingX: m->fields.erase(m->fields.begin()); break;
    case CloudFault::kXAsUInt8: m->fields[0].datatype = sensor_msgs::PointField::UINT8; break;
    case CloudFault::kZAsUnknownType: m->fields[2].datatype = 42; break;
    case CloudFault::kRowStepTooSmall: m->height = 2; m->width /= 2; m->row_step = 3; break;
    case CloudFault::kBigEndian: m->is_bigendian = true; break;
    case CloudFault::kHugeWidthNoData: m->width = 0xFFFFFFFFu; m->height = 1; m->row_step = 0xFFFFFFFFu; m->data.clear(); break;
    case CloudFault::kCount: break;
  }
  return m;
}

// Valid clouds that are unusual: NaN/Inf points, zero points, stamps going back.
sensor_msgs::PointCloud2Ptr oddValidCloud(int k, const lp::PackedCloud& valid,
                                          const std::string& frame, ros::Time stamp) {
  if (k % 3 == 1) {  // no points at all
    lp::PackedCloud empty;
    empty.layout = lp::velodyneXYZIRTLayout(0);
    return cloudMsg(empty, frame, stamp);
  }
  sensor_msgs::PointCloud2Ptr m = cloudMsg(valid, frame, stamp);
  if (k % 3 == 0) {  // every third point NaN, every fifth +Inf, every seventh -Inf in x or z
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < m->width; ++i) {
      uint8_t* p = m->data.data() + i * m->point_step;
      if (i % 3 == 0) std::memcpy(p + 0, &nan, 4);
      if (i % 5 == 0) std::memcpy(p + 8, &inf, 4);
      if (i % 7 == 0) { const float ninf = -inf; std::memcpy(p + 4, &ninf, 4); }
    }
  } else {  // a bag that loops: the stamp jumps back by a minute
    m->header.stamp = stamp - ros::Duration(60.0);
  }
  return m;
}

class Fixture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    static tf2_ros::StaticTransformBroadcaster broadcaster;
    std::vector<geometry_msgs::TransformStamped> ts;
    auto add = [&](const std::string& parent, const std::string& child, double z, double roll) {
      geometry_msgs::TransformStamped t;
      t.header.stamp = ros::Time::now();
      t.header.frame_id = parent;
      t.child_frame_id = child;
      t.transform.translation.z = z;
      tf2::Quaternion q;
      q.setRPY(roll, 0, 0);
      t.transform.rotation.x = q.x();
      t.transform.rotation.y = q.y();
      t.transform.rotation.z = q.z();
      t.transform.rotation.w = q.w();
      ts.push_back(t);
    };
    add("base_footprint", "velodyne", 1.8, 0.0);
    add("base_footprint", "sick", 1.0, M_PI / 2);
    add("odom", "base_link", 0.0, 0.0);
    add("base_link", "velodyne_ref", 1.8, 0.0);
    add("base_link", "velodyne_target", 1.9, 0.0);
    broadcaster.sendTransform(ts);
    spinner_ = new ros::AsyncSpinner(4);  // a manager's worker threads
    spinner_->start();
  }
  void SetUp() override {
    ros::NodeHandle nh;
    log_sub_ = nh.subscribe("/rosout", 10000, &LogCollector::callback, &logs_);
    diag_sub_ = nh.subscribe("/diagnostics", 100, &DiagnosticsCollector::callback, &diags_);
    start_ = ros::WallTime::now();
  }
  // Most lines that a throttle of kThrottle allows since the test began (one at once, one per
  // period after), plus one for a period boundary crossed while counting.
  int allowedLines() const {
    return static_cast<int>((ros::WallTime::now() - start_).toSec() / kThrottle) + 2;
  }
  static ros::AsyncSpinner* spinner_;
  LogCollector logs_;
  DiagnosticsCollector diags_;
  ros::Subscriber log_sub_, diag_sub_;
  ros::WallTime start_;
};
ros::AsyncSpinner* Fixture::spinner_ = nullptr;

TEST_F(Fixture, VerticalScanGroundSurvivesMalformedClouds) {
  ros::NodeHandle nh("vsg"), pnh("vsg_private");
  lp::VerticalScanGroundRos adapter(nh, pnh);
  Counter classified, ground;
  ros::Subscriber s1 = nh.subscribe("classified", 1000, &Counter::callback<sensor_msgs::PointCloud2ConstPtr>, &classified);
  ros::Subscriber s2 = nh.subscribe("ground", 1000, &Counter::callback<sensor_msgs::PointCloud2ConstPtr>, &ground);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 1000);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && classified.count == 0; }));

  const lp::PackedCloud valid = flatCloud(3200);
  int bad = 0, good = 0, unknown_frame = 0;
  const ros::Time t0 = ros::Time::now();
  for (int i = 0; bad < 1050; ++i) {
    const ros::Time stamp = t0 + ros::Duration(0.1 * i);
    sensor_msgs::PointCloud2ConstPtr m;
    std::string what = "valid";
    if (i % 10 == 0) {
      m = cloudMsg(valid, "velodyne", stamp);
      ++good;
    } else if (i % 10 == 5) {
      m = oddValidCloud(i / 10, valid, "velodyne", stamp);
      ++good;
    } else if (i % 50 == 7) {
      m = cloudMsg(valid, "no_such_frame", stamp);
      ++unknown_frame;
    } else {
      const auto f = static_cast<CloudFault>(bad % static_cast<int>(CloudFault::kCount));
      m = malformedCloud(f, valid, "velodyne", stamp);
      what = faultName(f);
      ++bad;
    }
    pub.publish(m);
    if (m->header.frame_id == "no_such_frame") continue;  // waits in the tf filter
    ASSERT_TRUE(waitFor([&] {
      return adapter.health().errorCount("unreadable cloud") == static_cast<uint64_t>(bad) &&
             classified.count == good;
    }, 30.0, kPacingPoll)) << "message " << i << " (" << what << "): "
        << adapter.health().errorCount("unreadable cloud") << " of "
        << bad << " rejected, " << classified.count << " of " << good << " classified";
  }
  // A 2-million-point cloud is handled like any other.
  lp::PackedCloud big = flatCloud(2000000);
  pub.publish(sensor_msgs::PointCloud2ConstPtr(cloudMsg(big, "velodyne", ros::Time::now())));
  ++good;
  ASSERT_TRUE(waitFor([&] { return classified.count == good && ground.count == good; }, 60.0));
  EXPECT_GE(bad, 1000);

  // Unknown frames are dropped as missing tf once the filter's queue pushes them out.
  const uint64_t queue = 3;
  EXPECT_TRUE(waitFor([&] { return adapter.health().errorCount("missing tf") + queue >= static_cast<uint64_t>(unknown_frame); }));
  EXPECT_EQ(adapter.health().processedCount(), static_cast<uint64_t>(good));

  // Each kind of bad cloud logged, at most once per throttle period, with the reason.
  ASSERT_TRUE(waitFor([&] { return !logs_.matching("VerticalScanGround: unreadable cloud").empty(); }));
  const std::vector<std::string> lines = logs_.matching("VerticalScanGround: unreadable cloud");
  const std::map<std::string, int> kinds = linesPerKind(lines, "unreadable cloud");
  EXPECT_GE(kinds.size(), 5u);  // the 8 faults fall into at least 5 CloudError kinds
  for (const auto& k : kinds) EXPECT_LE(k.second, allowedLines()) << k.first;
  for (const std::string& l : lines) {
    EXPECT_TRUE(l.find("point_step") != std::string::npos || l.find("missing") != std::string::npos ||
                l.find("data holds") != std::string::npos || l.find("float") != std::string::npos ||
                l.find("endian") != std::string::npos || l.find("row_step") != std::string::npos)
        << l;
  }
  // Diagnostics show the error count.
  EXPECT_TRUE(waitFor([&] {
    return diags_.sum("vertical scan ground", "errors: unreadable cloud") == bad;
  }, 10.0)) << diags_.sum("vertical scan ground", "errors: unreadable cloud");
}

// --- LaserScans.
sensor_msgs::LaserScanPtr validScan(ros::Time stamp, const std::string& frame = "sick") {
  sensor_msgs::LaserScanPtr s(new sensor_msgs::LaserScan);
  s->header.stamp = stamp;
  s->header.frame_id = frame;
  s->angle_min = -M_PI / 2;
  s->angle_increment = M_PI / 180;
  s->angle_max = M_PI / 2;
  s->range_min = 0.1f;
  s->range_max = 80.f;
  for (int k = 0; k <= 180; ++k) {
    const double a = s->angle_min + k * s->angle_increment;
    // Scan plane vertical (roll 90 deg): sensor y is up; the ground is 1 m below.
    s->ranges.push_back(std::sin(a) < -0.05 ? static_cast<float>(1.0 / -std::sin(a))
                                            : std::numeric_limits<float>::infinity());
  }
  return s;
}

TEST_F(Fixture, HoughGroundSurvivesMalformedScans) {
  ros::NodeHandle nh("hough"), pnh("hough_private");
  lp::HoughGroundRos adapter(nh, pnh);
  Counter classified;
  ros::Subscriber s1 = nh.subscribe("classified", 1000, &Counter::callback<sensor_msgs::PointCloud2ConstPtr>, &classified);
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("scan", 1000);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  int bad = 0, good = 0;
  const ros::Time t0 = ros::Time::now();
  for (int i = 0; bad < 1050; ++i) {
    const ros::Time stamp = t0 + ros::Duration(0.0133 * i);
    sensor_msgs::LaserScanPtr s = validScan(stamp);
    bool is_bad = true;
    switch (i % 13) {
      case 0: is_bad = false; break;
      case 1: s->angle_increment = 0.f; break;
      case 2: s->angle_increment = nan; break;
      case 3: s->angle_min = inf; break;
      case 4: s->angle_increment = 0.1f; break;  // 181 returns over 18 rad
      case 5: s->range_min = 50.f; s->range_max = 10.f; break;
      case 6: s->range_max = nan; break;
      case 7: s->range_min = -1.f; break;
      case 8: is_bad = false; s->ranges.assign(s->ranges.size(), nan); break;
      case 9: is_bad = false; s->ranges.clear(); break;
      case 10: is_bad = false; s->intensities.assign(7, 1.f); s->ranges[3] = -inf; break;
      case 11: is_bad = false; s->header.stamp = stamp - ros::Duration(60.0); break;  // bag loop
      case 12: s->ranges.assign(3000000, 5.f); s->angle_increment = 1e-6f; break;  // too many
    }
    if (is_bad) ++bad; else ++good;
    pub.publish(sensor_msgs::LaserScanConstPtr(s));
    ASSERT_TRUE(waitFor([&] {
      return adapter.health().errorCount("unreadable scan") == static_cast<uint64_t>(bad) &&
             classified.count == good;
    }, 30.0, kPacingPoll)) << "scan " << i << ": " << adapter.health().errorCount("unreadable scan") << " of " << bad
        << " rejected, " << classified.count << " of " << good << " classified";
  }
  EXPECT_GE(bad, 1000);
  EXPECT_EQ(adapter.health().processedCount(), static_cast<uint64_t>(good));
  ASSERT_TRUE(waitFor([&] { return !logs_.matching("HoughGround: unreadable scan").empty(); }));
  const std::vector<std::string> lines = logs_.matching("HoughGround: unreadable scan");
  EXPECT_LE(static_cast<int>(lines.size()), allowedLines());
  for (const std::string& l : lines) {
    EXPECT_TRUE(l.find("angle") != std::string::npos || l.find("range") != std::string::npos ||
                l.find("returns") != std::string::npos)
        << l;
  }
  EXPECT_TRUE(waitFor([&] {
    return diags_.sum("hough", "errors: unreadable scan") == bad;
  }, 10.0)) << diags_.sum("hough", "errors: unreadable scan");
}

TEST_F(Fixture, CalibrationSurvivesMalformedClouds) {
  ros::NodeHandle nh("cal"), pnh("cal_private");
  pnh.setParam("queue_size", 5000);  // nothing dropped by the subscriber queue
  pnh.setParam("buffer_size", 400);
  pnh.setParam("reference_frame", "velodyne_ref");
  pnh.setParam("target_frame", "velodyne_target");
  lp::CalibrationRos adapter(nh, pnh);
  ros::Publisher ref = nh.advertise<sensor_msgs::PointCloud2>("reference", 5000);
  ros::Publisher tgt = nh.advertise<sensor_msgs::PointCloud2>("target", 5000);
  ASSERT_TRUE(waitFor([&] { return ref.getNumSubscribers() > 0 && tgt.getNumSubscribers() > 0; }));

  const lp::PackedCloud valid = flatCloud(1600);
  int bad = 0, good_ref = 0, good_tgt = 0;
  const ros::Time t0 = ros::Time::now();
  for (int i = 0; bad < 1050; ++i) {
    const ros::Time stamp = t0 + ros::Duration(0.1 * i);
    const bool target = (i / 2) % 2;
    const std::string frame = target ? "velodyne_target" : "velodyne_ref";
    sensor_msgs::PointCloud2ConstPtr m;
    if (i % 10 == 0 || i % 10 == 3) {
      m = cloudMsg(valid, frame, stamp);
      (target ? good_tgt : good_ref)++;
    } else if (i % 50 == 7) {
      m = cloudMsg(valid, "no_such_frame", stamp);  // ignored: not the sensor's frame
    } else {
      const auto f = static_cast<CloudFault>(bad % static_cast<int>(CloudFault::kCount));
      m = malformedCloud(f, valid, frame, stamp);
      ++bad;
    }
    (target ? tgt : ref).publish(m);
  }
  EXPECT_GE(bad, 1000);
  // Every valid scan is buffered (with its vehicle pose from tf); nothing else is.
  EXPECT_TRUE(waitFor([&] {
    return adapter.bufferedScans(false) == static_cast<std::size_t>(good_ref) &&
           adapter.bufferedScans(true) == static_cast<std::size_t>(good_tgt);
  }, 60.0)) << adapter.bufferedScans(false) << "/" << good_ref << " reference, "
            << adapter.bufferedScans(true) << "/" << good_tgt << " target";
  ASSERT_TRUE(waitFor([&] { return !logs_.matching("Calibration: unreadable").empty(); }));
  const std::vector<std::string> lines = logs_.matching("Calibration: unreadable cloud");
  const std::map<std::string, int> kinds = linesPerKind(lines, "unreadable cloud");
  EXPECT_GE(kinds.size(), 5u);
  for (const auto& k : kinds) EXPECT_LE(k.second, allowedLines()) << k.first;
  EXPECT_EQ(adapter.health().errorCount("unreadable cloud"), static_cast<uint64_t>(bad));
  EXPECT_TRUE(waitFor([&] {
    return diags_.sum("calibration", "errors: unreadable cloud") == bad;
  }, 10.0)) << diags_.sum("calibration", "errors: unreadable cloud");
  const std::vector<std::string> frames = logs_.matching("no_such_frame");
  EXPECT_GE(frames.size(), 1u);
  EXPECT_LE(static_cast<int>(frames.size()), allowedLines());
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "malformed_input_test");
  ros::NodeHandle nh;
  const int rc = RUN_ALL_TESTS();
  ros::shutdown();
  return rc;
}
