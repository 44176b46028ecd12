// The Hough ground fit (3.3.4) against the 1-DOF vertical scan line on the simulated thesis
// vehicle's vertical SICK LMS-291, with ground truth, and per-scan timing of any ground model:
// the parts of ground_eval's comparison beyond the 3D models. Header-only, like
// ground_evaluation.h (the ground library does not depend on the simulator).
#pragma once

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/hough_ground.h"
#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {

// Median of per-scan times [ms] (0 for none).
inline double medianMs(std::vector<double> ms) {
  if (ms.empty()) return 0.0;
  const std::size_t mid = ms.size() / 2;
  std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(mid), ms.end());
  double m = ms[mid];
  if (ms.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return m;
}

// A ground model that times each classify() call of the model it wraps (one virtual call per
// scan, none per point).
class TimedGroundModel : public GroundModel {
 public:
  explicit TimedGroundModel(GroundModel* inner) : inner_(inner) {}
  std::string name() const override { return inner_->name(); }
  void classify(const PointCloudView& view, const SensorPose& pose,
                GroundClassification* out) override {
    const auto t0 = std::chrono::steady_clock::now();
    inner_->classify(view, pose, out);
    const auto t1 = std::chrono::steady_clock::now();
    ms_.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  void setLidarModel(const LidarModel& lidar) override { inner_->setLidarModel(lidar); }
  const std::vector<double>& milliseconds() const { return ms_; }
  void reset() { ms_.clear(); }

 private:
  GroundModel* inner_;
  std::vector<double> ms_;
};

// The ground fits compared on the vertical SICK's scans.
enum class SickGroundFit {
  kHough,        // the package's Hough fit (refinement, bends)
  kHoughThesis,  // the thesis's Hough fit: accumulator argmax, one straight line
  kOneDof,       // the vertical scan method's 1-DOF line (eqs 3.4-3.11) applied to the SICK,
                 // as the thesis first did (3.3.4), with the vertical scan thesis tolerances
};
inline const char* sickGroundFitName(SickGroundFit f) {
  switch (f) {
    case SickGroundFit::kHough: return "hough (vertical SICK)";
    case SickGroundFit::kHoughThesis: return "hough_thesis (vertical SICK)";
    case SickGroundFit::kOneDof: return "1-DOF vertical scan line (vertical SICK)";
  }
  return "?";
}

// Classifies `scans` scans of the thesis vehicle's vertical SICK (mount "sick_vertical" of
// sim::SensorRig::thesisVehicle) taken along the world's standard drive (evenly spaced in
// time); accumulates the accuracy over the returns (beams without a return are not counted)
// and the core's time per scan in *ms (for the 1-DOF line: its fit and labels, the projection
// is shared). The fit sees the scanner's pose relative to base_link
// with the point under the sensor as origin (what the nodelet's tf gives it).
inline bool evaluateVerticalSick(const std::string& world_name, SickGroundFit kind,
                                 sim::NoiseProfile noise, int scans, uint32_t seed,
                                 GroundAccuracy* acc, std::vector<double>* ms, std::string* error) {
  sim::World world;
  if (!sim::makeStandardWorld(world_name, seed, &world, error)) return false;
  const sim::SensorRig rig = sim::SensorRig::thesisVehicle(noise);
  const sim::SensorMount* mount = nullptr;
  for (const sim::SensorMount& m : rig.sensors) {
    if (m.name == "sick_vertical") mount = &m;
  }
  if (!mount) {
    if (error) *error = "the thesis vehicle has no sick_vertical scanner";
    return false;
  }
  SensorPose pose;
  pose.sensor_to_ground = mount->base_to_sensor.cast<float>();
  pose.sensor_to_ground.translation().x() = 0.f;
  pose.sensor_to_ground.translation().y() = 0.f;
  HoughGround hough(kind == SickGroundFit::kHough ? houghGroundDefaultParams()
                                                  : houghGroundThesisParams());
  OneDofLineFitter one_dof(verticalScanThesisParams());
  const ObstacleToleranceParams one_dof_tolerances = verticalScanThesisParams().tolerances;
  ScanGroundResult result;
  GroundClassification labels;
  sim::SimulatedLaserScan scan;
  std::vector<uint8_t> truth;
  const double duration = world.driveDuration();
  for (int k = 0; k < scans; ++k) {
    const double t = duration * (static_cast<double>(k) + 0.5) / std::max(scans, 1);
    sim::simulateSickScan(world, world.drivePose(t) * mount->base_to_sensor, mount->sick,
                          seed * 1000u + static_cast<uint32_t>(k), &scan);
    LaserScanView view;
    view.angle_min = scan.angle_min;
    view.angle_increment = scan.angle_increment;
    view.range_min = scan.range_min;
    view.range_max = scan.range_max;
    view.ranges = scan.ranges.data();
    view.size = scan.ranges.size();
    auto t0 = std::chrono::steady_clock::now();
    if (!hough.classify(view, pose, &result, error)) return false;
    const GroundClassification* out = &result.classification;
    if (kind == SickGroundFit::kOneDof) {
      t0 = std::chrono::steady_clock::now();  // timed: the 1-DOF fit and its labels only
      // The same projection; the line from the 1-DOF fit, labels by eqs 3.10, 3.11, 3.15.
      const int n = static_cast<int>(result.r.size());
      const HoughGroundParams& hp = hough.params();
      const GroundLineFit line = one_dof.fit(result.r.data(), result.height.data(), n,
                                             hp.min_fit_distance, hp.max_fit_distance);
      labels.resize(result.r.size());
      classifyAgainstLine(line, result.r.data(), result.height.data(), n, one_dof_tolerances,
                          labels.labels.data(), labels.p_obstacle.data());
      out = &labels;
    }
    const auto t1 = std::chrono::steady_clock::now();
    if (ms) ms->push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    // Only beams with a return count (kNone = no return).
    truth.clear();
    GroundClassification returned;
    for (std::size_t i = 0; i < scan.beam_truth.size() && i < out->size(); ++i) {
      if (scan.beam_truth[i] == static_cast<uint8_t>(sim::SurfaceClass::kNone)) continue;
      truth.push_back(scan.beam_truth[i]);
      returned.labels.push_back(out->labels[i]);
      returned.p_obstacle.push_back(out->p_obstacle[i]);
    }
    acc->add(truth, returned);
  }
  return true;
}

}  // namespace ladar_perception
