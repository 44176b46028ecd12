// Nodelet shell: onInit only builds the adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/latency_monitor.h"

namespace ladar_perception {

class LatencyMonitorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    adapter_.reset(new LatencyMonitorRos(getMTNodeHandle(), getMTPrivateNodeHandle()));
  }
  std::unique_ptr<LatencyMonitorRos> adapter_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::LatencyMonitorNodelet, nodelet::Nodelet)
