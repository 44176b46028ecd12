// Accumulation over time (thesis 4.2, Algorithm 2 step 2): every scan of a sensor is kept in the
// sensor frame with the vehicle pose (odom -> base_link) at its stamp, and projected into the odom
// frame through that pose and the sensor's extrinsic (base_link -> sensor). Sensors whose fields
// of view never overlap at one instant can then be compared once the vehicle has moved.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace ladar_perception {
namespace calibration {

using PointVector = std::vector<Eigen::Vector3f>;

// The scans of one sensor, packed: scan k holds points[scan_begin[k] .. scan_begin[k+1]) in the
// sensor frame, taken when the vehicle was at vehicle_poses[k] (odom -> base_link).
struct ScanSet {
  PointVector points;
  std::vector<uint32_t> scan_begin{0};
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> vehicle_poses;
  std::vector<double> stamps;

  std::size_t numScans() const { return vehicle_poses.size(); }
  std::size_t numPoints() const { return points.size(); }
  bool empty() const { return points.empty(); }
  void clear();
  // Appends one scan (points in the sensor frame).
  void addScan(double stamp, const Eigen::Isometry3d& vehicle_pose, const PointVector& scan_points);
  void addScan(double stamp, const Eigen::Isometry3d& vehicle_pose, const Eigen::Vector3f* begin,
               std::size_t count);
  // The scans with index in [first, last).
  ScanSet subset(std::size_t first, std::size_t last) const;
};

// Projects every point into the odom frame: p_odom = vehicle_pose_k * extrinsic * p.
// *out is resized to scans.numPoints() (no allocation when its capacity suffices).
void accumulate(const ScanSet& scans, const Eigen::Isometry3d& extrinsic, PointVector* out);

// Replaces the points of each voxel of `voxel` metres by their centroid (which also averages the
// range noise). Voxels are keyed in the points' own frame; the centroids come in the order of
// each voxel's first point.
PointVector voxelDownsample(const PointVector& points, double voxel);

// voxelDownsample with reusable storage, for scan-by-scan use: an open-addressing voxel index and
// the voxel sums keep their capacity from call to call, so a stream of scans thins without
// allocating once the largest scan has been seen.
class VoxelThinner {
 public:
  // Appends the centroids of `points[0, count)` (non-finite points skipped) to *out.
  void thin(const Eigen::Vector3f* points, std::size_t count, double voxel, PointVector* out);

 private:
  struct VoxelSum {
    Eigen::Vector3d sum;
    int count;
  };
  uint32_t slotOf(int64_t key) const;
  std::vector<int64_t> keys_;    // per slot; kEmptyKey when free
  std::vector<uint32_t> index_;  // per slot: the voxel's entry in sums_
  std::vector<VoxelSum> sums_;
  uint32_t mask_ = 0;
};
// The same per scan, in the sensor frame, so the result does not depend on any hypothesis.
ScanSet voxelDownsampleScans(const ScanSet& scans, double voxel);

// Voxel-downsamples each scan, then keeps every k-th point (evenly over all scans) so that at
// most max_points remain (0 = no limit).
ScanSet thinScans(const ScanSet& scans, double voxel, std::size_t max_points);

// Readable points of a cloud (finite, range within [min_range, max_range]) in its own frame.
void pointsFromView(const PointCloudView& view, double min_range, double max_range,
                    PointVector* out);
// A 2D ladar scan (sensor_msgs/LaserScan semantics) as points in the z = 0 plane of its frame.
void pointsFromLaserScan(const float* ranges, std::size_t count, double angle_min,
                         double angle_increment, double range_min, double range_max,
                         PointVector* out);

}  // namespace calibration
}  // namespace ladar_perception
