#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {

namespace {

std::vector<float> makeHdl64eTable() {
  std::vector<float> deg(64);
  // Lower block: 32 lasers from -24.8 deg up to -8.83 deg (ring 0..31).
  const float lower_bottom = -24.8f;
  const float lower_top = -8.83f;
  for (int j = 0; j < 32; ++j) {
    deg[j] = lower_bottom + (lower_top - lower_bottom) * static_cast<float>(j) / 31.0f;
  }
  // Upper block: 32 lasers spaced 1/3 deg, from -8.333 deg up to +2.0 deg (ring 32..63).
  for (int i = 0; i < 32; ++i) {
    deg[32 + i] = 2.0f - static_cast<float>(31 - i) / 3.0f;
  }
  return deg;
}

}  // namespace

const std::vector<float>& hdl64eElevationsDeg() {
  static const std::vector<float> table = makeHdl64eTable();
  return table;
}

}  // namespace ladar_perception
