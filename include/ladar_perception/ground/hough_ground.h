// Hough ground fit for a vertically mounted 2D ladar (thesis 3.3.4, algorithms.md).
//
// A vertical scan lies in one plane, so each return is a pair (r_i, Height_i). The ground line
// has two degrees of freedom, Ground (its height under the sensor) and Slope, because the
// sensor's height above the local ground is not trusted:
//   ErrorValue_i = Height_i - Ground - r_i * Slope
//   (Ground*, Slope*) = argmax over the (Ground, Slope) accumulator of
//                       count(|ErrorValue_i| < ErrorTolerance)                     (eq 3.12)
// Beyond the thesis, the winning cell is refined by least squares on its inliers (accuracy is
// not limited to the accumulator's resolution) and the fit reports a confidence: the inlier
// count and the margin over the best clearly different line (the runner-up).
// Keep cfg/HoughGround.cfg, config/hough_ground.yaml and the ROS adapter in step with
// HoughGroundParams.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ladar_perception/cloud/laser_scan.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/obstacle_probability.h"
#include "ladar_perception/ground/param_table.h"
#include "ladar_perception/ground/vertical_scan.h"

namespace ladar_perception {

struct HoughGroundParams {
  // --- The (Ground, Slope) accumulator of eq 3.12.
  float ground_min = -1.0f;          // lowest Ground hypothesis (ground frame height) [m]
  float ground_max = 1.0f;           // highest Ground hypothesis [m]
  float ground_resolution = 0.04f;   // cell size along Ground [m]
  float slope_min = -0.35f;          // steepest downhill Slope hypothesis [-]
  float slope_max = 0.35f;           // steepest uphill Slope hypothesis [-]
  float slope_resolution = 0.01f;    // cell size along Slope [-]
  // ErrorTolerance of eq 3.12 [m]. The accumulator counts a return for the cells within
  // round(ErrorTolerance / ground_resolution - 0.5) cells of its own, i.e. within about
  // ErrorTolerance; the refinement uses the exact value.
  float error_tolerance = 0.1f;
  // Returns that vote: |r| within [min_fit_distance, max_fit_distance] [m].
  float min_fit_distance = 0.5f;
  float max_fit_distance = 40.0f;
  int min_inliers = 5;               // fewer: no ground line, every return unknown

  // --- Beyond the thesis: least-squares refinement of the winning cell on its inliers.
  bool refine = true;
  int refine_iterations = 5;         // rounds of (inliers of the line, least-squares line)

  // --- Beyond the thesis: the ground line bends beyond the fitted line's support (a hill
  // rising or falling away ahead). From the farthest inlier ahead, each segment of
  // segment_length continues the line with the slope (within max_bend of the previous one)
  // that the most returns of that segment support; at least min_segment_inliers, else the line
  // goes on straight. 0 segments: one straight line, as the thesis.
  int bend_segments = 4;
  float segment_length = 10.0f;      // [m]
  float max_bend = 0.15f;            // [-] largest slope change from one segment to the next
  int min_segment_inliers = 4;
  // SlopeError (3.14) divides by |r|; returns closer than this along r use this distance, since
  // the slope from the point under the sensor to a return right below it is all noise [m].
  float slope_error_min_distance = 2.0f;

  // --- Obstacle probability (eqs 3.13-3.15). SlopeError is GndError / r here (see
  // houghSlopeError), so SlopeErrorMax sets how tall an obstacle must be at range r to score:
  // P > 0.5 needs at least |GndError| > 0.5 * SlopeErrorMax * r. The vertical SICK sees the
  // ground to about 40 m, hence a smaller SlopeErrorMax than the vertical scan method's.
  ObstacleToleranceParams tolerances = houghTolerances();

