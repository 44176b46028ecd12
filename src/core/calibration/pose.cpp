#include "ladar_perception/calibration/pose.h"

#include <cmath>

namespace ladar_perception {
namespace calibration {

namespace {
const std::array<const char*, 6> kDofNames = {"x", "y", "z", "roll", "pitch", "yaw"};
}

const char* dofName(int dof) { return (dof >= 0 && dof < 6) ? kDofNames[dof] : "?"; }

int dofIndex(const std::string& name) {
  for (int i = 0; i < 6; ++i) {
    if (name == kDofNames[i]) return i;
  }
  return -1;
}

Eigen::Isometry3d toIsometry(const Pose6& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(p[kYaw], Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(p[kPitch], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(p[kRoll], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = p.head<3>();
  return t;
}

Pose6 fromIsometry(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d r = t.linear();
  Pose6 p;
  p.head<3>() = t.translation();
  // R = Rz(yaw) Ry(pitch) Rx(roll): r20 = -sin(pitch).
  const double sp = std::max(-1.0, std::min(1.0, -r(2, 0)));
  p[kPitch] = std::asin(sp);
  if (std::abs(sp) < 1.0 - 1e-12) {
    p[kRoll] = std::atan2(r(2, 1), r(2, 2));
    p[kYaw] = std::atan2(r(1, 0), r(0, 0));
  } else {  // gimbal lock: put everything in yaw
    p[kRoll] = 0.0;
    p[kYaw] = std::atan2(-r(0, 1), r(1, 1));
  }
  return p;
}

Pose6 makePose(double x, double y, double z, double roll, double pitch, double yaw) {
  Pose6 p;
  p << x, y, z, roll, pitch, yaw;
  return p;
}

double wrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0) a += 2.0 * M_PI;
  return a - M_PI;
}

Pose6 poseDifference(const Pose6& a, const Pose6& b) {
  Pose6 d = a - b;
  for (int i = 3; i < 6; ++i) d[i] = wrapAngle(d[i]);
  return d;
}

}  // namespace calibration
}  // namespace ladar_perception
