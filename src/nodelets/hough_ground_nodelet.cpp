// Nodelet shell: onInit only builds the adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/hough_ground_ros.h"

namespace ladar_perception {

class HoughGroundNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    adapter_.reset(new HoughGroundRos(getMTNodeHandle(), getMTPrivateNodeHandle()));
  }
  std::unique_ptr<HoughGroundRos> adapter_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::HoughGroundNodelet, nodelet::Nodelet)
