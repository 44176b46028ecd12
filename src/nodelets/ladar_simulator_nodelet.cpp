// Nodelet shell of the ladar simulator: onInit only builds the ROS adapter.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "ladar_perception/ros/ladar_simulator.h"

namespace ladar_perception {

class LadarSimulatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    simulator_ = std::make_unique<LadarSimulatorRos>(getNodeHandle(), getPrivateNodeHandle(),
                                                     getName());
  }
  std::unique_ptr<LadarSimulatorRos> simulator_;
};

}  // namespace ladar_perception

PLUGINLIB_EXPORT_CLASS(ladar_perception::LadarSimulatorNodelet, nodelet::Nodelet)
