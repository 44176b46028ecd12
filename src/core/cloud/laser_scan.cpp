#include "ladar_perception/cloud/laser_scan.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace ladar_perception {

namespace {
constexpr std::size_t kMaxReturns = 1u << 20;  // far above any 2D ladar (LMS: 361..1141)
}

bool validateLaserScan(const LaserScanView& scan, std::string* error) {
  std::ostringstream s;
  if (scan.size > 0 && scan.ranges == nullptr) {
    s << "no range array for " << scan.size << " returns";
  } else if (scan.size > kMaxReturns) {
    s << scan.size << " returns, more than the " << kMaxReturns << " accepted";
  } else if (!std::isfinite(scan.angle_min) || !std::isfinite(scan.angle_increment) ||
             (scan.size > 1 && scan.angle_increment == 0.f)) {
    s << "unusable angles (angle_min " << scan.angle_min << ", angle_increment "
      << scan.angle_increment << ")";
  } else if (scan.size > 1 &&
             std::fabs(scan.angle_increment) * static_cast<float>(scan.size - 1) > 2.f * 3.1416f) {
    s << "the " << scan.size << " returns at increment " << scan.angle_increment
      << " rad sweep more than one turn";
  } else if (!std::isfinite(scan.range_min) || !std::isfinite(scan.range_max) ||
             scan.range_min < 0.f || !(scan.range_max > scan.range_min)) {
    s << "unusable range limits (range_min " << scan.range_min << ", range_max "
      << scan.range_max << ")";
  } else {
    return true;
  }
  if (error) *error = s.str();
  return false;
}

void LaserScanProjector::updateTable(const LaserScanView& scan) {
  if (cos_.size() == scan.size && angle_min_ == scan.angle_min &&
      angle_increment_ == scan.angle_increment) {
    return;
  }
  cos_.resize(scan.size);
  sin_.resize(scan.size);
  for (std::size_t k = 0; k < scan.size; ++k) {
    // In double: the angle of the last return must not drift by accumulated rounding.
    const double a = static_cast<double>(scan.angle_min) +
                     static_cast<double>(k) * static_cast<double>(scan.angle_increment);
    cos_[k] = static_cast<float>(std::cos(a));
    sin_[k] = static_cast<float>(std::sin(a));
  }
  angle_min_ = scan.angle_min;
  angle_increment_ = scan.angle_increment;
}

std::size_t LaserScanProjector::project(const LaserScanView& scan, float* x, float* y) {
  updateTable(scan);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t valid = 0;
  for (std::size_t k = 0; k < scan.size; ++k) {
    if (validReturn(scan, k)) {
      const float r = scan.ranges[k];
      x[k] = r * cos_[k];
      y[k] = r * sin_[k];
      ++valid;
    } else {
      x[k] = nan;
      y[k] = nan;
    }
  }
  return valid;
}

std::size_t LaserScanProjector::projectPacked(const LaserScanView& scan, uint8_t* data) {
  updateTable(scan);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t valid = 0;
  for (std::size_t k = 0; k < scan.size; ++k) {
    float v[4];
    if (validReturn(scan, k)) {
      const float r = scan.ranges[k];
      v[0] = r * cos_[k];
      v[1] = r * sin_[k];
      v[2] = 0.f;
      ++valid;
    } else {
      v[0] = v[1] = v[2] = nan;
    }
    v[3] = scan.intensities ? scan.intensities[k] : 0.f;
    std::memcpy(data + k * 16, v, 16);
  }
  return valid;
}

CloudLayout laserScanLayout(uint32_t num_points) {
  CloudLayout layout;
  appendField(&layout, "x", FieldType::kFloat32);
  appendField(&layout, "y", FieldType::kFloat32);
  appendField(&layout, "z", FieldType::kFloat32);
  appendField(&layout, "intensity", FieldType::kFloat32);
  layout.width = num_points;
  layout.height = 1;
  layout.row_step = layout.point_step * num_points;
  return layout;
}

}  // namespace ladar_perception
