#include "ladar_perception/calibration/scan_plane.h"

#include <algorithm>
#include <cmath>

namespace ladar_perception {
namespace calibration {

namespace {
// The ground line of the scan plane: direction d and the point q closest to the sensor.
bool groundLine(const Eigen::Isometry3d& t, double ground_z, double max_distance,
                Eigen::Vector3d* d, Eigen::Vector3d* q) {
  const Eigen::Vector3d s = t.translation();
  const Eigen::Vector3d n = t.linear().col(2);  // scan plane normal
  *d = n.cross(Eigen::Vector3d::UnitZ());
  if (d->norm() < 1e-6) return false;  // plane parallel to the ground
  d->normalize();
  const Eigen::Vector3d m = n.cross(*d);  // in the plane, across the line
  if (std::abs(m.z()) < 1e-9) return false;
  const double reach = (ground_z - s.z()) / m.z();
  if (!std::isfinite(reach) || std::abs(reach) > max_distance) return false;
  *q = s + reach * m;
  return true;
}
}  // namespace

bool rotateAboutGroundLine(const Pose6& extrinsic, double angle, double ground_z, Pose6* out,
                           double max_distance) {
  const Eigen::Isometry3d t = toIsometry(extrinsic);
  Eigen::Vector3d d, q;
  if (!groundLine(t, ground_z, max_distance, &d, &q)) return false;
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(angle, d).toRotationMatrix();
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = rot * t.linear();
  moved.translation() = q + rot * (t.translation() - q);
  *out = fromIsometry(moved);
  return out->allFinite();
}

bool groundLineStepDirection(const Pose6& extrinsic, double ground_z, Pose6* direction,
                             double max_distance) {
  const Eigen::Isometry3d t = toIsometry(extrinsic);
  Eigen::Vector3d d, q;
  if (!groundLine(t, ground_z, max_distance, &d, &q)) return false;
  direction->head<3>() = d.cross(t.translation() - q);
  direction->tail<3>() = d;
  return true;
}

bool grazesGround(const Pose6& extrinsic, double ground_z, double min_incidence, double max_range) {
  if (!(min_incidence > 0)) return false;
  const Eigen::Isometry3d t = toIsometry(extrinsic);
  const double nz = std::min(1.0, std::abs(t.linear()(2, 2)));  // the plane normal's z
  const double tilt = std::acos(nz);  // angle between the scan plane and the ground
  if (tilt >= min_incidence) return false;
  // The scan plane meets the ground at distance height / sin(tilt) from the sensor.
  const double height = std::abs(t.translation().z() - ground_z);
  return height < max_range * std::sin(tilt) || height < 1e-3;
}

bool refinedAlike(const SweepMember& a, const SweepMember& b, double ground_z, double tolerance) {
  Pose6 rotated = a.pose;
  if (std::abs(b.angle - a.angle) > 0 &&
      !rotateAboutGroundLine(a.pose, b.angle - a.angle, ground_z, &rotated)) {
    return false;
  }
  return (rotated.head<2>() - b.pose.head<2>()).cwiseAbs().maxCoeff() <= tolerance;
}

bool sweepProfileMinimum(const std::vector<SweepMember>& members, const SweepMember& best,
                         double ground_z, double tolerance, double* minimum, std::size_t* nearest,
                         double* relative_curvature) {
  std::vector<std::size_t> alike;
  for (std::size_t i = 0; i < members.size(); ++i) {
    if (refinedAlike(best, members[i], ground_z, tolerance)) alike.push_back(i);
  }
  if (alike.size() < 3) return false;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  double lo = members[alike[0]].angle, hi = lo;
  for (std::size_t i : alike) {
    const SweepMember& m = members[i];
    const Eigen::Vector3d row(m.angle * m.angle, m.angle, 1.0);
    ata += row * row.transpose();
    atb += m.cost * row;
    lo = std::min(lo, m.angle);
    hi = std::max(hi, m.angle);
  }
  const Eigen::Vector3d abc = ata.ldlt().solve(atb);
  if (!abc.allFinite() || !(abc[0] > 0)) return false;
  if (relative_curvature) {
    const double at_minimum = abc[2] - 0.25 * abc[1] * abc[1] / abc[0];
    *relative_curvature = at_minimum > 0 ? abc[0] / at_minimum : 0.0;
  }
  *minimum = std::max(lo, std::min(hi, -0.5 * abc[1] / abc[0]));
  *nearest = alike[0];
  for (std::size_t i : alike) {
    if (std::abs(members[i].angle - *minimum) < std::abs(members[*nearest].angle - *minimum)) *nearest = i;
  }
  return true;
}

}  // namespace calibration
}  // namespace ladar_perception
