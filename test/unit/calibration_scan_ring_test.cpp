// ScanRing: the calibration's bounded scan buffer. Scans keep their points intact while they are
// buffered, whatever the sizes of the scans around them; the limits on posed scans, waiting scans
// and points hold, the oldest scans going first; poses resolve in arrival order; the storage it
// uses stays packed, so its memory stops growing once the ring has turned over.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "ladar_perception/calibration/scan_ring.h"

namespace cal = ladar_perception::calibration;

namespace {

// A scan whose every point encodes its stamp and index, so any overwrite shows.
cal::PointVector scanOf(int stamp, std::size_t n) {
  cal::PointVector pts(n);
  for (std::size_t i = 0; i < n; ++i) pts[i] = Eigen::Vector3f(float(stamp), float(i), 1.f);
  return pts;
}

Eigen::Isometry3d poseOf(int stamp) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation().x() = stamp;
  return p;
}

// Checks every posed scan against its encoding; returns their stamps, oldest first.
std::vector<int> posedStamps(const cal::ScanRing& ring) {
  cal::ScanSet set;
  ring.appendPosedTo(&set);
  std::vector<int> stamps;
  for (std::size_t k = 0; k < set.numScans(); ++k) {
    const int stamp = static_cast<int>(std::lround(set.stamps[k] * 1e9));
    EXPECT_EQ(set.vehicle_poses[k].translation().x(), stamp);
    for (uint32_t i = set.scan_begin[k]; i < set.scan_begin[k + 1]; ++i) {
      EXPECT_EQ(set.points[i].x(), float(stamp)) << "scan " << stamp << " overwritten";
      EXPECT_EQ(set.points[i].y(), float(i - set.scan_begin[k]));
    }
    stamps.push_back(stamp);
  }
  return stamps;
}

TEST(ScanRing, KeepsTheLatestPosedScansIntact) {
  cal::ScanRing ring(5, 10, 1000);
  for (int t = 0; t < 12; ++t) {
    const cal::PointVector pts = scanOf(t, 100);
    EXPECT_TRUE(ring.push(t, pts.data(), pts.size()).stored);
    int64_t stamp = -1;
    ASSERT_TRUE(ring.oldestWaiting(&stamp));
    EXPECT_EQ(stamp, t);
    ring.resolvePose(poseOf(t));
  }
  EXPECT_EQ(posedStamps(ring), (std::vector<int>{7, 8, 9, 10, 11}));
  EXPECT_EQ(ring.posedScans(), 5u);
  EXPECT_EQ(ring.waitingScans(), 0u);
  EXPECT_EQ(ring.points(), 500u);
}

TEST(ScanRing, PosesResolveInArrivalOrderAndWaitingScansAreNotListed) {
  cal::ScanRing ring(10, 10, 1000);
  for (int t = 0; t < 4; ++t) {
    const cal::PointVector pts = scanOf(t, 10);
    ring.push(t, pts.data(), pts.size());
  }
  EXPECT_TRUE(posedStamps(ring).empty());
  ring.resolvePose(poseOf(0));
  ring.dropWaiting();  // scan 1's pose never came
  ring.resolvePose(poseOf(2));
  EXPECT_EQ(posedStamps(ring), (std::vector<int>{0, 2}));
  int64_t stamp = -1;
  ASSERT_TRUE(ring.oldestWaiting(&stamp));
  EXPECT_EQ(stamp, 3);
  EXPECT_EQ(ring.waitingScans(), 1u);
  ring.clear();
  EXPECT_FALSE(ring.oldestWaiting(&stamp));
  EXPECT_TRUE(posedStamps(ring).empty());
}

TEST(ScanRing, TooManyWaitingScansDropTheOldestWaiting) {
  cal::ScanRing ring(10, 3, 1000);
  std::size_t dropped = 0;
  for (int t = 0; t < 5; ++t) {
    const cal::PointVector pts = scanOf(t, 10);
    dropped += ring.push(t, pts.data(), pts.size()).dropped_waiting;
  }
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(ring.waitingScans(), 3u);
  int64_t stamp = -1;
  ASSERT_TRUE(ring.oldestWaiting(&stamp));
  EXPECT_EQ(stamp, 2);
}

TEST(ScanRing, APointBudgetEvictsTheOldestAndRefusesAScanLargerThanIt) {
  cal::ScanRing ring(100, 100, 1000);
  for (int t = 0; t < 20; ++t) {
    const cal::PointVector pts = scanOf(t, 300);
    ASSERT_TRUE(ring.push(t, pts.data(), pts.size()).stored);
    ring.resolvePose(poseOf(t));
    EXPECT_LE(ring.points(), 1000u);
  }
  const std::vector<int> stamps = posedStamps(ring);
  ASSERT_FALSE(stamps.empty());
  EXPECT_EQ(stamps.back(), 19);
  EXPECT_GE(stamps.size(), 2u);  // 3 fit; the wrap can cost one
  const cal::PointVector huge = scanOf(99, 1001);
  EXPECT_FALSE(ring.push(99, huge.data(), huge.size()).stored);
  EXPECT_EQ(posedStamps(ring), stamps);
}

// Scans of random sizes, as a real sensor's: never an overwritten point, never more than the
// limits, and the span of storage written stays within the live points plus one scan's worth of
// the largest (so the memory touched stops growing).
TEST(ScanRing, RandomSizesStayIntactAndPacked) {
  const std::size_t kMaxPoints = 400000;
  cal::ScanRing ring(20, 5, kMaxPoints);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> size(2000, 9000);
  std::deque<int> waiting;
  for (int t = 0; t < 2000; ++t) {
    const cal::PointVector pts = scanOf(t, static_cast<std::size_t>(size(rng)));
    ASSERT_TRUE(ring.push(t, pts.data(), pts.size()).stored);
    waiting.push_back(t);
    // Poses arrive with a lag of 0-3 scans; now and then one never does.
    while (waiting.size() > static_cast<std::size_t>(rng() % 4)) {
      if (rng() % 50 == 0) ring.dropWaiting(); else ring.resolvePose(poseOf(waiting.front()));
      waiting.pop_front();
    }
    EXPECT_LE(ring.posedScans(), 20u);
    EXPECT_LE(ring.waitingScans(), 5u);
  }
  const std::vector<int> stamps = posedStamps(ring);
  EXPECT_GE(stamps.size(), 18u);
  EXPECT_TRUE(std::is_sorted(stamps.begin(), stamps.end()));
  // 20 posed + 5 waiting + the scan being placed, at most 9000 points each.
  EXPECT_LE(ring.highWater(), 26u * 9000u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
