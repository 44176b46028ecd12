// Speed of the Hough ground fit (thesis 3.3.4). Target: at most 50 us for a 361-return scan on
// one core, so a 75 Hz SICK LMS-291 costs under 0.4% of a core.
//   build_*/devel/lib/ladar_perception/ground_hough_bench
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "../unit/ground_hough_scene.h"
#include "ladar_perception/ground/hough_ground.h"

namespace lp = ladar_perception;

namespace {

// A vertical SICK 1.2 m above a sloped road with a car 9 m ahead and a wall at 25 m; 0.5 degree
// steps over 180 degrees from straight down to straight up (361 returns), 1 cm noise.
struct BenchScan {
  std::vector<float> ranges, r, h;
  std::vector<uint8_t> truth;
  BenchScan() {
    hough_test::VerticalScene scene;
    scene.sensor_height = 1.2;
    scene.addGroundLine(0.13, 0.04, -200.0, 25.0);
    scene.addBox(9.0, 13.5, 0.13 + 0.04 * 9.0, 1.4);
    scene.addWall(25.0, 0.0, 8.0);
    scene.scan(-M_PI / 2, M_PI / 360, 361, &ranges, &truth);
    std::mt19937 rng(3);
    std::normal_distribution<float> noise(0.f, 0.01f);
    for (float& v : ranges) {
      if (std::isfinite(v)) v += noise(rng);
    }
    scene.pairs(&r, &h, &truth);
  }
};

const BenchScan& benchScan() {
  static const BenchScan scan;
  return scan;
}

// The whole per-scan path of the nodelet's core: projection through the pose, eq 3.12
// accumulator, runner-up, refinement, eqs 3.13-3.15 labels.
void BM_HoughGroundLaserScan361(benchmark::State& state) {
  const BenchScan& s = benchScan();
  lp::LaserScanView scan;
  scan.angle_min = static_cast<float>(-M_PI / 2);
  scan.angle_increment = static_cast<float>(M_PI / 360);
  scan.range_min = 0.5f;
  scan.range_max = 80.f;
  scan.ranges = s.ranges.data();
  scan.size = s.ranges.size();
  // Sensor y up: rolled 90 degrees about x, 1.2 m above the ground frame's origin.
  lp::SensorPose pose;
  pose.sensor_to_ground.linear() =
      Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitX()).toRotationMatrix();
  pose.sensor_to_ground.translation() = Eigen::Vector3f(0.f, 0.f, 1.2f);
  lp::HoughGround hough;
  lp::ScanGroundResult result;
  for (auto _ : state) {
    hough.classify(scan, pose, &result);
    benchmark::DoNotOptimize(result.classification.labels.data());
  }
  if (!result.fit.valid) state.SkipWithError("no ground line");
  state.counters["ground"] = result.fit.ground;
  state.counters["slope"] = result.fit.slope;
  state.counters["inliers"] = result.fit.inliers;
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size));
}
BENCHMARK(BM_HoughGroundLaserScan361)->Unit(benchmark::kMicrosecond);

// The fit alone on (r, Height) pairs, default and thesis settings.
void BM_HoughLineFit361(benchmark::State& state) {
  const BenchScan& s = benchScan();
  lp::HoughLineFitter fitter(state.range(0) ? lp::houghGroundThesisParams()
                                            : lp::houghGroundDefaultParams());
  lp::GroundLineFit fit;
  for (auto _ : state) {
    fit = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()));
    benchmark::DoNotOptimize(fit);
  }
  state.SetLabel(state.range(0) ? "thesis" : "default");
}
BENCHMARK(BM_HoughLineFit361)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The thesis's 1-DOF fit on the same scan, for comparison.
void BM_OneDofLineFit361(benchmark::State& state) {
  const BenchScan& s = benchScan();
  lp::OneDofLineFitter fitter;
  lp::GroundLineFit fit;
  for (auto _ : state) {
    fit = fitter.fit(s.r.data(), s.h.data(), static_cast<int>(s.r.size()), 0.5f, 40.f);
    benchmark::DoNotOptimize(fit);
  }
}
BENCHMARK(BM_OneDofLineFit361)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
