#include "ladar_perception/calibration/observability.h"

#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace ladar_perception {
namespace calibration {

Observability analyseObservability(const Matrix6& hessian, double residual_variance,
                                   long correspondences, double lever_arm,
                                   const ObservabilityParams& params,
                                   const CostAlong& cost_along,
                                   const LossesAlong& losses_along,
                                   const Matrix6* score_covariance) {
  Observability out;
  const double inf = std::numeric_limits<double>::infinity();
  if (correspondences <= 0 || !hessian.allFinite()) {
    out.stddev.setConstant(inf);
    for (int i = 0; i < 6; ++i) {
      out.unobservable.push_back(i);
      out.unobservable_names.push_back(dofName(i));
    }
    return out;
  }
  // u = S^-1 * (t, w) with S = diag(1,1,1,1/L,1/L,1/L): rotations in metres at the lever arm.
  Pose6 s;
  const double l = std::max(lever_arm, 1e-3);
  s << 1, 1, 1, 1 / l, 1 / l, 1 / l;
  const Matrix6 hs = s.asDiagonal() * hessian * s.asDiagonal() / static_cast<double>(correspondences);
  Eigen::SelfAdjointEigenSolver<Matrix6> es(hs);
  out.eigenvalues = es.eigenvalues();
  out.curvature = out.eigenvalues;
  const bool by_points = static_cast<bool>(losses_along);
  if (by_points) {
    // Per point: d_i = l_i(+h v) + l_i(-h v) - 2 l_i(0); curvature = mean(d) / h^2, its
    // standard error sd(d) / sqrt(n) / h^2 (points with a correspondence at all three).
    std::vector<float> l0, lp, lm;
    losses_along(Pose6::Zero(), &l0);
    const double h = params.probe;
    for (int k = 0; k < 6; ++k) {
      const Pose6 step = s.asDiagonal() * (h * es.eigenvectors().col(k));
      losses_along(step, &lp);
      losses_along(-step, &lm);
      double sum = 0, sum2 = 0;
      long n = 0;
      const std::size_t m = std::min(l0.size(), std::min(lp.size(), lm.size()));
      for (std::size_t i = 0; i < m; ++i) {
        const double d = static_cast<double>(lp[i]) + lm[i] - 2.0 * l0[i];
        if (!std::isfinite(d)) continue;
        sum += d;
        sum2 += d * d;
        ++n;
      }
      if (n < 2) {
        out.curvature[k] = 0;
        continue;
      }
      const double mean = sum / n;
      const double var = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
      const double se = std::sqrt(var / n);
      out.curvature[k] = std::max(0.0, mean / (h * h));
      out.significance[k] = se > 0 ? mean / se : (mean > 0 ? inf : 0.0);
    }
  } else if (cost_along) {
    const double c0 = cost_along(Pose6::Zero());
    const double h = params.probe;
    for (int k = 0; k < 6; ++k) {
      const Pose6 step = s.asDiagonal() * (h * es.eigenvectors().col(k));
      const double c = (cost_along(step) + cost_along(-step) - 2.0 * c0) / (h * h);
      out.curvature[k] = std::isfinite(c) ? std::max(0.0, c) : 0.0;
    }
  }
  const double top = std::max(out.curvature.maxCoeff(), 1e-300);
  {
    // Covariance sigma^2 / N * (measured Hessian)^-1 back in (t, w) units; a direction measured
    // flat (curvature <= 0, or 1e-12 of the strongest) counts as next to infinitely uncertain.
    Pose6 var = Pose6::Zero();
    for (int k = 0; k < 6; ++k) {
      const Pose6 v = s.asDiagonal() * es.eigenvectors().col(k);
      const double c = std::max(out.curvature[k], 1e-12 * top);
      var += v.cwiseAbs2() * (residual_variance / (static_cast<double>(correspondences) * c));
    }
    out.measured_stddev = var.cwiseSqrt();
  }
  out.relative_min = out.curvature.minCoeff() / top;
  // Weak: flat relative to the strongest direction, or too flat to fix the solution to
  // max_stddev given the residual noise and the number of correspondences.
  std::array<bool, 6> weak{};
  for (int k = 0; k < 6; ++k) {
    const double predicted =
        out.curvature[k] > 0
            ? std::sqrt(residual_variance / (static_cast<double>(correspondences) * out.curvature[k]))
            : inf;
    weak[k] = by_points ? out.significance[k] < params.min_significance
                        : out.curvature[k] < params.relative_threshold * top ||
                              predicted > params.max_stddev;
  }
  Matrix6 weak_projector = Matrix6::Zero();
  Matrix6 pinv = Matrix6::Zero();  // pseudo-inverse over the strong directions
  for (int k = 0; k < 6; ++k) {
    const Pose6 v = es.eigenvectors().col(k);
    if (weak[k]) {
      weak_projector += v * v.transpose();
    } else {
      pinv += v * v.transpose() / std::max(out.eigenvalues[k], 1e-300);
    }
  }
  // Back to (t, w) units; the per-correspondence normalisation comes off with 1/N. Over the
  // fixed directions H^+ = S pinv S / N: the variances of sigma^2 H^+, and of the sandwich
  // H^+ M H^+ of the cluster sums' score covariance M when given (the larger of the two).
  const Matrix6 h_pinv = s.asDiagonal() * pinv * s.asDiagonal() / static_cast<double>(correspondences);
  Pose6 variance = residual_variance * h_pinv.diagonal();
  if (score_covariance && score_covariance->allFinite()) {
    variance = variance.cwiseMax((h_pinv * (*score_covariance) * h_pinv).diagonal());
  }
  // Each weak direction names at least its dominant DOF, even when it mixes several.
  std::array<bool, 6> weak_dof{};
  for (int i = 0; i < 6; ++i) weak_dof[i] = weak_projector(i, i) >= params.min_projection;
  if (by_points) {
    // The accuracy wanted, per DOF, against the standard deviation from the measured curvature.
    for (int i = 0; i < 6; ++i) {
      const double tol = i < 3 ? params.max_stddev : params.max_stddev_rotation;
      if (out.measured_stddev[i] > tol) weak_dof[i] = true;
    }
  }
  for (int k = 0; k < 6; ++k) {
    if (!weak[k]) continue;
    int dominant = 0;
    es.eigenvectors().col(k).cwiseAbs().maxCoeff(&dominant);
    weak_dof[dominant] = true;
  }
  for (int i = 0; i < 6; ++i) {
    if (weak_dof[i]) {
      out.unobservable.push_back(i);
      out.unobservable_names.push_back(dofName(i));
      out.stddev[i] = inf;
    } else {
      out.stddev[i] = std::sqrt(std::max(0.0, variance[i]));
    }
  }
  return out;
}

}  // namespace calibration
}  // namespace ladar_perception
