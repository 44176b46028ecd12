// Standalone node for users who do not run a nodelet manager: the same adapter.
#include <ros/ros.h>

#include "ladar_perception/ros/vertical_scan_ground_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "vertical_scan_ground");
  ladar_perception::VerticalScanGroundRos adapter(ros::NodeHandle(), ros::NodeHandle("~"));
  ros::MultiThreadedSpinner spinner(2);
  spinner.spin();
  return 0;
}
