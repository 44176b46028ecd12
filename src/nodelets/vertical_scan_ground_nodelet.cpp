// Nodelet shell: onInit only builds the adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/vertical_scan_ground_ros.h"

namespace ladar_perception {

class VerticalScanGroundNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    adapter_.reset(new VerticalScanGroundRos(getMTNodeHandle(), getMTPrivateNodeHandle()));
  }
  std::unique_ptr<VerticalScanGroundRos> adapter_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::VerticalScanGroundNodelet, nodelet::Nodelet)
