// Helpers shared by the rostest nodes in test/ros: waiting on a condition, collecting the
// messages of a topic, and the synthetic flat-ground Velodyne cloud most tests feed the
// perception nodelets.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include <boost/shared_ptr.hpp>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ros/cloud_conversion.h"

namespace ladar_perception {
namespace rostest {

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

}  // namespace rostest
}  // namespace ladar_perception
