// Writing a calibration result where the vehicle's launch files can use it: a YAML holding one
// TransformStamped-shaped dict (header.frame_id, child_frame_id, transform.translation/rotation),
// the form tf2_ros's static_transform_publisher loads when given a single parameter name.
// Written atomically (temporary file in the same directory, fsync, rename).
#pragma once

#include <string>

#include "ladar_perception/calibration/calibrator.h"

namespace ladar_perception {
namespace calibration {

// The YAML text. Figures that are not part of the transform (stddev, cost, unobservable DOFs,
// method) go into comments so that the parameter stays exactly a TransformStamped.
std::string staticTransformYaml(const std::string& parent_frame, const std::string& child_frame,
                                const CalibrationResult& result);
bool writeStaticTransformYaml(const std::string& path, const std::string& parent_frame,
                              const std::string& child_frame, const CalibrationResult& result,
                              std::string* error);
// The ready-to-paste roslaunch lines loading that YAML and starting the publisher.
std::string staticTransformLaunchLine(const std::string& yaml_path,
                                      const std::string& parent_frame,
                                      const std::string& child_frame);
// Writes `text` to `path` atomically.
bool writeFileAtomically(const std::string& path, const std::string& text, std::string* error);

}  // namespace calibration
}  // namespace ladar_perception
