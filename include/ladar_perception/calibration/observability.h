// Observability check from the curvature of the cost at the solution: the eigenvectors of the
// Gauss-Newton Hessian J^T W J (rotations scaled by the lever arm so metres and radians compare).
// Directions the scene cannot fix (the long axis of an alley; x, y and yaw over a flat plane)
// are weak: with per-point losses, those whose measured curvature is not significantly above
// the points' noise, or too small for the accuracy wanted (see min_significance); without them,
// those whose curvature is a small fraction of the strongest. The DOFs lying mostly in the weak
// subspace are named, and their standard deviations are infinite instead of a made-up figure.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ladar_perception/calibration/pose.h"

namespace ladar_perception {
namespace calibration {

struct ObservabilityParams {
  // A direction whose curvature is below this fraction of the largest is weak.
  double relative_threshold = 0.006;
  // A direction whose predicted standard deviation sqrt(sigma^2 / (N * curvature)) exceeds this
  // is weak too [m; rotations in metres at the lever arm].
  double max_stddev = 0.05;
  // A DOF is unobservable when at least this fraction of its unit vector lies in the weak subspace.
  double min_projection = 0.5;
  // Probe length for the measured curvature [m; radians are scaled by the lever arm].
  double probe = 0.1;
  // With per-point losses (LossesAlong): a direction is fixed only when its measured curvature,
  // the mean of the points' second differences, is at least this many standard errors above
  // zero (a flat direction's re-associated cost only wobbles), and a DOF is unobservable when
  // its standard deviation sqrt(diag(sigma^2 / N * H_measured^-1)) exceeds the accuracy wanted
  // (max_stddev [m], max_stddev_rotation [rad]); the relative threshold is then not used.
  double min_significance = 3.0;
  double max_stddev_rotation = 0.01;
  // The reported standard deviations (Observability::stddev) come from the cluster-robust
  // sandwich H^-1 M H^-1, M the covariance of the scores summed over cubes of this size [m]
  // around the reference surface points (Linearisation::score_covariance), never below
  // sigma^2 H^-1; 0 = sigma^2 H^-1 alone, which treats every residual as independent. The
  // residuals on one surface patch share its modelling error (a plane fitted to noisy returns
  // leans or sits off as a whole): on the thesis experiment sigma^2 H^-1 was a median 2.5x
  // (Velodyne-Velodyne) and 7-8x (SICK-Velodyne) smaller than the errors; with 8 m cubes 0.9x
  // and 1.2-2.1x (calibration_benchmark's "reported stddev" line; 2 m: 1.2x and 4x).
  double score_cluster = 8.0;
  // Fewer clusters than this estimate M too poorly (rank 6 needs 7): sigma^2 H^-1 alone.
  int min_score_clusters = 12;
};

// The cost at the solution moved by a step in (x, y, z, rotation) coordinates (see refinement.h).
using CostAlong = std::function<double(const Pose6& step)>;
// The same, each target point's loss (NaN without a correspondence) into *losses.
using LossesAlong = std::function<void(const Pose6& step, std::vector<float>* losses)>;

struct Observability {
  // sqrt(max(diag(H^+ M H^+), diag(sigma^2 H^+))) with score_covariance M, else
  // sqrt(diag(sigma^2 H^+)), over the fixed directions; infinity for an unobservable DOF.
  Pose6 stddev = Pose6::Zero();
  std::vector<int> unobservable;         // DOF indices
  std::vector<std::string> unobservable_names;
  Pose6 eigenvalues = Pose6::Zero();     // of the scaled, per-correspondence Hessian, ascending
  Pose6 curvature = Pose6::Zero();       // measured along the same eigenvectors (or = eigenvalues)
  // Per DOF, the standard deviation from the measured curvature and the residual variance,
  // sqrt(diag(S V diag(sigma^2 / (N c_k)) V^T S)) [m, rad]; infinity along a flat direction.
  Pose6 measured_stddev = Pose6::Zero();
  // Per eigenvector: the measured curvature over its standard error (LossesAlong only, else 0).
  Pose6 significance = Pose6::Zero();
  double relative_min = 0;               // smallest / largest scaled eigenvalue
  bool observable() const { return unobservable.empty(); }
};

// hessian: J^T W J in (x, y, z, rotation) coordinates; residual_variance: sigma^2 of a residual;
// correspondences: number of residuals; lever_arm: metres per radian for the scaling.
// When cost_along is given, the curvature along each eigenvector of the Hessian is measured on
// the cost itself (central second difference, correspondences re-associated at each probe):
// J^T W J alone credits the noise in the reference normals with information, so a flat plane
// would seem to fix x and y a little; the measured curvature does not.
// score_covariance, when given: M of the sandwich covariance H^+ M H^+ of the reported stddev
// (Linearisation::score_covariance); each DOF's variance is the larger of that and sigma^2 H^+.
Observability analyseObservability(const Matrix6& hessian, double residual_variance,
                                   long correspondences, double lever_arm,
                                   const ObservabilityParams& params = ObservabilityParams(),
                                   const CostAlong& cost_along = nullptr,
                                   const LossesAlong& losses_along = nullptr,
                                   const Matrix6* score_covariance = nullptr);

}  // namespace calibration
}  // namespace ladar_perception
