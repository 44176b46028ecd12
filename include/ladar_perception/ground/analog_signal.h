// The analog signal approach (thesis 3.2; algorithms.md): a baseline ground model
// ("analog_signal"). Each laser sweeps a fixed elevation; over a ground plane
// A x + B y + C z = 1 (C = -1 / sensor_height) its returns satisfy
//   s(theta) = (1/d - C sin(phi)) / cos(phi) = (1 - C z) / r = A cos(theta) + B sin(theta),
// a pure first harmonic in azimuth. A and B are fitted jointly over all lasers by least squares
// on sectors of 3 degrees, together with each laser's DC bias; what remains after removing
// everything of period >= 2 pi is the obstacle signal. The thesis found it fails on non-planar
// (crowned, hilly) roads; it is kept to measure that.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/vertical_scan.h"

namespace ladar_perception {

struct AnalogSignalParams {
  float sector_deg = 3.0f;         // azimuth width of a sector [deg]
  // The obstacle signal as a height above the fitted ground, (z + h) - h r s_fit(theta) [m]:
  // |height| below this is ground.
  float threshold = 0.2f;
  int fit_rounds = 5;              // least-squares rounds; sectors off by > threshold drop out
  // The first round uses only sectors within this height of level ground sensor_height below
  // the sensor (the seed, as Algorithm 1's) [m].
  float initial_gate = 0.3f;
  // Sectors whose median return points higher than this elevation never see nearby ground and
  // take no part in the fit [deg].
  float max_fit_elevation_deg = -2.0f;
  // Laser elevations for clouds without a `ring` field [deg]; empty = the HDL-64E table.
  std::vector<float> laser_elevations_deg;
  float min_range = 1.0f;          // returns closer or farther than these are unknown [m]
  float max_range = 120.0f;
};

// The fitted signal model of one revolution.
struct AnalogSignalFit {
  double a = 0.0, b = 0.0;        // first harmonic: A cos(theta) + B sin(theta) [1/m]
  std::vector<double> bias;       // DC bias per laser row [1/m] (0 for rows without a fit)
  int sectors = 0;                // sectors that took part in the last round
  bool valid = false;
};

class AnalogSignalGround : public GroundModel {
 public:
  explicit AnalogSignalGround(const AnalogSignalParams& params = AnalogSignalParams());
  std::string name() const override { return "analog_signal"; }
  void classify(const PointCloudView& view, const SensorPose& pose,
                GroundClassification* out) override;
  const AnalogSignalFit& fit() const { return fit_; }
  // Rows from this sensor's elevations (clouds without a ring field).
  void setLidarModel(const LidarModel& lidar) override {
    params_.laser_elevations_deg = lidar.elevations_deg;
    row_table_.build(lidar.elevations_deg);
  }

 private:
  AnalogSignalParams params_;
  ElevationRowTable row_table_;
  int sectors_per_row_ = 120;
  AnalogSignalFit fit_;
  // Per-scan workspace, reused.
  std::vector<float> r_, z_, s_, theta_;
  std::vector<int> row_;
  std::vector<uint32_t> bin_, start_, fill_, order_;
  std::vector<std::pair<float, uint32_t>> scratch_;
  struct Sector {
    int row;
    float theta, s, r, z;
    bool active;
  };
  std::vector<Sector> sectors_;
};

}  // namespace ladar_perception
