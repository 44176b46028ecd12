// Vertical scan ground extraction for a Velodyne-style 3D ladar (thesis 3.3, algorithms.md).
// DRAFT interface written by the package skeleton; the owner of the algorithm may extend the
// params (keep cfg/VerticalScanGround.cfg, config/vertical_scan_ground.yaml and
// src/ros/vertical_scan_params_ros.cpp in step with it).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/obstacle_probability.h"

namespace ladar_perception {

struct VerticalScanParams {
  // --- Binning (3.3 step 1): rows by laser, columns by azimuth, median range per bin.
  float column_width_deg = 1.5f;          // azimuth width of a vertical scan [deg]
  // Laser elevations used to assign a row when the cloud has no `ring` field [deg];
  // empty = the HDL-64E table (laser_elevations.h).
  std::vector<float> laser_elevations_deg;
  float min_range = 1.0f;                 // returns closer than this are unknown [m]
  float max_range = 120.0f;               // returns farther than this are unknown [m]

  // --- Feasibility (eq 3.4): GroundSlopeMin < Height / r < GroundSlopeMax.
  float ground_slope_min = -0.35f;
  float ground_slope_max = 0.35f;

  // --- Slope estimate (eqs 3.6-3.9).
  int iterations = 9;
  float weight_bias = 0.02f;              // WeightBias of eq 3.6: biases the fit downward

  // --- Obstacle probability (eq 3.15).
  ObstacleToleranceParams tolerances;

  // --- Beyond the thesis (5.1.2 future work). All off in the thesis mode.
  bool bend_ground_line = true;           // piecewise ground line: slope may change with r
  float segment_length = 10.0f;           // radial length of one ground-line segment [m]
  bool couple_columns = true;             // neighbouring columns share ground evidence
  int coupling_radius = 2;                // columns on each side that are coupled
  int min_ground_returns = 3;             // fewer feasible returns: borrow from neighbours
  bool negative_obstacles = true;         // returns well below the ground line are obstacles
};

// Settings by name: "thesis" (the thesis's method and settings) and "default" (beyond it).
VerticalScanParams verticalScanThesisParams();
VerticalScanParams verticalScanDefaultParams();

// The vertical scan method as a GroundModel with the given params (used by the nodelet, which
// rebuilds the model when dynamic_reconfigure changes a parameter). Declared here by the lead
// for the ROS adapter; implement it next to the algorithm.
class GroundModel;
std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params);

}  // namespace ladar_perception
