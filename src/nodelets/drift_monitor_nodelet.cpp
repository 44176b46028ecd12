// Nodelet shell: onInit only builds the adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/drift_monitor_ros.h"

namespace ladar_perception {

class DriftMonitorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    adapter_.reset(new DriftMonitorRos(getMTNodeHandle(), getMTPrivateNodeHandle()));
  }
  std::unique_ptr<DriftMonitorRos> adapter_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::DriftMonitorNodelet, nodelet::Nodelet)
