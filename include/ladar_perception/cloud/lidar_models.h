// Spinning multi-beam lidars as data: the package's one table of named sensor models. The
// ground extractor takes its row geometry from it (sensor_model / --sensor-model), the
// simulator its beams, range limits and noise (--sensor), the evaluator its per-sensor table.
// A user's own sensor is a `laser_elevations_deg` list (YAML), see lidarModelFromElevations().
#pragma once

#include <string>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace ladar_perception {

// How the driver numbers the beams in the cloud's ring / channel field (and orders the rows
// of an organised cloud): Velodyne's driver numbers them from the lowest beam up, Ouster's
// from the highest down. The ground extractor also checks the order on every scan.
enum class RingOrder { kBottomUp, kTopDown };

struct LidarModel {
  std::string name;         // table key: "vlp16"
  std::string description;  // "Velodyne VLP-16"
  std::string source;       // the datasheet (and revision) the numbers come from
  // Beam elevations [deg], ascending: index k is the k-th beam from the bottom.
  std::vector<float> elevations_deg;
  int azimuth_steps = 1800;    // firings per revolution per beam at rate_hz
  double rate_hz = 10.0;       // revolutions per second
  double min_range = 1.0;      // [m]
  double max_range = 100.0;    // [m] (datasheet range at high reflectivity)
  double noise_sigma = 0.03;   // [m] range noise, 1 sigma along the beam (datasheet accuracy)
  double mount_height = 1.8;   // [m] a usual mounting height above the ground (the simulator's)
  RingOrder ring_order = RingOrder::kBottomUp;
  bool organised = false;      // the driver publishes rows x columns clouds with empty slots

  int beams() const { return static_cast<int>(elevations_deg.size()); }
  // The smallest spacing of adjacent beams [deg].
  float minSpacingDeg() const;
};

// Every named model, HDL-64E first.
const std::vector<LidarModel>& lidarModels();
// The model of that name, nullptr when there is none.
const LidarModel* findLidarModel(const std::string& name);
// "hdl64e, hdl32e, vlp16, ..." for messages and --help.
std::string lidarModelNames();
// A user's sensor from its beam elevations [deg] (any order, sorted here); the other fields
// keep the defaults above. False with a reason when the list cannot describe a sensor (empty,
// more than 128 beams, non-finite, outside (-90, 90), two beams closer than 0.005 deg).
bool lidarModelFromElevations(const std::vector<float>& elevations_deg, LidarModel* model,
                              std::string* error);

// The beam elevations of a cloud with rings (ring or channel field, organised rows; sensor
// frame), measured for a sensor whose table is not at hand: per ring number, the median
// elevation of its returns [deg], ascending from the bottom beam (each at least 0.01 deg above
// the one below). A ring with fewer than 10 returns is interpolated from its neighbours'. False with a reason when the cloud has no rings, more than 128, or
// fewer than half of them have returns.
bool measureRingElevations(const PointCloudView& view, std::vector<float>* elevations_deg,
                           std::string* error);

// Whether a cloud (sensor frame) can come from the sensor: empty when it can, else one sentence
// naming the mismatch, for a throttled error. Sampled (every 7th return for the rings, every
// 31st for the elevations: strides prime to the usual beam counts, so that the firing order
// hides no beam), no allocation.
//  - With rings (ring or channel field, organised rows): more distinct rings than the model has
//    beams, a ring number at or beyond twice the beams, or fewer distinct rings than half the
//    beams (a 16-beam cloud read as an HDL-64E: "cloud has 16 distinct rings, sensor_model
//    hdl64e has 64").
//  - Without: the returns' elevations (2nd to 98th percentile) reach more than 3 degrees beyond
//    the model's beams (a VLP-16's +15 deg against the HDL-64E's +2 deg).
// Clouds too small to judge (fewer than 200 sampled returns: about 1,400 returns with rings,
// 6,200 without) are not judged.
std::string checkCloudAgainstLidarModel(const PointCloudView& view, const LidarModel& lidar);

}  // namespace ladar_perception
