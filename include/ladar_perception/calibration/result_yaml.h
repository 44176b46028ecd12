// Writing a calibration result where the vehicle's launch files can use it: a YAML holding one
// TransformStamped-shaped dict (header.frame_id, child_frame_id, transform.translation/rotation),
// the form tf2_ros's static_transform_publisher loads when given a single parameter name.
// Written atomically (temporary file in the same directory, fsync, rename).
#pragma once

#include <string>

#include "ladar_perception/calibration/calibrator.h"

namespace ladar_perception {
namespace calibration {

// The TransformStamped dict alone (header.frame_id, child_frame_id, transform), every line
// prefixed by `indent` (a network's YAML nests one per sensor under its key).
std::string transformStampedYaml(const std::string& parent_frame, const std::string& child_frame,
                                 const Pose6& extrinsic, const std::string& indent = "");
// Pieces of the YAML text: a number that XmlRpc reads as a double (always with a decimal
// point); a figure for a comment ("unobservable" when not finite); text for a comment or a
// quoted string (no line breaks, no quotes).
std::string yamlNumber(double v);
std::string yamlFigure(double v, int significant_digits = 6);
std::string yamlText(const std::string& s);

// The YAML text. Figures that are not part of the transform (stddev, cost, unobservable DOFs,
// method) go into comments so that the parameter stays exactly a TransformStamped.
std::string staticTransformYaml(const std::string& parent_frame, const std::string& child_frame,
                                const CalibrationResult& result);
// Writes the YAML atomically (a temporary file renamed over `path`: a kill at any moment leaves
// either the previous file or the new one, never a partial one). A previous file is kept first
// as `path`.YYYYMMDDTHHMMSSZ.bak (UTC; -N appended if that name exists).
bool writeStaticTransformYaml(const std::string& path, const std::string& parent_frame,
                              const std::string& child_frame, const CalibrationResult& result,
                              std::string* error);
// The ready-to-paste roslaunch lines loading that YAML and starting the publisher.
std::string staticTransformLaunchLine(const std::string& yaml_path,
                                      const std::string& parent_frame,
                                      const std::string& child_frame);
// Keeps an existing `path` as `path`.YYYYMMDDTHHMMSSZ.bak (its name in *backup; empty when
// there was no file). False with a reason when the backup cannot be made.
bool backupExistingFile(const std::string& path, std::string* backup, std::string* error);
// Writes `text` to `path` atomically (temporary file, fsync, rename).
bool writeFileAtomically(const std::string& path, const std::string& text, std::string* error);

}  // namespace calibration
}  // namespace ladar_perception
