// Refinement on the dense accumulated clouds (beyond the thesis): robust point-to-plane
// Gauss-Newton / Levenberg-Marquardt. The reference cloud, accumulated in the odom frame through
// its known extrinsic, becomes a surface model (points with normals from their neighbourhood,
// KD-tree built once); every target point, projected through its scan's vehicle pose and the
// hypothesis, gives the residual r = n . (p_odom - q) to its closest surface point q, weighted by
// a Huber loss. The Gauss-Newton Hessian J^T W J at the solution is the cost's curvature that the
// observability check reads.
//
// Parametrisation of a step: t += dt (base_link frame), R = Exp(dw) * R (rotation about the
// sensor's origin, base_link axes), so steps map one to one onto x, y, z and, near a level
// mount, roll, pitch, yaw.
#pragma once

#include <string>
#include <vector>

#include "ladar_perception/calibration/accumulation.h"
#include "ladar_perception/calibration/kdtree.h"
#include "ladar_perception/calibration/nearest_grid.h"
#include "ladar_perception/calibration/pose.h"
#include "ladar_perception/calibration/search.h"

namespace ladar_perception {
namespace calibration {

struct RefinementParams {
  double reference_voxel = 0.2;  // dense reference resolution [m]
  double target_voxel = 0.3;     // dense target resolution, per scan in the sensor frame [m]
  int max_target_points = 60000; // evenly thinned beyond this (speed bound)
  int normal_neighbours = 16;
  double normal_radius = 1.5;    // neighbours farther than this are not used for a normal [m]
  double max_curvature = 0.04;   // lambda_min / sum(lambda) above this: not a surface point
  double max_correspondence_start = 1.5;  // [m], shrinks linearly to the end value
  double max_correspondence_end = 0.5;
  double huber = 0.1;            // [m]
  int max_iterations = 30;
  double convergence = 1e-5;     // step norm (m, rad) below which it stops
  double damping = 1e-4;         // Levenberg-Marquardt lambda relative to diag(H)
  // Keep the reference points that are not on a surface (edges, corners, poles, thin objects)
  // as point-to-point correspondences (normal zero, three residuals) instead of dropping them.
  // Used for 2D targets: many of a tilted 2D ladar's object returns fall on car edges and poles,
  // and without them those returns find no correspondence while the degenerate mount that lays
  // every return on the ground finds one for each (scan_plane.h).
  bool keep_edges = false;
  // When non-zero: a direction in step coordinates (dx, dy, dz, dwx, dwy, dwz) the refinement
  // must not move along (the steps are solved in its orthogonal complement). The calibrator
  // holds a 2D ladar's ground-line rotation fixed this way while it profiles the cost along it.
  Pose6 frozen_direction = Pose6::Zero();
  // When > 0 [m]: each residual is weighted by noise_floor / sqrt(noise_floor^2 + s_j^2), s_j the
  // RMS spread of its reference neighbourhood about the local plane (or about its centroid for
  // an edge point), so that a return on a noisily modelled surface (a car side seen by a 0.2 m
  // noise Velodyne) counts for less than one on a crisp surface (the ground seen at grazing
  // angles). Used for 2D targets: without it their cost prefers mounts that move object returns
  // onto the crisper ground.
  double noise_floor = 0.0;
  // When > 0 (and noise_floor > 0) [m]: the target's range noise (Table 4.1 accuracy). A range
  // error moves a return along its ray, so its share of the point-to-plane residual is
  // range_noise * (u . n), u the ray. Left unweighted, a noisy 2D ladar's ground returns fit the
  // ground better the flatter its scan plane lies (the residual shrinks with u . n): the
  // ground-line family (scan_plane.h) is then biased towards a lower tilt. The residual is
  // instead weighted by its expected spread: noise_floor / sqrt(range_noise^2 (u . n)^2 +
  // s_j^2 / normal_neighbours + reference_noise^2) for a plane point (s_j / sqrt(k): the
  // uncertainty of the fitted plane, not the raw spread), noise_floor / sqrt(range_noise^2 +
  // s_j^2) for an edge point. Ground and vertical faces are treated alike. The calibrator uses it
  // to score the members of a 2D ladar's ground-line sweep (CalibrationParams::sparse_range_noise).
  double range_noise = 0.0;
  double reference_noise = 0.0;  // [m] the floor of the reference plane's uncertainty
  // [1/m] A target whose range noise grows with range squared (a stereo camera: depth from
  // disparity, sigma = depth^2 sigma_d / (f b)): its range noise at range r is range_noise +
  // range_noise_per_m2 r^2, in the weighting above (with noise_floor > 0). 0 = constant.
  double range_noise_per_m2 = 0.0;
  // When > 0: after each Gauss-Newton step the step doubled, up to this many times, is tried and
  // kept while the robust cost over all target points (robustCostOverAll) keeps falling. Along a
  // weak direction (a 2D ladar's x and y over mostly flat ground) the nearest-neighbour
  // correspondences re-form after each step and pull back: each step then covers only a few
  // per cent of the way (2.5 mm per iteration from 0.13 m off in y, 30 iterations left it 6 cm
  // off), and the refinement stalls short of the minimum. 0 = plain Gauss-Newton.
  int extrapolation_steps = 0;
};

// Reference points with normals, ready for correspondences.
class SurfaceModel {
 public:
  // points: the reference accumulated in the odom frame (already downsampled or not).
  void build(const PointVector& points, const RefinementParams& params);
  bool empty() const { return tree_.empty(); }
  std::size_t size() const { return points_.size(); }
  const KdTree& tree() const { return tree_; }
  // Index of the closest surface point within sqrt(max_sq_dist), or -1 (KdTree::nearest's
  // answer): from the grid of max_correspondence_end cells when it decides, else the KD-tree.
  int nearest(const Eigen::Vector3f& query, float* sq_dist, float max_sq_dist) const {
    const int j = grid_.nearest(query, sq_dist, max_sq_dist);
    return j != NearestGrid::kUndecided ? j : tree_.nearest(query, sq_dist, max_sq_dist);
  }
  const PointVector& points() const { return points_; }
  // Unit normal of a surface point; zero for an edge point (point-to-point).
  const PointVector& normals() const { return normals_; }
  // RMS spread of each point's neighbourhood about its plane (centroid for edge points) [m].
  const std::vector<float>& spreads() const { return spreads_; }
  // The neighbourhood size of the plane fits (a plane's uncertainty is about spread / sqrt(k)).
  int neighbours() const { return neighbours_; }

