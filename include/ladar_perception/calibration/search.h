// Search methods over the 6-DOF hypothesis (thesis 4.4). Each works on any cost of a hypothesis
// (the feature metric of the calibrator, or an analytic function in the tests) and reports
// progress after each iteration; the callback returns false to cancel.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ladar_perception/calibration/pose.h"

namespace ladar_perception {
namespace calibration {

using CostFn = std::function<double(const Pose6&)>;

struct SearchProgress {
  std::string stage;     // method or stage name
  int iteration = 0;
  long evaluations = 0;  // cost evaluations so far
  double best_cost = 0;
  Pose6 estimate = Pose6::Zero();  // the current best hypothesis
  Pose6 spread = Pose6::Zero();    // the current search spread per DOF
};
using ProgressFn = std::function<bool(const SearchProgress&)>;

struct SearchParams {
  Pose6 initial = Pose6::Zero();
  // Initial search spread per DOF (half-range for interval search, sigma for the particle filter,
  // step for gradient descent).
  Pose6 spread = (Pose6() << 1.0, 1.0, 1.0, 0.2, 0.2, 0.2).finished();
  // Stop once every DOF's spread is below this (the wanted accuracy).
  Pose6 min_spread = (Pose6() << 0.01, 0.01, 0.01, 0.001, 0.001, 0.001).finished();
  int max_iterations = 60;  // the depth limit of Algorithm 2
  // Interval search (Algorithm 3): offsets -R..R in `interval_steps` values per axis (odd);
  // after each pass R *= shrink.
  int interval_steps = 3;
  double shrink = 0.6;
  // Gradient descent: finite-difference step as a fraction of the current spread.
  double gradient_probe = 0.25;
  // Particle filter (4.4.4): hypotheses drawn per iteration ("points per step") around each of
  // the `resampling_centres` best so far; the next spread is the standard deviation of the centres
  // times `spread_gain`, never more than `max_shrink` times smaller than before per iteration.
  int particles_per_step = 100;
  int resampling_centres = 10;
  double spread_gain = 1.5;
  double max_shrink = 0.5;
  // Iterations without improvement of the best cost before the filter stops (0 = never).
  int patience = 0;
  uint64_t seed = 1;
  // DOFs to leave at the initial value (e.g. z for a planar search); true = search it.
  std::array<bool, 6> active{{true, true, true, true, true, true}};
};

struct SearchResult {
  Pose6 best = Pose6::Zero();     // the minimum-cost hypothesis
  double best_cost = 0;
  Pose6 weighted_mean = Pose6::Zero();  // particle filter: inverse-error weighted mean
  Pose6 spread = Pose6::Zero();   // final spread
  long evaluations = 0;
  int iterations = 0;
  bool cancelled = false;
  std::vector<Pose6> trace;       // the best hypothesis after each iteration (for the plots)
};

// Fixed-step gradient descent (4.4.1): finite-difference gradient scaled per DOF by the spread,
// one step of the spread's length along it while the cost falls.
SearchResult gradientDescent(const CostFn& cost, const SearchParams& params,
                             const ProgressFn& progress = nullptr);
// Multi-scale gradient descent: fixed-step descent, the step halved whenever no step improves,
// down to min_spread.
SearchResult multiScaleGradientDescent(const CostFn& cost, const SearchParams& params,
                                       const ProgressFn& progress = nullptr);
// Interval search (Algorithm 3): exhaustive grid of offsets in all 6 DOF around the centre, move
// to the minimum, shrink, repeat. O(n^6) per pass.
SearchResult intervalSearch(const CostFn& cost, const SearchParams& params,
                            const ProgressFn& progress = nullptr);
// Semi-independent interval search (4.4.3): alternates the rotational and the translational
// triples, O(2 n^3) per pass.
SearchResult semiIndependentIntervalSearch(const CostFn& cost, const SearchParams& params,
                                           const ProgressFn& progress = nullptr);
// Particle filter (4.4.4): Gaussian samples around the N best hypotheses so far, keep the N best,
// shrink each DOF's sigma from the spread of the best ones.
SearchResult particleFilter(const CostFn& cost, const SearchParams& params,
                            const ProgressFn& progress = nullptr);

}  // namespace calibration
}  // namespace ladar_perception
