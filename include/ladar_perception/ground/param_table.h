// One row of a node's parameter table (vertical_scan_params.def, hough_params.def): what the
// tools list, the tests check the .cfg, YAML and README against, and the ROS mapping follows.
#pragma once

namespace ladar_perception {

struct ParamInfo {
  const char* name;     // ROS parameter and --set key
  const char* member;   // field of the params struct
  const char* type;     // "float", "int" or "bool"
  double default_value; // in the default method
  double min;
  double max;
  const char* unit;     // "" for a ratio or a count
  const char* meaning;
};

}  // namespace ladar_perception
