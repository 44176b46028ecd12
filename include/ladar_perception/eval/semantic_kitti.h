// Ground extraction scored on real labelled scans in the SemanticKITTI layout:
//   DIR/velodyne/NNNNNN.bin   float32 x, y, z, intensity per return (KITTI)
//   DIR/labels/NNNNNN.label   uint32 per return in the same order; class = label & 0xFFFF
//
// Two protocols, as the ground segmentation literature reports them (Patchwork, Patchwork++):
//   A ("without vegetation"): ground = road 40, parking 44, sidewalk 48, other-ground 49,
//     lane-marking 60, terrain 72; vegetation 70, unlabeled 0 and outlier 1 are not scored;
//     every other class is non-ground.
//   B ("with vegetation"): as A, but vegetation below -0.75 x the sensor height (z in the
//     sensor frame) is ground and the rest of it non-ground; unlabeled and outlier returns called
//     ground are dropped from the precision's denominator (never a false ground), and are not
//     scored otherwise.
// Precision and recall are of the ground: positive = called ground. Obstacle recall is the share
// of the scored non-ground returns not called ground. A return labelled unknown by a model is
// not called ground (a model that drops a return does not call it ground either).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace ladar_perception {
namespace eval {

// SemanticKITTI semantic classes the scoring names (label & 0xFFFF).
namespace semantic_kitti {
constexpr uint16_t kUnlabeled = 0, kOutlier = 1, kCar = 10, kRoad = 40, kParking = 44,
                   kSidewalk = 48, kOtherGround = 49, kBuilding = 50, kFence = 51,
                   kOtherStructure = 52, kLaneMarking = 60, kVegetation = 70, kTrunk = 71,
                   kTerrain = 72, kPole = 80, kTrafficSign = 81;
// The class's name in the SemanticKITTI configuration ("class-NN" for one it does not know).
std::string className(uint16_t semantic_class);
// Ground under both protocols (vegetation aside): road, parking, sidewalk, other-ground,
// lane-marking, terrain.
bool isGroundClass(uint16_t semantic_class);
}  // namespace semantic_kitti

enum class GroundProtocol { kA, kB };
const char* protocolName(GroundProtocol p);

// What one return counts as under a protocol.
enum class TruthRole : uint8_t {
  kGround,          // a true positive when called ground, a false negative otherwise
  kNonGround,       // a false positive (false ground) when called ground
  kNotScored,       // left out of every count
  kNotScoredUnlessGround,  // B's unlabeled/outlier: called ground, it is dropped (counted apart)
};
TruthRole truthRole(uint16_t semantic_class, float z_sensor, float sensor_height, GroundProtocol p);

// Bands of horizontal range from the sensor, for the per-range breakdown.
struct RangeBands {
  static constexpr int kCount = 6;
  static constexpr std::array<float, kCount - 1> kEdges = {5.f, 10.f, 20.f, 30.f, 50.f};
  static int band(float range) {
    int b = 0;
    while (b < kCount - 1 && range >= kEdges[b]) ++b;
    return b;
  }
  static std::string name(int b);  // "0-5 m", ..., "50 m and beyond"
};

// Counts of one model on one or more scans under one protocol.
struct RealGroundScore {
  std::size_t scans = 0;
  std::size_t true_ground = 0;       // ground called ground (TP)
  std::size_t false_ground = 0;      // non-ground called ground (FP)
  std::size_t missed_ground = 0;     // ground not called ground (FN)
  std::size_t true_obstacle = 0;     // non-ground not called ground (TN)
  std::size_t dropped_ground = 0;    // B: unlabeled/outlier called ground, not a false ground
  struct ClassCount {
    std::size_t points = 0;          // scored returns of the class
    std::size_t called_ground = 0;
  };
  std::map<uint16_t, ClassCount> classes;  // by SemanticKITTI class (scored returns only)
  struct BandCount {
    std::size_t ground = 0, ground_called_ground = 0;
    std::size_t non_ground = 0, non_ground_called_ground = 0;
  };
  std::array<BandCount, RangeBands::kCount> bands{};

  static double ratio(std::size_t a, std::size_t b) {
    return b ? static_cast<double>(a) / static_cast<double>(b) : 1.0;
  }
  double precision() const { return ratio(true_ground, true_ground + false_ground); }
  double recall() const { return ratio(true_ground, true_ground + missed_ground); }
  double f1() const {
    const double p = precision(), r = recall();
    return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0;
  }
  double obstacleRecall() const { return ratio(true_obstacle, true_obstacle + false_ground); }
  void add(const RealGroundScore& other);
};

// Scores one scan: called_ground[i] != 0 where the model called return i ground; classes[i] is
// the semantic class of return i (label & 0xFFFF); z comes from the view (sensor frame).
// The three have the same length. Adds to *score (scans + 1).
void scoreGroundScan(const PointCloudView& view, const uint16_t* classes,
                     const uint8_t* called_ground, float sensor_height, GroundProtocol protocol,
                     RealGroundScore* score);

// One labelled frame of a SemanticKITTI-layout folder.
struct LabelledFrameFiles {
  std::string name;        // "000000"
  std::string scan_path;   // DIR/velodyne/000000.bin
  std::string label_path;  // DIR/labels/000000.label
};

// The frames of DIR that have both a scan and a label file, in frame order; with
// first <= last, only frames whose number lies in [first, last]. False with a reason when DIR has
// no velodyne/ folder or no labelled frame in the range.
bool listLabelledFrames(const std::string& dir, long first, long last,
                        std::vector<LabelledFrameFiles>* frames, std::string* error);

// Reads a .label file of `expected_points` uint32 labels into semantic classes.
// False with a reason when the file is missing or its size does not match the scan.
bool readSemanticClasses(const std::string& path, std::size_t expected_points,
                         std::vector<uint16_t>* classes, std::string* error);

// Parses "a:b", "a:" (from a), ":b" (up to b) or "a" (one frame). False for anything else.
bool parseFrameRange(const std::string& text, long* first, long* last);

}  // namespace eval
}  // namespace ladar_perception
