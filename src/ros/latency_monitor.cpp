#include "ladar_perception/ros/latency_monitor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <xmlrpcpp/XmlRpcException.h>

namespace ladar_perception {

namespace {

double wallNow() { return ros::WallTime::now().toSec(); }

long residentKib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.compare(0, 6, "VmRSS:") == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  }
  return -1;
}

// p in [0, 100] of an unsorted sample (copied: the caller keeps recording).
double percentile(std::vector<float> v, double p) {
  if (v.empty()) return -1;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string stats(const LatencyHistogram& h) {
  std::ostringstream s;
  s << "{\"p50\": " << h.percentile(50) << ", \"p99\": " << h.percentile(99)
    << ", \"max\": " << h.max() << "}";
  return s.str();
}

constexpr double kBinMinMs = 0.001, kBinGrowth = 1.01;
const double kLogGrowth = std::log(kBinGrowth);
constexpr std::size_t kBins = 1856;  // 0.001 ms * 1.01^1856 = 1.0e5 ms

}  // namespace

LatencyHistogram::LatencyHistogram() : bins_(kBins + 1, 0) {}

void LatencyHistogram::add(double ms) {
  // Bin 0: below 0.001 ms; bin k: [0.001 * 1.01^(k-1), 0.001 * 1.01^k); the last: beyond.
  std::size_t k = 0;
  if (ms >= kBinMinMs) {
    k = 1 + static_cast<std::size_t>(std::log(ms / kBinMinMs) / kLogGrowth);
    if (k > kBins) k = kBins;
  }
  ++bins_[k];
  ++count_;
  if (count_ == 1 || ms > max_) max_ = ms;
}

double LatencyHistogram::percentile(double p) const {
  if (count_ == 0) return -1;
  // The sample of rank p / 100 * (count - 1), rounded, as nth_element over the samples gave.
  const uint64_t rank = std::min<uint64_t>(count_ - 1, static_cast<uint64_t>(p / 100.0 * (count_ - 1) + 0.5));
  uint64_t seen = 0;
  for (std::size_t k = 0; k <= kBins; ++k) {
    seen += bins_[k];
    if (seen > rank) {
      if (k == 0) return 0.0;
      // The bin's geometric middle, at most the maximum.
      return std::min(max_, kBinMinMs * std::pow(kBinGrowth, static_cast<double>(k) - 0.5));
    }
  }
  return max_;
}

LatencyMonitorRos::LatencyMonitorRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh) {
  warmup_ = private_nh_.param("warmup", 10.0);
  grace_ = private_nh_.param("grace", 2.0);
  write_period_ = private_nh_.param("write_period", 10.0);
  output_file_ = private_nh_.param<std::string>("output_file", "");
  if (output_file_.empty()) ROS_ERROR("LatencyMonitor: ~output_file is not set; nothing is written");
  start_ = wallNow();
  last_write_ = start_;

  XmlRpc::XmlRpcValue list;
  if (!private_nh_.getParam("streams", list) || list.getType() != XmlRpc::XmlRpcValue::TypeArray) {
    ROS_ERROR("LatencyMonitor: ~streams must be a list of {name, input, output, input_type}");
    return;
  }
  for (int i = 0; i < list.size(); ++i) {
    try {
      std::unique_ptr<Stream> s(new Stream);
      s->name = static_cast<std::string>(list[i]["name"]);
      s->input = static_cast<std::string>(list[i]["input"]);
      s->output = static_cast<std::string>(list[i]["output"]);
      s->input_type = list[i].hasMember("input_type")
                          ? static_cast<std::string>(list[i]["input_type"])
                          : std::string("PointCloud2");
      Stream* raw = s.get();
      if (s->input_type == "LaserScan") {
        s->input_sub = nh_.subscribe<sensor_msgs::LaserScan>(
            s->input, 100, [this, raw](const sensor_msgs::LaserScanConstPtr& m) { onInput(raw, m->header); });
      } else {
        s->input_sub = nh_.subscribe<sensor_msgs::PointCloud2>(
            s->input, 100, [this, raw](const sensor_msgs::PointCloud2ConstPtr& m) { onInput(raw, m->header); });
      }
      s->output_sub = nh_.subscribe<sensor_msgs::PointCloud2>(
          s->output, 100, [this, raw](const sensor_msgs::PointCloud2ConstPtr& m) { onOutput(raw, m->header); });
      streams_.push_back(std::move(s));
    } catch (const XmlRpc::XmlRpcException& e) {
      ROS_ERROR_STREAM("LatencyMonitor: stream " << i << " of ~streams is malformed: " << e.getMessage());
    }
  }
  timer_ = private_nh_.createWallTimer(ros::WallDuration(1.0), &LatencyMonitorRos::sample, this);
  ROS_INFO("LatencyMonitor: %zu streams, writing %s", streams_.size(), output_file_.c_str());
}

LatencyMonitorRos::~LatencyMonitorRos() {
  timer_.stop();
  for (auto& s : streams_) {
    s->input_sub.shutdown();
    s->output_sub.shutdown();
  }
  try {
    write();
  } catch (const std::exception& e) {
    ROS_ERROR("LatencyMonitor: final write failed: %s", e.what());
  }
}

