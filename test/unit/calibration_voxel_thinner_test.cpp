// VoxelThinner: the voxel centroids of each scan, the same as a plain per-voxel average, in the
// order of each voxel's first point, whatever scans the thinner has seen before (its reused
// index must not carry anything over), and without reallocating once the largest scan is seen.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "ladar_perception/calibration/accumulation.h"

namespace cal = ladar_perception::calibration;

namespace {

// Per-voxel average by an ordered map, the voxels listed in order of first appearance.
cal::PointVector referenceThinning(const cal::PointVector& pts, double voxel) {
  using Key = std::tuple<int64_t, int64_t, int64_t>;
  std::map<Key, std::size_t> slot;
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  for (const Eigen::Vector3f& p : pts) {
    if (!p.allFinite()) continue;
    const Key k{static_cast<int64_t>(std::floor(p.x() / voxel)),
                static_cast<int64_t>(std::floor(p.y() / voxel)),
                static_cast<int64_t>(std::floor(p.z() / voxel))};
    auto it = slot.emplace(k, sum.size());
    if (it.second) {
      sum.push_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    sum[it.first->second] += p.cast<double>();
    ++count[it.first->second];
  }
  cal::PointVector out;
  for (std::size_t i = 0; i < sum.size(); ++i) out.push_back((sum[i] / count[i]).cast<float>());
  return out;
}

cal::PointVector randomScan(std::size_t n, double extent, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(static_cast<float>(-extent), static_cast<float>(extent));
  cal::PointVector pts(n);
  for (auto& p : pts) p = Eigen::Vector3f(u(rng), u(rng), 0.1f * u(rng));
  pts[n / 2].x() = std::numeric_limits<float>::quiet_NaN();  // skipped
  return pts;
}

void expectSame(const cal::PointVector& a, const cal::PointVector& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT((a[i] - b[i]).norm(), 1e-5f) << i;
}

TEST(VoxelThinner, CentroidsPerVoxelInFirstSeenOrder) {
  const cal::PointVector pts = randomScan(20000, 30.0, 1);
  cal::VoxelThinner thinner;
  cal::PointVector out;
  thinner.thin(pts.data(), pts.size(), 0.5, &out);
  expectSame(out, referenceThinning(pts, 0.5));
  EXPECT_LT(out.size(), pts.size());
  expectSame(cal::voxelDownsample(pts, 0.5), out);
}

TEST(VoxelThinner, ReuseAcrossScansOfEverySize) {
  cal::VoxelThinner thinner;
  cal::PointVector out;
  const std::size_t sizes[] = {50000, 10, 3000, 0, 50000, 7};
  uint32_t seed = 10;
  for (std::size_t n : sizes) {
    const cal::PointVector pts = n ? randomScan(n, 20.0, seed++) : cal::PointVector();
    out.clear();
    thinner.thin(pts.data(), pts.size(), 0.25, &out);
    expectSame(out, referenceThinning(pts, 0.25));
  }
}

TEST(VoxelThinner, AppendsAndKeepsTheOutputsCapacity) {
  const cal::PointVector big = randomScan(30000, 40.0, 3);
  const cal::PointVector small = randomScan(500, 40.0, 4);
  cal::VoxelThinner thinner;
  cal::PointVector out;
  thinner.thin(big.data(), big.size(), 0.2, &out);
  const std::size_t capacity = out.capacity();
  const Eigen::Vector3f* storage = out.data();
  out.clear();
  thinner.thin(small.data(), small.size(), 0.2, &out);  // fits: no reallocation
  EXPECT_EQ(out.data(), storage);
  EXPECT_EQ(out.capacity(), capacity);
  const std::size_t first = out.size();
  thinner.thin(small.data(), small.size(), 0.2, &out);  // appends
  ASSERT_EQ(out.size(), 2 * first);
  for (std::size_t i = 0; i < first; ++i) EXPECT_EQ(out[i], out[first + i]);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
