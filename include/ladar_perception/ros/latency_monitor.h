// ROS adapter of the nodelet ladar_perception/LatencyMonitor: loaded into the perception
// nodelet manager, it measures what a perception nodelet costs its vehicle, without adding any
// transport (in-process subscriptions share the manager's connection and receive the very
// pointers that were published):
//  - per stream (an input topic and the output topic its nodelet publishes for each input),
//    the latency input receipt -> output receipt in the manager and the end-to-end latency
//    input header stamp -> output receipt, as p50 / p99 / max;
//  - dropped scans: inputs whose output did not arrive within `grace` seconds;
//  - the manager's resident memory once a second, and its growth after the first minute: the
//    median over the last minute against the median over the second minute (the medians
//    ignore the swing of large messages being allocated and freed).
// The summary is written (atomically) as JSON to ~output_file every ~write_period seconds and
// at shutdown; scripts/soak reads it. Parameters:
//   ~streams: list of {name, input, output, input_type: PointCloud2|LaserScan}
//   ~warmup [s] (default 10): inputs before this are not measured
//   ~grace [s] (default 2), ~output_file (required), ~write_period [s] (default 10)
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

namespace ladar_perception {

// Latencies in a fixed set of bins 1% wide (0.001 ms to 100 s), allocated and written once:
// recording a sample allocates nothing, so the monitor's own memory does not grow with the length
// of the run (a vector of every sample grew 0.7 KiB/s at 85 scans/s and showed as the manager's
// growth). Percentiles are exact to the bin, 1%; the maximum is exact.
class LatencyHistogram {
 public:
  LatencyHistogram();
  void add(double ms);
  bool empty() const { return count_ == 0; }
  double percentile(double p) const;  // p in [0, 100]; -1 when empty
  double max() const { return count_ ? max_ : -1.0; }

 private:
  std::vector<uint64_t> bins_;
  uint64_t count_ = 0;
  double max_ = 0;
};

class LatencyMonitorRos {
 public:
  LatencyMonitorRos(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~LatencyMonitorRos();

 private:
  struct Stream {
    std::string name, input, output, input_type;
    // Input stamp (ns) -> wall receipt time of inputs still waiting for their output.
    std::map<uint64_t, double> waiting;
    // Outputs whose input callback has not run yet (the manager's threads run the perception
    // nodelet and this monitor concurrently): stamp -> wall receipt time.
    std::map<uint64_t, double> early;
    LatencyHistogram latency_ms, end_to_end_ms;
    uint64_t inputs = 0, outputs = 0, dropped = 0, unmatched_outputs = 0;
    ros::Subscriber input_sub, output_sub;
  };

  void onInput(Stream* s, const std_msgs::Header& header);
  void onOutput(Stream* s, const std_msgs::Header& header);
  void sample(const ros::WallTimerEvent&);
  void expire(Stream* s, double now);  // caller holds mutex_
  std::string summaryJson();          // caller holds mutex_
  void write();

  ros::NodeHandle nh_, private_nh_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Stream>> streams_;
  std::vector<std::pair<double, long>> rss_kib_;  // (seconds since start, VmRSS)
  double start_ = 0, warmup_ = 10, grace_ = 2, write_period_ = 10, last_write_ = 0;
  std::string output_file_;
  ros::WallTimer timer_;
};

}  // namespace ladar_perception