  static ObstacleToleranceParams houghTolerances() {
    ObstacleToleranceParams t;
    t.gnd_error_max_base = 0.15f;
    t.gnd_error_max_per_m = 0.005f;
    t.slope_error_max_base = 0.05f;
    t.slope_error_max_per_m = 0.0f;
    t.obstacle_threshold = 0.5f;
    return t;
  }
};

// Settings of the thesis (3.3.4: accumulator argmax only) and the default (with refinement).
HoughGroundParams houghGroundThesisParams();
HoughGroundParams houghGroundDefaultParams();

// The parameter table (hough_params.def): set one parameter by its name or field path within
// its range (false with a reason otherwise), read one, list them.
bool setHoughGroundParam(HoughGroundParams* params, const std::string& key, double value,
                         std::string* error);
bool getHoughGroundParam(const HoughGroundParams& params, const std::string& key, double* value);
const std::vector<ParamInfo>& houghGroundParamTable();

// The fitted ground line Height = ground + slope * r of one vertical scan and its confidence.
struct GroundLineFit {
  bool valid = false;       // false: fewer than min_inliers returns support any line
  float ground = 0.f;       // Ground* [m]
  float slope = 0.f;        // Slope* [-]
  float cell_ground = 0.f;  // the winning accumulator cell (before refinement)
  float cell_slope = 0.f;
  int votes = 0;            // returns that voted
  int cell_count = 0;       // accumulator count of the winning cell
  int inliers = 0;          // returns with |ErrorValue| < ErrorTolerance about the final line
  int runner_up = 0;        // the most returns any line explains among the returns the
                            // winning cell does not explain (the best competing hypothesis)
  float margin = 0.f;       // (cell_count - runner_up) / cell_count, 0..1 (1: unambiguous)
  float rms = 0.f;          // RMS ErrorValue of the inliers [m]
  float r_min = 0.f;        // extent of the inliers along r [m]
  float r_max = 0.f;
  // Bends beyond the line's support (bend_segments): segment k starts at bend_r[k] (ascending,
  // ahead of the sensor) at ground height bend_h[k] and rises by bend_slope[k] per metre.
  static constexpr int kMaxBends = 8;
  int bends = 0;
  float bend_r[kMaxBends] = {};
  float bend_h[kMaxBends] = {};
  float bend_slope[kMaxBends] = {};

  // Height of the ground line at r (the fitted line, then the bends).
  float heightAt(float r) const {
    for (int k = bends - 1; k >= 0; --k) {
      if (r > bend_r[k]) return bend_h[k] + bend_slope[k] * (r - bend_r[k]);
    }
    return ground + slope * r;
  }
};

// The accumulator and the fit on (r, Height) pairs of one vertical scan. Keep one per stream:
// its buffers are reused, so steady-state scans do not allocate.
class HoughLineFitter {
 public:
  explicit HoughLineFitter(const HoughGroundParams& params = houghGroundDefaultParams());
  void setParams(const HoughGroundParams& params);
  const HoughGroundParams& params() const { return params_; }

  // Eq 3.12 plus refinement. r may be signed (a vertical plane seen on both sides of the
  // sensor); non-finite pairs are skipped.
  GroundLineFit fit(const float* r, const float* height, int n);

  // Accumulator of the last fit: slopeCells() rows of groundCells() counts (tests, rviz).
  int groundCells() const { return n_ground_; }
  int slopeCells() const { return n_slope_; }
  int count(int slope_cell, int ground_cell) const;

 private:
  // Fills votes_; returns the number of returns that voted. With `exclude`, returns within
  // ErrorTolerance of that line do not vote.
  int vote(const float* r, const float* height, int n, const GroundLineFit* exclude);
  // Window counts of votes_ (into counts_ when store) and their argmax cell.
  uint32_t argmax(bool store, int* best_j, int* best_c);
  void refine(const float* r, const float* height, int n, GroundLineFit* fit) const;
  void bend(const float* r, const float* height, int n, GroundLineFit* fit);

