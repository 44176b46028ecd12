// Nodelet shell: onInit only builds the adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/calibration_ros.h"

namespace ladar_perception {

class CalibrationNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    adapter_.reset(new CalibrationRos(getMTNodeHandle(), getMTPrivateNodeHandle()));
  }
  std::unique_ptr<CalibrationRos> adapter_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::CalibrationNodelet, nodelet::Nodelet)
