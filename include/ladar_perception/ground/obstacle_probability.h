// Probability of obstacle (thesis eq 3.15), shared by the vertical scan method (3.3) and the
// Hough ground fit (3.3.4).
#pragma once

#include <algorithm>
#include <cmath>

namespace ladar_perception {

// Tolerances that grow with HorizontalDistance r: near the car they are almost constant, far
// away they widen with the measurement uncertainty (thesis 3.3.5, Figure 3.6).
struct ObstacleToleranceParams {
  float gnd_error_max_base = 0.15f;     // GndErrorMax at r = 0 [m]
  float gnd_error_max_per_m = 0.004f;   // growth of GndErrorMax per metre of r [m/m]
  float slope_error_max_base = 0.15f;   // SlopeErrorMax at r = 0 [-]
  float slope_error_max_per_m = 0.0f;   // growth of SlopeErrorMax per metre of r [1/m]
  float obstacle_threshold = 0.5f;      // P(obstacle) above which a return is an obstacle
};

inline float gndErrorMax(const ObstacleToleranceParams& p, float r) {
  return p.gnd_error_max_base + p.gnd_error_max_per_m * r;
}
inline float slopeErrorMax(const ObstacleToleranceParams& p, float r) {
  return p.slope_error_max_base + p.slope_error_max_per_m * r;
}

// Eq 3.15: P = min(|GndError|, GndErrorMax)/GndErrorMax * min(|SlopeError|, SlopeErrorMax)/SlopeErrorMax.
// Absolute values, so returns below the ground line (negative obstacles) score too.
inline float obstacleProbability(float gnd_error, float slope_error, float r,
                                 const ObstacleToleranceParams& p) {
  const float g_max = gndErrorMax(p, r);
  const float s_max = slopeErrorMax(p, r);
  const float g = std::min(std::fabs(gnd_error), g_max) / g_max;
  const float s = std::min(std::fabs(slope_error), s_max) / s_max;
  return g * s;
}

}  // namespace ladar_perception