void LatencyMonitorRos::onInput(Stream* s, const std_msgs::Header& header) {
  const double now = wallNow();
  if (now - start_ < warmup_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++s->inputs;
  auto early = s->early.find(header.stamp.toNSec());
  if (early != s->early.end()) {  // the output was faster than this callback
    ++s->outputs;
    s->latency_ms.add(0.0);
    s->end_to_end_ms.add((early->second - header.stamp.toSec()) * 1e3);
    s->early.erase(early);
    return;
  }
  s->waiting[header.stamp.toNSec()] = now;
}

void LatencyMonitorRos::onOutput(Stream* s, const std_msgs::Header& header) {
  const double now = wallNow();
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = s->waiting.find(header.stamp.toNSec());
  if (it == s->waiting.end()) {
    if (now - start_ >= warmup_) s->early[header.stamp.toNSec()] = now;
    return;
  }
  ++s->outputs;
  s->latency_ms.add((now - it->second) * 1e3);
  s->end_to_end_ms.add((now - header.stamp.toSec()) * 1e3);
  s->waiting.erase(it);
}

void LatencyMonitorRos::expire(Stream* s, double now) {
  for (auto it = s->waiting.begin(); it != s->waiting.end();) {
    if (now - it->second > grace_) {
      ++s->dropped;
      it = s->waiting.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = s->early.begin(); it != s->early.end();) {
    if (now - it->second > grace_) {
      ++s->unmatched_outputs;  // an output for no input seen (e.g. before the warm-up ended)
      it = s->early.erase(it);
    } else {
      ++it;
    }
  }
}

void LatencyMonitorRos::sample(const ros::WallTimerEvent&) {
  try {
    const double now = wallNow();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      rss_kib_.emplace_back(now - start_, residentKib());
      for (auto& s : streams_) expire(s.get(), now);
    }
    if (now - last_write_ >= write_period_) {
      last_write_ = now;
      write();
    }
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(10.0, "LatencyMonitor: %s", e.what());
  }
}

std::string LatencyMonitorRos::summaryJson() {
  std::ostringstream j;
  j << "{\n  \"measured_s\": " << std::max(0.0, wallNow() - start_ - warmup_) << ",\n  \"streams\": {";
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    const Stream& s = *streams_[i];
    j << (i ? "," : "") << "\n    " << quoted(s.name) << ": {\"input\": " << quoted(s.input)
      << ", \"output\": " << quoted(s.output) << ", \"inputs\": " << s.inputs
      << ", \"outputs\": " << s.outputs << ", \"dropped\": " << s.dropped
      << ", \"waiting\": " << s.waiting.size() << ", \"unmatched_outputs\": " << s.unmatched_outputs
      << ",\n      \"latency_ms\": " << stats(s.latency_ms)
      << ",\n      \"end_to_end_ms\": " << stats(s.end_to_end_ms) << "}";
  }
  // Resident memory: medians over the second minute and over the last minute.
  const double end_t = rss_kib_.empty() ? 0.0 : rss_kib_.back().first;
  std::vector<float> second_minute, last_minute;
  for (const auto& r : rss_kib_) {
    if (r.first >= 60.0 && r.first < 120.0) second_minute.push_back(static_cast<float>(r.second));
    if (r.first >= 120.0 && r.first > end_t - 60.0) last_minute.push_back(static_cast<float>(r.second));
  }
  const double base = percentile(second_minute, 50), last = percentile(last_minute, 50);
  long max_after = -1;
  for (const auto& r : rss_kib_) {
    if (r.first >= 60.0) max_after = std::max(max_after, r.second);
  }
  j << "\n  },\n  \"rss_mib\": {\"second_minute_median\": " << base / 1024.0
    << ", \"last_minute_median\": " << last / 1024.0 << ", \"max_after_1min\": " << max_after / 1024.0
    << ", \"end\": " << (rss_kib_.empty() ? -1 : rss_kib_.back().second) / 1024.0
    << ", \"growth_after_1min_percent\": " << (base > 0 && last > 0 ? (last - base) * 100.0 / base : -1.0)
    << "},\n  \"rss_kib_every_10s\": [";
  for (std::size_t i = 0; i < rss_kib_.size(); i += 10) {
    j << (i ? ", " : "") << "[" << static_cast<int>(rss_kib_[i].first) << ", " << rss_kib_[i].second << "]";
  }
  j << "]\n}\n";
  return j.str();
}

void LatencyMonitorRos::write() {
  if (output_file_.empty()) return;
  std::string text;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    text = summaryJson();
  }
  const std::string tmp = output_file_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    if (!out) {
      ROS_ERROR_THROTTLE(10.0, "LatencyMonitor: cannot write %s", tmp.c_str());
      return;
    }
  }
  if (std::rename(tmp.c_str(), output_file_.c_str()) != 0) {
    ROS_ERROR_THROTTLE(10.0, "LatencyMonitor: cannot replace %s", output_file_.c_str());
  }
}

}  // namespace ladar_perception
