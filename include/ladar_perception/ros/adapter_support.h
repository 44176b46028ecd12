// The plumbing every ground adapter shares, written once:
//  - SensorInput<M>: the input topic, through a tf2_ros::MessageFilter to the ground frame (or
//    directly when tf is off), with the filter's drops reported to InputHealth and every
//    callback guarded so no exception reaches the nodelet manager;
//  - AdapterDiagnostics: a diagnostic_updater with the input-rate check and the adapter's own
//    status task, published at 1 Hz of wall-clock time (also on a short bag at sim time);
//  - MethodReconfigure<Config>: the dynamic_reconfigure server, with named methods: at start-up
//    the method's settings are loaded except the thresholds given explicitly as parameters;
//    choosing another method later loads that method's settings into every threshold; the
//    processing callback takes the config when it changed.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <boost/shared_ptr.hpp>
#include <dynamic_reconfigure/server.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <message_filters/subscriber.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include "ladar_perception/ros/input_health.h"

namespace ladar_perception {

template <typename M>
class SensorInput {
 public:
  using ConstPtr = boost::shared_ptr<const M>;
  using Callback = std::function<void(const ConstPtr&)>;

  // Subscribes `topic` on nh. With use_tf, messages wait (at most queue_size of them) until
  // tf covers target_frame <- their frame at stamp + tolerance; drops are counted in health.
  SensorInput(ros::NodeHandle nh, const std::string& topic, bool use_tf,
              const std::string& target_frame, int queue_size, double tolerance,
              InputHealth* health, Callback callback)
      : health_(health), callback_(std::move(callback)), target_frame_(target_frame) {
    if (use_tf) {
      listener_.reset(new tf2_ros::TransformListener(buffer_, nh));
      subscriber_.subscribe(nh, topic, queue_size);
      filter_.reset(new tf2_ros::MessageFilter<M>(subscriber_, buffer_, target_frame, queue_size, nh));
      filter_->setTolerance(ros::Duration(tolerance));
      filter_->registerCallback([this](const ConstPtr& m) { guarded(m); });
      filter_->registerFailureCallback(
          [this](const ConstPtr& m, tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
            try {
              health_->tfFilterDropped(target_frame_, m->header, reason);
            } catch (const std::exception& e) {
              ROS_ERROR_THROTTLE(5.0, "tf failure handler: %s", e.what());
            }
          });
    } else {
      direct_ = nh.subscribe<M>(topic, queue_size, [this](const ConstPtr& m) { guarded(m); });
    }
  }
  ~SensorInput() {
    direct_.shutdown();
    subscriber_.unsubscribe();
    if (filter_) filter_->clear();
  }
  SensorInput(const SensorInput&) = delete;
  SensorInput& operator=(const SensorInput&) = delete;

  // The tf buffer the filter waits on (lookups at a passed message's stamp succeed).
  const tf2_ros::Buffer& buffer() const { return buffer_; }

 private:
  // No exception may leave a callback: it would take down every nodelet of the manager.
  void guarded(const ConstPtr& m) {
    try {
      callback_(m);
    } catch (const std::exception& e) {
      health_->error("internal error", e.what());
    } catch (...) {
      health_->error("internal error", "unknown exception");
    }
  }

  InputHealth* health_;
  Callback callback_;
  std::string target_frame_;
  tf2_ros::Buffer buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
  message_filters::Subscriber<M> subscriber_;
  std::unique_ptr<tf2_ros::MessageFilter<M>> filter_;
  ros::Subscriber direct_;
};

class AdapterDiagnostics {
 public:
  using Task = std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)>;
  // `name` prefixes log lines; `task_name` names the status; rates in Hz bound the input rate
  // check (no rate check when expected_rate_max <= 0).
  AdapterDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& name,
                     const std::string& task_name, double expected_rate_min,
                     double expected_rate_max, Task task);
  ~AdapterDiagnostics() { timer_.stop(); }
  // One input received (for the rate check).
  void tick() {
    if (rate_) rate_->tick();
  }

 private:
  diagnostic_updater::Updater updater_;
  double rate_min_, rate_max_;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> rate_;
  Task task_;
  ros::WallTimer timer_;
};

template <typename Config>
class MethodReconfigure {
 public:
  using LoadSettings = std::function<void(const std::string& method, Config* config)>;
  // Notes the thresholds given explicitly at start-up (before the dynamic_reconfigure server
  // writes every parameter to the parameter server), then starts the server on private_nh.
  MethodReconfigure(ros::NodeHandle private_nh, LoadSettings load)
      : private_nh_(private_nh), load_(std::move(load)) {
    for (const auto& param : Config::__getParamDescriptions__()) {
      if (param->name != "method" && private_nh_.hasParam(param->name)) explicit_.push_back(param->name);
    }
    server_.reset(new dynamic_reconfigure::Server<Config>(private_nh_));
    server_->setCallback([this](Config& config, uint32_t) { apply(config); });
  }
  // For the processing callback: when the config changed since the last call (always before
  // the first call), copies it to *out and returns true.
  bool takeChanged(Config* out) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!changed_) return false;
    *out = config_;
    changed_ = false;
    return true;
  }
  Config current() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return config_;
  }

 private:
  // The server's callback with the requested config; adjusts it in place (what the server then
  // reports back) and keeps it.
  void apply(Config& config) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (last_method_.empty()) {
      load_(config.method, &config);
      for (const auto& param : Config::__getParamDescriptions__()) {
        if (std::find(explicit_.begin(), explicit_.end(), param->name) != explicit_.end()) {
          param->fromServer(private_nh_, config);
        }
      }
    } else if (config.method != last_method_) {
      load_(config.method, &config);  // the user tunes from the new method's settings
    }
    last_method_ = config.method;
    config_ = config;
    changed_ = true;
  }

  ros::NodeHandle private_nh_;
  LoadSettings load_;
  std::vector<std::string> explicit_;
  std::string last_method_;
  mutable std::mutex mutex_;
  Config config_;
  bool changed_ = false;
  std::unique_ptr<dynamic_reconfigure::Server<Config>> server_;  // last: stops first
};

}  // namespace ladar_perception
