// Gaussian re-weighted linear least squares ground plane (thesis 3.1, Algorithm 1): a baseline
// ground model ("plane"). The thesis shows it works on a single plane and fails on crowned
// roads and multi-planar scenes; it is kept to measure exactly that.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"

namespace ladar_perception {

struct PlaneFitParams {
  int max_iterations = 10;        // MaxIterations of Algorithm 1
  float sigma = 0.2f;             // [m] width of the Gaussian re-weighting
  float inlier_threshold = 0.2f;  // [m] |distance to the plane| below this: ground
  float min_range = 1.0f;         // returns closer or farther than these are unknown [m]
  float max_range = 120.0f;
};

// Algorithm 1 on n points of a gravity-aligned frame whose origin is the sensor (the plane
// A x + B y + C z = 1 cannot pass through it). *c holds the seed on entry and the fitted
// (A, B, C) on return. Each iteration: e_i = (p_i . c - 1) / |c|,
// w_i = sqrt(exp(-e_i^2 / (2 sigma^2))), solve diag(w) P c = w in the least-squares sense.
// False (c unchanged from the last good iteration) when the weighted system is singular.
bool fitPlaneGaussianReweighted(const float* x, const float* y, const float* z, int n,
                                const PlaneFitParams& params, Eigen::Vector3d* c);

// Signed distance of a point to the plane c along its normal, positive on the sensor's side
// (above the ground).
inline float heightAbovePlane(const Eigen::Vector3d& c, float x, float y, float z) {
  return static_cast<float>((1.0 - (c.x() * x + c.y() * y + c.z() * z)) / c.norm());
}

// The plane as a GroundModel: one plane per scan, seeded with the level ground sensor_height
// below the sensor; |height above the plane| < inlier_threshold is ground, else obstacle;
// P(obstacle) = min(|height| / (2 inlier_threshold), 1), so 0.5 is the label boundary.
class PlaneFitGround : public GroundModel {
 public:
  explicit PlaneFitGround(const PlaneFitParams& params = PlaneFitParams()) : params_(params) {}
  std::string name() const override { return "plane"; }
  void classify(const PointCloudView& view, const SensorPose& pose,
                GroundClassification* out) override;
  // The plane of the last scan in the gravity-aligned sensor frame.
  const Eigen::Vector3d& plane() const { return plane_; }

 private:
  PlaneFitParams params_;
  Eigen::Vector3d plane_ = Eigen::Vector3d(0, 0, -1);
  std::vector<float> x_, y_, z_;
  std::vector<uint32_t> index_;
};

// The mount of a sensor whose height and tilt are not known, from one scan (sensor frame): the
// ground plane of Algorithm 1 fitted to the returns within [min_range, 40 m] (seeded with level
// ground seed_height below the sensor), as the sensor's height above it and the roll and pitch
// that level it (SensorPose::fromMount conventions). False when fewer than 100 returns take
// part or the fit is degenerate.
struct MountEstimate {
  float height = 0.f, roll_deg = 0.f, pitch_deg = 0.f;
  std::size_t returns = 0;   // returns in the fit
  double inlier_fraction = 0.0;  // of them within the fit's sigma of the plane
};
bool estimateMountFromGround(const PointCloudView& view, float seed_height, MountEstimate* mount);

}  // namespace ladar_perception
