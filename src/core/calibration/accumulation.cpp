#include "ladar_perception/calibration/accumulation.h"

#include <cmath>

namespace ladar_perception {
namespace calibration {

void ScanSet::clear() {
  points.clear();
  scan_begin.assign(1, 0);
  vehicle_poses.clear();
  stamps.clear();
}

void ScanSet::addScan(double stamp, const Eigen::Isometry3d& vehicle_pose,
                      const PointVector& scan_points) {
  addScan(stamp, vehicle_pose, scan_points.data(), scan_points.size());
}

void ScanSet::addScan(double stamp, const Eigen::Isometry3d& vehicle_pose,
                      const Eigen::Vector3f* begin, std::size_t count) {
  if (scan_begin.empty()) scan_begin.push_back(0);
  points.insert(points.end(), begin, begin + count);
  scan_begin.push_back(static_cast<uint32_t>(points.size()));
  vehicle_poses.push_back(vehicle_pose);
  stamps.push_back(stamp);
}

ScanSet ScanSet::subset(std::size_t first, std::size_t last) const {
  ScanSet out;
  last = std::min(last, numScans());
  for (std::size_t k = first; k < last; ++k) {
    out.addScan(stamps[k], vehicle_poses[k], points.data() + scan_begin[k],
                scan_begin[k + 1] - scan_begin[k]);
  }
  return out;
}

void accumulate(const ScanSet& scans, const Eigen::Isometry3d& extrinsic, PointVector* out) {
  out->resize(scans.numPoints());
  for (std::size_t k = 0; k < scans.numScans(); ++k) {
    const Eigen::Isometry3f m = (scans.vehicle_poses[k] * extrinsic).cast<float>();
    const Eigen::Matrix3f r = m.linear();
    const Eigen::Vector3f t = m.translation();
    for (uint32_t i = scans.scan_begin[k]; i < scans.scan_begin[k + 1]; ++i) {
      (*out)[i].noalias() = r * scans.points[i] + t;
    }
  }
}

namespace {
constexpr int64_t kEmptyKey = -1;  // voxel keys are >= 0

inline int64_t voxelKey(const Eigen::Vector3f& p, double inv) {
  const int64_t ix = static_cast<int64_t>(std::floor(p.x() * inv)) & 0x1FFFFF;
  const int64_t iy = static_cast<int64_t>(std::floor(p.y() * inv)) & 0x1FFFFF;
  const int64_t iz = static_cast<int64_t>(std::floor(p.z() * inv)) & 0x1FFFFF;
  return (ix << 42) | (iy << 21) | iz;
}
}  // namespace

uint32_t VoxelThinner::slotOf(int64_t key) const {
  // Fibonacci hashing of the key, then linear probing.
  uint32_t slot = static_cast<uint32_t>((static_cast<uint64_t>(key) * 0x9E3779B97F4A7C15ull) >> 32) & mask_;
  while (keys_[slot] != kEmptyKey && keys_[slot] != key) slot = (slot + 1) & mask_;
  return slot;
}

void VoxelThinner::thin(const Eigen::Vector3f* points, std::size_t count, double voxel,
                        PointVector* out) {
  std::size_t slots = 16;
  while (slots < 2 * count) slots *= 2;  // load factor <= 1/2
  keys_.assign(slots, kEmptyKey);        // keeps the capacity of earlier, larger scans
  index_.resize(slots);
  mask_ = static_cast<uint32_t>(slots - 1);
  sums_.clear();
  const double inv = 1.0 / voxel;
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!p.allFinite()) continue;
    const int64_t key = voxelKey(p, inv);
    const uint32_t slot = slotOf(key);
    if (keys_[slot] == kEmptyKey) {
      keys_[slot] = key;
      index_[slot] = static_cast<uint32_t>(sums_.size());
      sums_.push_back({Eigen::Vector3d::Zero(), 0});
    }
    VoxelSum& s = sums_[index_[slot]];
    s.sum += p.cast<double>();
    ++s.count;
  }
  out->reserve(out->size() + sums_.size());
  for (const VoxelSum& s : sums_) out->push_back((s.sum / s.count).cast<float>());
}

PointVector voxelDownsample(const PointVector& points, double voxel) {
  if (!(voxel > 0)) return points;
  PointVector out;
  VoxelThinner thinner;
  thinner.thin(points.data(), points.size(), voxel, &out);
  return out;
}

ScanSet voxelDownsampleScans(const ScanSet& scans, double voxel) {
  if (!(voxel > 0)) return scans;
  ScanSet out;
  VoxelThinner thinner;
  PointVector scan;
  for (std::size_t k = 0; k < scans.numScans(); ++k) {
    scan.clear();
    thinner.thin(scans.points.data() + scans.scan_begin[k], scans.scan_begin[k + 1] - scans.scan_begin[k],
                 voxel, &scan);
    out.addScan(scans.stamps[k], scans.vehicle_poses[k], scan);
  }
  return out;
}

ScanSet thinScans(const ScanSet& scans, double voxel, std::size_t max_points) {
  ScanSet thin = voxelDownsampleScans(scans, voxel);
  if (max_points == 0 || thin.numPoints() <= max_points) return thin;
  const double stride = static_cast<double>(thin.numPoints()) / static_cast<double>(max_points);
  ScanSet out;
  PointVector scan;
  double next = 0;
  for (std::size_t k = 0; k < thin.numScans(); ++k) {
    scan.clear();
    for (uint32_t i = thin.scan_begin[k]; i < thin.scan_begin[k + 1]; ++i) {
      if (i >= next) {
        scan.push_back(thin.points[i]);
        next += stride;
      }
    }
    out.addScan(thin.stamps[k], thin.vehicle_poses[k], scan);
  }
  return out;
}

void pointsFromView(const PointCloudView& view, double min_range, double max_range,
                    PointVector* out) {
  out->clear();
  out->reserve(view.size());
  const float min2 = static_cast<float>(min_range * min_range);
  const float max2 = static_cast<float>(max_range * max_range);
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    if (!p.allFinite()) continue;
    const float r2 = p.squaredNorm();
    if (r2 < min2 || r2 > max2) continue;
    out->push_back(p);
  }
}

void pointsFromLaserScan(const float* ranges, std::size_t count, double angle_min,
                         double angle_increment, double range_min, double range_max,
                         PointVector* out) {
  out->clear();
  out->reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const float r = ranges[i];
    if (!std::isfinite(r) || r < range_min || r > range_max) continue;
    const double a = angle_min + angle_increment * static_cast<double>(i);
    out->emplace_back(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                      0.f);
  }
}

}  // namespace calibration
}  // namespace ladar_perception