 private:
  PointVector points_, normals_;  // surface points (and edge points when keep_edges)
  std::vector<float> spreads_;
  int neighbours_ = 1;
  KdTree tree_;
  NearestGrid grid_;
};

// The linearised problem at one hypothesis.
struct Linearisation {
  Matrix6 hessian = Matrix6::Zero();   // J^T W J
  Pose6 gradient = Pose6::Zero();      // J^T W r
  double cost = 0;                     // mean Huber loss over the correspondences
  double residual_variance = 0;        // weighted mean r^2
  long correspondences = 0;
  double lever_arm = 1.0;              // RMS distance of the target points from their sensor [m]
  // Filled when linearise is given a score cluster size: the target points' scores (each
  // residual's w r J, the terms of the gradient) summed per cluster of their surface points (a
  // cube of that size in the odom frame), and the covariance of those cluster sums, times the
  // number of clusters: the "meat" of a cluster-robust sandwich covariance H^-1 M H^-1. The
  // residuals of points on one reference surface patch share its modelling error (a plane
  // fitted to noisy returns leans or sits off as a whole), so they are not independent, and
  // sigma^2 H^-1 alone is over-confident (observability.h).
  Matrix6 score_covariance = Matrix6::Zero();
  long score_clusters = 0;
};

Linearisation linearise(const SurfaceModel& model, const ScanSet& target, const Pose6& extrinsic,
                        double max_correspondence, double huber, double noise_floor = 0.0,
                        double range_noise = 0.0, double reference_noise = 0.0,
                        std::vector<float>* point_loss = nullptr, double score_cluster = 0.0,
                        double range_noise_per_m2 = 0.0);
// The same with the weighting of `params` (noise_floor, range_noise, range_noise_per_m2,
// reference_noise, huber).
// point_loss, when given: each target point's Huber loss, NaN without a correspondence (sized
// once per call, not per point). score_cluster > 0 [m]: also the score covariance over clusters
// of that size (Linearisation::score_covariance).
Linearisation linearise(const SurfaceModel& model, const ScanSet& target, const Pose6& extrinsic,
                        double max_correspondence, const RefinementParams& params,
                        std::vector<float>* point_loss = nullptr, double score_cluster = 0.0);

struct RefinementResult {
  Pose6 extrinsic = Pose6::Zero();
  Linearisation at_solution;
  int iterations = 0;
  bool converged = false;
  bool cancelled = false;
  std::vector<Pose6> trace;
};

// The robust cost over ALL target points at a linearisation: the mean of the correspondences'
// Huber loss with a point without a correspondence counted at the loss of max_correspondence
// (so that pushing points away from every surface does not pay).
double robustCostOverAll(const Linearisation& lin, std::size_t target_points,
                         double max_correspondence, double huber);

// Applies a step in the parametrisation above.
Pose6 applyStep(const Pose6& extrinsic, const Pose6& step);

// The target scans thinned for the refinement (voxel per scan, then evenly to max_target_points).
ScanSet refinementTarget(const ScanSet& target, const RefinementParams& params);

// Normal-space thinning (the simplest form of Rusinkiewicz and Levoy's normal-space sampling):
// the target points whose closest surface point at `extrinsic` (within max_correspondence) has a
// near-vertical normal (|n_z| >= min_normal_z, odom frame) are kept one in keep_every, in scan
// order; every other point is kept. A tilted 2D ladar puts two thirds of its returns on the
// ground: thinned, the ground no longer outweighs the few returns on faces that fix x and y.
ScanSet thinLevelSurfaceReturns(const SurfaceModel& model, const ScanSet& target,
                                const Pose6& extrinsic, double max_correspondence,
                                double min_normal_z, int keep_every);

RefinementResult refine(const SurfaceModel& model, const ScanSet& target, const Pose6& initial,
                        const RefinementParams& params, const ProgressFn& progress = nullptr);

}  // namespace calibration
}  // namespace ladar_perception
