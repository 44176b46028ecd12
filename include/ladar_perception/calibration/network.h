// Calibration of a network of sensors (thesis 5.2.2): one reference with a known mount and
// several targets. Each target is calibrated against the reference (calibrate(), the pairwise
// edges); with cross_pairs each pair of targets is then refined against each other (the cross
// edges: the denser sensor's accumulated cloud is the surface, placed at its pairwise estimate).
// The joint solution is the one consistent tree that fits every edge best, each weighted by its
// own per-DOF standard deviation (a weighted least-squares pose graph over the targets' mounts,
// the reference held fixed); an edge whose DOF is unobservable carries no weight in it. Every
// loop reference -> i -> j -> reference gives a closure residual, a measure of the edges'
// consistency that no single pair can give. ROS-free: ladar_calibrate, the Calibration nodelet
// and calibration_benchmark call calibrateNetwork().
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ladar_perception/calibration/calibrator.h"

namespace ladar_perception {
namespace calibration {

struct NetworkTarget {
  std::string name;  // the sensor's frame
  ScanSet scans;
  Pose6 initial = Pose6::Zero();  // base_link -> sensor, the initial guess
  Pose6 spread = (Pose6() << 1.0, 1.0, 1.0, 0.2, 0.2, 0.2).finished();
  // The refinement's surface voxel when this sensor's cloud is a surface or is fitted to one
  // (0 = the params'): 0.4 m for a stereo camera (adaptParamsToPair).
  double surface_voxel = 0.0;
};

struct NetworkInput {
  std::string reference_name;
  ScanSet reference;
  Eigen::Isometry3d reference_extrinsic = Eigen::Isometry3d::Identity();
  std::vector<NetworkTarget> targets;
};

struct NetworkParams {
  CalibrationParams calibration;  // the pairwise calibrations (initial, spread set per target)
  // Refine every pair of targets against each other (all pairs); false: a star around the
  // reference, and the joint solution equals the pairwise one.
  bool cross_pairs = true;
  // The cross refinements start from the pairwise estimates and search within this spread.
  Pose6 cross_spread = (Pose6() << 0.2, 0.2, 0.2, 0.05, 0.05, 0.05).finished();
  // Added in quadrature to every edge's reported standard deviation: what the statistics of one
  // refinement do not see (the surface model's bias), so that no edge outweighs the others by
  // its point count alone.
  double floor_translation = 0.005;  // [m]
  double floor_rotation = 0.001;     // [rad]
  int joint_iterations = 30;
  // Scale the pairwise and the cross edges' variances each by its own factor estimated from the
  // residuals (variance component estimation), when the network has redundancy.
  bool variance_components = true;
  // Huber threshold on an edge's residual norm in standard deviations (its used DOFs together):
  // beyond it the edge's weight falls as threshold / residual. sqrt of chi-square(6) at 99%.
  // 0 = plain least squares.
  double robust_threshold = 4.1;
  // A DOF of the joint solution whose standard deviation exceeds this is unobservable.
  double max_stddev = 0.05;           // [m]
  double max_stddev_rotation = 0.01;  // [rad]
};

// One edge of the graph: a calibration of sensor `to` against sensor `from` (-1 = the reference).
struct NetworkEdge {
  int from = -1, to = 0;
  CalibrationResult result;   // result.extrinsic: base_link -> `to`, with `from` at its estimate
  Pose6 from_estimate = Pose6::Zero();  // where `from` was placed (its pairwise estimate)
  bool used = false;          // carried weight in the joint solution
  double weight = 1.0;        // its robust weight there (1 = full)
  // Closure of the loop reference -> from -> to -> reference before the joint solve (cross edges:
  // the cross estimate of `to` minus its pairwise estimate), and this edge's residual at the
  // joint solution; per DOF and as a translation [m] and rotation angle [rad].
  Pose6 loop = Pose6::Zero();
  double loop_translation = 0, loop_rotation = 0;
  Pose6 residual = Pose6::Zero();
  double residual_translation = 0, residual_rotation = 0;
};

struct NetworkSensorResult {
  std::string name;
  bool success = false;            // every DOF observable in the joint solution
  Pose6 pairwise = Pose6::Zero();  // the pairwise estimate against the reference
  bool pairwise_success = false;
  Pose6 joint = Pose6::Zero();     // base_link -> sensor in the joint solution
  Pose6 stddev = Pose6::Zero();    // of the joint solution; infinity when unobservable
  std::vector<std::string> unobservable;
};

struct NetworkResult {
  bool success = false;  // every target calibrated
  std::string message;
  std::vector<NetworkSensorResult> sensors;  // in the input's target order
  std::vector<NetworkEdge> edges;            // the pairwise edges first, then the cross edges
  double joint_cost = 0;                     // sum of squared normalised edge residuals
  double elapsed = 0, cpu_time = 0;          // [s]
};

// Progress of the network: which edge is being computed ("sick_front <- velodyne") and the
// calibration's own progress in it. Returning false cancels.
using NetworkProgressFn =
    std::function<bool(const std::string& edge, const SearchProgress& progress)>;

NetworkResult calibrateNetwork(const NetworkInput& input, const NetworkParams& params,
                               const NetworkProgressFn& progress = nullptr);

// The joint solve alone (used by calibrateNetwork; exposed for tests): edges' estimates and
// stddevs in, the joint mounts and their stddevs out (targets = number of targets). Edges
// without `used` are ignored; each target needs at least one used edge to be solved.
void solveNetwork(int targets, const NetworkParams& params, std::vector<NetworkEdge>* edges,
                  std::vector<NetworkSensorResult>* sensors, double* cost);

// A network's result as one YAML: a TransformStamped dict per sensor under its (sanitised)
// frame name, the figures in comments; and the launch file that loads it and starts one
// static_transform_publisher per sensor (`yaml_path` is where the YAML will be).
std::string networkYaml(const std::string& parent_frame, const NetworkResult& result);
std::string networkLaunch(const std::string& yaml_path, const NetworkResult& result);
// The name a sensor's transform has in that YAML (frame with non-alphanumerics as '_').
std::string networkKey(const std::string& frame);

}  // namespace calibration
}  // namespace ladar_perception
