// Gaussian re-weighted least squares plane (thesis 3.1, Algorithm 1; algorithms.md).
#include "ladar_perception/ground/plane_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace ladar_perception {

bool fitPlaneGaussianReweighted(const float* x, const float* y, const float* z, int n,
                                const PlaneFitParams& params, Eigen::Vector3d* c) {
  const double sigma = params.sigma > 0.f ? params.sigma : 0.2;
  const double inv_two_sigma2 = 1.0 / (2.0 * sigma * sigma);
  bool ok = n >= 3;
  for (int it = 0; it < params.max_iterations && ok; ++it) {
    const Eigen::Vector3d cc = *c;
    const double inv_norm = 1.0 / cc.norm();
    // Normal equations of diag(w) P c = w: (sum w_i^2 p_i p_i^T) c = sum w_i^2 p_i, with
    // w_i^2 = exp(-e_i^2 / (2 sigma^2)).
    double m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0, m22 = 0, b0 = 0, b1 = 0, b2 = 0;
    for (int i = 0; i < n; ++i) {
      const double px = x[i], py = y[i], pz = z[i];
      const double e = (px * cc.x() + py * cc.y() + pz * cc.z() - 1.0) * inv_norm;
      const double w2 = std::exp(-e * e * inv_two_sigma2);
      m00 += w2 * px * px;
      m01 += w2 * px * py;
      m02 += w2 * px * pz;
      m11 += w2 * py * py;
      m12 += w2 * py * pz;
      m22 += w2 * pz * pz;
      b0 += w2 * px;
      b1 += w2 * py;
      b2 += w2 * pz;
    }
    Eigen::Matrix3d m;
    m << m00, m01, m02, m01, m11, m12, m02, m12, m22;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(m);
    if (ldlt.info() != Eigen::Success || !(std::fabs(m.determinant()) > 1e-12 * std::pow(m.trace(), 3))) {
      ok = false;
      break;
    }
    const Eigen::Vector3d next = ldlt.solve(Eigen::Vector3d(b0, b1, b2));
    if (!next.allFinite() || next.norm() < 1e-9) {
      ok = false;
      break;
    }
    *c = next;
  }
  return ok;
}

void PlaneFitGround::classify(const PointCloudView& view, const SensorPose& pose,
                              GroundClassification* out) {
  const std::size_t n = view.size();
  out->resize(n);
  x_.clear();
  y_.clear();
  z_.clear();
  index_.clear();
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const RangeGate gate(params_.min_range, params_.max_range);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    out->labels[i] = kLabelUnknown;
    out->p_obstacle[i] = 0.f;
    if (!gate.admits(p)) continue;
    const Eigen::Vector3f q = R * p;  // gravity aligned, origin at the sensor
    x_.push_back(q.x());
    y_.push_back(q.y());
    z_.push_back(q.z());
    index_.push_back(static_cast<uint32_t>(i));
  }
  // Seed: level ground sensor_height below the sensor.
  const double h = std::max(0.3f, pose.height());
  Eigen::Vector3d c(0.0, 0.0, -1.0 / h);
  if (!fitPlaneGaussianReweighted(x_.data(), y_.data(), z_.data(), static_cast<int>(x_.size()),
                                  params_, &c)) {
    // Too few or degenerate points: keep the last good estimate (or the seed).
    if (x_.size() < 3) return;  // nothing to label against
  }
  plane_ = c;
  const float thr = params_.inlier_threshold > 0.f ? params_.inlier_threshold : 0.2f;
  for (std::size_t k = 0; k < index_.size(); ++k) {
    const float height = heightAbovePlane(c, x_[k], y_[k], z_[k]);
    const float a = std::fabs(height);
    const uint32_t i = index_[k];
    out->labels[i] = a < thr ? kLabelGround : kLabelObstacle;
    out->p_obstacle[i] = std::min(a / (2.f * thr), 1.f);
  }
}

bool estimateMountFromGround(const PointCloudView& view, float seed_height, MountEstimate* mount) {
  PlaneFitParams params;
  params.max_iterations = 20;
  std::vector<float> x, y, z;
  const RangeGate gate(params.min_range, 40.f);
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    if (!gate.admits(p)) continue;
    x.push_back(p.x());
    y.push_back(p.y());
    z.push_back(p.z());
  }
  const int n = static_cast<int>(x.size());
  if (n < 100) return false;
  Eigen::Vector3d c(0.0, 0.0, -1.0 / std::max(0.3f, seed_height));
  if (!fitPlaneGaussianReweighted(x.data(), y.data(), z.data(), n, params, &c) || !(c.z() < 0.0)) return false;
  // The plane n . p = d with n = c / |c| pointing down to it, d = 1 / |c| the height; up = -n
  // in the sensor frame is R^T e_z for R = Ry(pitch) Rx(roll): (-sin p, sin r cos p, cos r cos p).
  const Eigen::Vector3d up = -c.normalized();
  mount->height = static_cast<float>(1.0 / c.norm());
  mount->pitch_deg = static_cast<float>(std::asin(std::max(-1.0, std::min(1.0, -up.x()))) * 180.0 / M_PI);
  mount->roll_deg = static_cast<float>(std::atan2(up.y(), up.z()) * 180.0 / M_PI);
  mount->returns = x.size();
  std::size_t inliers = 0;
  for (int i = 0; i < n; ++i) inliers += std::fabs(heightAbovePlane(c, x[i], y[i], z[i])) < params.sigma;
  mount->inlier_fraction = static_cast<double>(inliers) / n;
  return true;
}

}  // namespace ladar_perception
