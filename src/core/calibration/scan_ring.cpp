#include "ladar_perception/calibration/scan_ring.h"

#include <algorithm>
#include <cstring>

namespace ladar_perception {
namespace calibration {

ScanRing::ScanRing(std::size_t max_posed, std::size_t max_waiting, std::size_t max_points)
    : max_posed_(std::max<std::size_t>(1, max_posed)),
      max_waiting_(std::max<std::size_t>(1, max_waiting)),
      max_points_(std::max<std::size_t>(1, max_points)),
      // Default-initialised (Eigen leaves the coefficients alone): no page is touched until a
      // scan is written there.
      points_(new Eigen::Vector3f[max_points_]),
      entries_(max_posed_ + max_waiting_) {}

bool ScanRing::overlapsAny(std::size_t begin, std::size_t count) const {
  for (std::size_t i = 0; i < size_; ++i) {
    const Entry& e = entry(i);
    if (e.begin < begin + count && begin < e.begin + e.count) return true;
  }
  return false;
}

// Where a scan of `count` points goes: the lowest free place of [0, count) or just after the
// newest scan, so the live scans stay packed at the start of the storage; when neither is free,
// the place the oldest scans will be evicted from.
std::size_t ScanRing::placement(std::size_t count) const {
  if (size_ == 0 || !overlapsAny(0, count)) return 0;
  const Entry& newest = entry(size_ - 1);
  const std::size_t tail = newest.begin + newest.count;
  if (tail + count <= max_points_) return tail;
  return 0;
}

void ScanRing::popFront() {
  Entry& e = entry(0);
  if (e.state == State::kPosed) --posed_;
  if (e.state == State::kWaiting) --waiting_;
  front_ = (front_ + 1) % entries_.size();
  --size_;
}

std::size_t ScanRing::firstWaiting() const {
  for (std::size_t i = 0; i < size_; ++i) {
    if (entry(i).state == State::kWaiting) return i;
  }
  return size_;
}

ScanRing::PushOutcome ScanRing::push(int64_t stamp_ns, const Eigen::Vector3f* points,
                                     std::size_t count) {
  PushOutcome outcome;
  if (count > max_points_) return outcome;
  if (waiting_ == max_waiting_) {
    dropWaiting();
    ++outcome.dropped_waiting;
  }
  if (size_ == entries_.size()) {
    outcome.dropped_waiting += entry(0).state == State::kWaiting;
    popFront();
  }
  std::size_t begin = placement(count);
  while (size_ > 0 && overlapsAny(begin, count)) {  // the oldest scans make room
    outcome.dropped_waiting += entry(0).state == State::kWaiting;
    popFront();
    begin = placement(count);
  }
  if (count > 0) std::memcpy(static_cast<void*>(points_.get() + begin), points, count * sizeof(Eigen::Vector3f));
  high_water_ = std::max(high_water_, begin + count);
  Entry& e = entries_[(front_ + size_) % entries_.size()];
  e.stamp_ns = stamp_ns;
  e.pose.setIdentity();
  e.begin = begin;
  e.count = count;
  e.state = State::kWaiting;
  ++size_;
  ++waiting_;
  outcome.stored = true;
  return outcome;
}

bool ScanRing::oldestWaiting(int64_t* stamp_ns) const {
  const std::size_t i = firstWaiting();
  if (i == size_) return false;
  *stamp_ns = entry(i).stamp_ns;
  return true;
}

void ScanRing::resolvePose(const Eigen::Isometry3d& vehicle_pose) {
  const std::size_t i = firstWaiting();
  if (i == size_) return;
  Entry& e = entry(i);
  e.pose = vehicle_pose;
  e.state = State::kPosed;
  --waiting_;
  ++posed_;
  // Waiting scans are the newest, so the oldest posed (and dropped) scans are at the front.
  while (posed_ > max_posed_ && size_ > 0 && entry(0).state != State::kWaiting) popFront();
}

void ScanRing::dropWaiting() {
  const std::size_t i = firstWaiting();
  if (i == size_) return;
  entry(i).state = State::kDropped;
  --waiting_;
  while (size_ > 0 && entry(0).state == State::kDropped) popFront();
}

void ScanRing::appendPosedTo(ScanSet* out) const {
  for (std::size_t i = 0; i < size_; ++i) {
    const Entry& e = entry(i);
    if (e.state == State::kPosed) {
      out->addScan(static_cast<double>(e.stamp_ns) * 1e-9, e.pose, points_.get() + e.begin, e.count);
    }
  }
}

void ScanRing::clear() {
  front_ = size_ = posed_ = waiting_ = 0;
}

std::size_t ScanRing::points() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < size_; ++i) {
    if (entry(i).state != State::kDropped) n += entry(i).count;
  }
  return n;
}

}  // namespace calibration
}  // namespace ladar_perception
