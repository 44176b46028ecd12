// Helpers shared by the rostest nodes in test/ros: waiting on a condition, collecting the
// messages of a topic, the synthetic flat-ground Velodyne cloud most tests feed the
// perception nodelets, and the real KITTI scans some of them read when they are present.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include <dirent.h>

#include <boost/shared_ptr.hpp>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "ladar_perception/calibration/accumulation.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {
namespace rostest {

// Scan k of a calibration scan set as an x, y, z PointCloud2 in `frame` (the calibration
// rostests publish the simulator's trials through it).
inline sensor_msgs::PointCloud2Ptr scanSetCloud(const calibration::ScanSet& set, std::size_t k,
                                                const std::string& frame, const ros::Time& stamp) {
  sensor_msgs::PointCloud2Ptr msg(new sensor_msgs::PointCloud2);
  msg->header.frame_id = frame;
  msg->header.stamp = stamp;
  sensor_msgs::PointCloud2Modifier mod(*msg);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(set.scan_begin[k + 1] - set.scan_begin[k]);
  sensor_msgs::PointCloud2Iterator<float> x(*msg, "x"), y(*msg, "y"), z(*msg, "z");
  for (uint32_t i = set.scan_begin[k]; i < set.scan_begin[k + 1]; ++i, ++x, ++y, ++z) {
    *x = set.points[i].x();
    *y = set.points[i].y();
    *z = set.points[i].z();
  }
  return msg;
}

// Polls `done` every `poll` seconds (wall time) until it holds or `seconds` have passed; returns
// its last value.
inline bool waitFor(const std::function<bool()>& done, double seconds = 30.0, double poll = 0.002) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(poll).sleep();
  }
  return done();
}

// Counts the messages of a topic.
struct Counter {
  std::atomic<int> count{0};
  template <typename M>
  void callback(const M&) { ++count; }
};

// Keeps the latest message of a topic and counts them.
template <typename M>
struct Latest {
  std::mutex mutex;
  boost::shared_ptr<const M> msg;
  std::atomic<int> count{0};
  void callback(const boost::shared_ptr<const M>& m) {
    std::lock_guard<std::mutex> lock(mutex);
    msg = m;
    ++count;
  }
  boost::shared_ptr<const M> get() {
    std::lock_guard<std::mutex> lock(mutex);
    return msg;
  }
};

// n returns of a 16-ring ladar (elevations -20..-5 degrees, ring field set) `sensor_height`
// above a flat ground, in velodyne's packed XYZIRT layout.
inline PackedCloud flatCloud(int n, float sensor_height = 1.8f) {
  PackedCloud c;
  c.layout = velodyneXYZIRTLayout(static_cast<uint32_t>(n));
  c.data.assign(static_cast<std::size_t>(c.layout.row_step) * c.layout.height, 0);
  const CloudLayout& L = c.layout;
  const FieldDesc& fx = *findField(L, "x");
  const FieldDesc& fy = *findField(L, "y");
  const FieldDesc& fz = *findField(L, "z");
  const FieldDesc& fring = *findField(L, "ring");
  for (int i = 0; i < n; ++i) {
    const int ring = i % 16;
    const double elev = (-20.0 + ring) * M_PI / 180.0;
    const double az = (i / 16) * 2.0 * M_PI / std::max(1, n / 16);
    const double range = sensor_height / std::sin(-elev);
    uint8_t* p = c.data.data() + static_cast<std::size_t>(i) * L.point_step;
    writeField(p, fx, range * std::cos(elev) * std::cos(az));
    writeField(p, fy, range * std::cos(elev) * std::sin(az));
    writeField(p, fz, range * std::sin(elev));
    writeField(p, fring, ring);
  }
  return c;
}

// A freshly allocated message of `c`, framed and stamped.
inline sensor_msgs::PointCloud2Ptr cloudMsg(const PackedCloud& c, const std::string& frame,
                                            ros::Time stamp) {
  sensor_msgs::PointCloud2Ptr m = toMessage(c);
  m->header.frame_id = frame;
  m->header.stamp = stamp;
  return m;
}

// A sensor mount `z` metres straight above `parent`, unrotated, at `stamp`.
inline geometry_msgs::TransformStamped mountTransform(const std::string& parent, const std::string& child,
                                                      double z, ros::Time stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.z = z;
  t.transform.rotation.w = 1.0;
  return t;
}

// The folder of real KITTI Velodyne scans: $LADAR_KITTI_DIR, else the data folder beside the
// package. The data are not part of the package; tests that read them skip without them.
inline std::string kittiDir() {
  if (const char* env = std::getenv("LADAR_KITTI_DIR")) return env;
  return std::string(LADAR_SOURCE_DIR) + "/../shared/data/kitti_hdl64";
}

// The .bin scans of kittiDir(), sorted by name (empty when there are none).
inline std::vector<std::string> kittiScans() {
  std::vector<std::string> out;
  const std::string dir = kittiDir();
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 4 && name.substr(name.size() - 4) == ".bin") out.push_back(dir + "/" + name);
    }
    closedir(d);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The `label` field of a classified cloud, one byte per point (empty when it has none).
inline std::vector<uint8_t> labelsOf(const sensor_msgs::PointCloud2& msg) {
  CloudLayout layout;
  PointCloudView view;
  std::string error;
  std::vector<uint8_t> out;
  if (!viewOf(msg, &layout, &view, &error)) return out;
  const FieldAccessor label = view.field("label");
  if (!label.valid) return out;
  out.reserve(view.size());
  for (std::size_t i = 0; i < view.size(); ++i) {
    out.push_back(static_cast<uint8_t>(label.read<int>(view.pointData(i))));
  }
  return out;
}

}  // namespace rostest
}  // namespace ladar_perception
