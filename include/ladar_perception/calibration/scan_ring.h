// The calibration's buffer of one sensor's latest scans (thesis 4.2: scans kept with the vehicle
// pose at their stamp): a bounded ring in one block of point storage reserved once, so buffering
// a stream of scans allocates nothing and the memory it occupies stops growing once the ring has
// turned over, whatever the scans' sizes.
//
// A scan is pushed as soon as it arrives, waiting for its vehicle pose; the poses are resolved
// in arrival order (resolvePose) or the waiting scan is dropped (dropWaiting). At most
// `max_posed` scans with a pose and `max_waiting` without are kept, and at most `max_points`
// points in all: the oldest scans make room for the newest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ladar_perception/calibration/accumulation.h"

namespace ladar_perception {
namespace calibration {

class ScanRing {
 public:
  ScanRing(std::size_t max_posed, std::size_t max_waiting, std::size_t max_points);

  // What push() had to give up to store the scan.
  struct PushOutcome {
    bool stored = false;          // false: the scan alone has more than max_points points
    std::size_t dropped_waiting = 0;  // scans still waiting for a pose, dropped to make room
  };
  // stamp_ns: the scan's stamp in nanoseconds (exact, as a ROS stamp).
  PushOutcome push(int64_t stamp_ns, const Eigen::Vector3f* points, std::size_t count);

  // The oldest scan waiting for a pose: its stamp [ns], or false when none waits.
  bool oldestWaiting(int64_t* stamp_ns) const;
  // Gives the oldest waiting scan its vehicle pose (odom -> base_link).
  void resolvePose(const Eigen::Isometry3d& vehicle_pose);
  // Drops the oldest waiting scan (its pose will not come).
  void dropWaiting();

  // Appends the scans with a pose, oldest first (stamps in seconds).
  void appendPosedTo(ScanSet* out) const;
  void clear();

  std::size_t posedScans() const { return posed_; }
  std::size_t waitingScans() const { return waiting_; }
  std::size_t points() const;  // points held by live scans
  std::size_t maxPoints() const { return max_points_; }
  // The end of the highest storage ever written [points]: the part of the reserve in memory.
  std::size_t highWater() const { return high_water_; }

 private:
  enum class State : uint8_t { kWaiting, kPosed, kDropped };
  struct Entry {
    int64_t stamp_ns = 0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    std::size_t begin = 0, count = 0;  // points_[begin, begin + count)
    State state = State::kWaiting;
  };
  Entry& entry(std::size_t i) { return entries_[(front_ + i) % entries_.size()]; }
  const Entry& entry(std::size_t i) const { return entries_[(front_ + i) % entries_.size()]; }
  bool overlapsAny(std::size_t begin, std::size_t count) const;
  std::size_t placement(std::size_t count) const;
  void popFront();
  std::size_t firstWaiting() const;  // index among the entries; size_ when none

  std::size_t max_posed_, max_waiting_, max_points_;
  std::unique_ptr<Eigen::Vector3f[]> points_;  // reserved once; pages are touched as they fill
  std::vector<Entry> entries_;                 // circular, capacity max_posed + max_waiting
  std::size_t front_ = 0, size_ = 0;
  std::size_t posed_ = 0, waiting_ = 0;
  std::size_t high_water_ = 0;
};

}  // namespace calibration
}  // namespace ladar_perception
