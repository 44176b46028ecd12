// The 6-DOF hypothesis of a sensor extrinsic (thesis 4.3: x, y, z, roll, pitch, yaw) and its
// conversions. Rotation convention: ROS fixed-axis RPY, R = Rz(yaw) * Ry(pitch) * Rx(roll).
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ladar_perception {
namespace calibration {

// x, y, z [m], roll, pitch, yaw [rad].
using Pose6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

enum Dof { kX = 0, kY = 1, kZ = 2, kRoll = 3, kPitch = 4, kYaw = 5 };

// "x", "y", "z", "roll", "pitch", "yaw".
const char* dofName(int dof);
// Index of a DOF name, -1 when unknown.
int dofIndex(const std::string& name);

Eigen::Isometry3d toIsometry(const Pose6& pose);
// The RPY of the rotation is taken in (-pi, pi], pitch in [-pi/2, pi/2].
Pose6 fromIsometry(const Eigen::Isometry3d& transform);
Pose6 makePose(double x, double y, double z, double roll, double pitch, double yaw);

// Difference a - b with the angles wrapped into (-pi, pi].
Pose6 poseDifference(const Pose6& a, const Pose6& b);
double wrapAngle(double angle);

}  // namespace calibration
}  // namespace ladar_perception