  HoughGroundParams params_;
  int n_ground_ = 0, n_slope_ = 0, pad_ = 0, row_ = 0, stride_ = 0;
  std::vector<int16_t> votes_;    // n_slope_ rows of row_ (padded) single-cell votes
  std::vector<int16_t> counts_;   // n_slope_ rows of n_ground_ window counts
  std::vector<int16_t> row_scratch_, row_max_;
  std::vector<float> fr_, fh_;    // the returns that vote (compacted)
  std::vector<float> seg_d_, seg_e_;  // one bend segment's returns
};

// Eqs 3.13-3.15 for one return against a fitted line. SlopeError (3.14) is Slope_i - Slope*
// with Slope_i the slope of the line from the fitted ground point under the sensor to the
// return, (Height_i - Ground*) / r_i, which makes SlopeError_i = GndError_i / |r_i| (the
// thesis's 1-DOF Slope_i = Height_i / r_i is the case Ground* = 0).
inline float houghGndError(const GroundLineFit& f, float r, float height) {
  return height - f.heightAt(r);  // eq 3.13 (Height - Ground* - r Slope* before any bend)
}
inline float houghSlopeError(float gnd_error, float r, float min_distance = 0.05f) {
  const float ar = std::fabs(r);
  return gnd_error / (ar > min_distance ? ar : min_distance);  // eq 3.14
}

// Labels and P(obstacle) of n (r, Height) pairs against a fit: obstacle when eq 3.15 exceeds
// the threshold, ground otherwise; non-finite pairs and every return of an invalid fit are
// unknown. labels and p_obstacle hold n values.
void classifyAgainstLine(const GroundLineFit& fit, const float* r, const float* height, int n,
                         const ObstacleToleranceParams& tolerances, uint8_t* labels,
                         float* p_obstacle, float slope_error_min_distance = 0.05f);

// The thesis's 1-DOF vertical scan fit (eqs 3.4-3.11, through the vertical scan method's own
// vertical_scan::estimateSlope) applied to one 2D vertical scan: the line is pinned to the
// ground point under the sensor and only its slope is estimated. The baseline the Hough fit
// is compared with (3.3.4). Returns with r <= min_fit_distance or beyond max_fit_distance are
// not part of the fit but are labelled.
class OneDofLineFitter {
 public:
  explicit OneDofLineFitter(const VerticalScanParams& params = verticalScanThesisParams())
      : params_(params) {}
  GroundLineFit fit(const float* r, const float* height, int n, float min_fit_distance,
                    float max_fit_distance);

 private:
  VerticalScanParams params_;
  std::vector<std::pair<float, float>> pairs_;
  std::vector<float> r_, h_, w_;
};

// One vertical 2D ladar scan: projection through the sensor's pose, the fit, and the labels.
// The scan plane's horizontal direction u (in the ground frame, pointing forward, +x) gives
// the signed r_i = q_i . u of each ground-frame return q_i; a scan plane tilted more than 30
// degrees from vertical is not a vertical scan, and r_i is then the unsigned horizontal
// distance.
struct ScanGroundResult {
  GroundClassification classification;  // per return, in scan order
  GroundLineFit fit;
  std::vector<float> r;        // per return (NaN when invalid)
  std::vector<float> height;   // per return (NaN when invalid)
  Eigen::Vector2f direction = Eigen::Vector2f::UnitX();  // u (x, y) in the ground frame
  bool signed_r = true;
};

class HoughGround {
 public:
  explicit HoughGround(const HoughGroundParams& params = houghGroundDefaultParams());
  void setParams(const HoughGroundParams& params);
  const HoughGroundParams& params() const { return fitter_.params(); }

  // Never throws: an invalid scan geometry gives an empty result with *error set (false).
  bool classify(const LaserScanView& scan, const SensorPose& pose, ScanGroundResult* out,
                std::string* error = nullptr);

 private:
  HoughLineFitter fitter_;
  LaserScanProjector projector_;
  std::vector<float> x_, y_;
};

// The Hough fit as a GroundModel for 3D clouds ("hough"): every azimuth column of
// column_width_deg is one vertical scan, r the horizontal distance; one line per column.
struct HoughColumnsParams {
  HoughGroundParams fit = houghGroundDefaultParams();
  float column_width_deg = 1.5f;
  float min_range = 1.0f;     // returns closer or farther than these are unknown [m]
  float max_range = 120.0f;
};
std::unique_ptr<GroundModel> makeHoughColumnsModel(const HoughColumnsParams& params = {});

}  // namespace ladar_perception
