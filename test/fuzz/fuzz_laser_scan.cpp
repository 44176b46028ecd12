// libFuzzer target: an arbitrary LaserScan (geometry + ranges + intensities) and mount pose into
// HoughGround::classify, and the raw (r, Height) pairs into HoughLineFitter::fit.
// Input: angle_min, angle_increment, range_min, range_max (float32), sensor height, roll,
// pitch, yaw (int16 milli-units), a flags byte, then float32 ranges (and intensities).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "ladar_perception/cloud/laser_scan.h"
#include "ladar_perception/ground/hough_ground.h"
#include "fuzz_reader.h"

#ifndef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

namespace fuzz_laser_scan {
using namespace ladar_perception;
using ladar_perception::fuzz::Reader;
}  // namespace fuzz_laser_scan

extern "C" int LADAR_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  using namespace ladar_perception;
  using namespace fuzz_laser_scan;
  Reader in{data, size};
  const float angle_min = in.get<float>();
  const float angle_increment = in.get<float>();
  const float range_min = in.get<float>();
  const float range_max = in.get<float>();
  const float height = in.get<int16_t>() / 1000.f;
  const float roll = in.get<int16_t>() / 1000.f;
  const float pitch = in.get<int16_t>() / 1000.f;
  const float yaw = in.get<int16_t>() / 1000.f;
  const uint8_t flags = in.get<uint8_t>();

  const size_t n = in.n / sizeof(float);
  const bool with_intensities = (flags & 1) && n >= 2;
  const size_t returns = with_intensities ? n / 2 : n;
  // Exact-size heap arrays so that ASan sees any read past the scan.
  std::vector<float> ranges(returns), intensities(with_intensities ? returns : 0);
  if (returns) std::memcpy(ranges.data(), in.p, returns * sizeof(float));
  if (with_intensities)
    std::memcpy(intensities.data(), in.p + returns * sizeof(float), returns * sizeof(float));

  LaserScanView scan;
  scan.angle_min = angle_min;
  scan.angle_increment = angle_increment;
  scan.range_min = range_min;
  scan.range_max = range_max;
  scan.ranges = ranges.data();
  scan.size = returns;
  scan.intensities = with_intensities ? intensities.data() : nullptr;

  SensorPose pose = SensorPose::fromHeight(height);
  pose.sensor_to_ground.linear() =
      (Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
       Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY()) *
       Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX())).toRotationMatrix();

  static HoughGround ground(houghGroundDefaultParams());
  static HoughGround thesis(houghGroundThesisParams());
  HoughGround& h = (flags & 2) ? thesis : ground;
  ScanGroundResult result;
  std::string error;
  const bool ok = h.classify(scan, pose, &result, &error);
  if (!ok && error.empty()) __builtin_trap();  // a rejection must say why
  if (ok && result.classification.size() != returns) __builtin_trap();

  // The fitter on raw pairs: first half r, second half height (any floats, NaN and Inf too).
  if (flags & 4) {
    static HoughLineFitter fitter;
    const int pairs = static_cast<int>(returns / 2);
    if (pairs > 0) fitter.fit(ranges.data(), ranges.data() + pairs, pairs);
  }
  return 0;
}
