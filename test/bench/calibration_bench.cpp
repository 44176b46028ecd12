// Speed of the calibration's hot paths on one trial of the thesis experiment (simulated once):
// one hypothesis score (accumulate the target, Algorithm 4 features, eq 4.1 through the KD-tree),
// one linearisation of the refinement, and a whole default calibration.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>

#include "ladar_perception/calibration/experiment.h"

namespace cal = ladar_perception::calibration;
namespace sim = ladar_perception::sim;

namespace {

const cal::ExperimentTrial& trial(const std::string& pair_name) {
  static std::map<std::string, std::unique_ptr<cal::ExperimentTrial>> cache;
  auto it = cache.find(pair_name);
  if (it != cache.end()) return *it->second;
  static sim::World world;
  if (world.empty()) sim::makeStandardWorld("thesis", 1, &world, nullptr);
  cal::PairSetup pair;
  cal::pairFromName(pair_name, &pair, nullptr);
  auto t = std::make_unique<cal::ExperimentTrial>();
  cal::makeTrial(world, pair, cal::ExperimentOptions(), 1000003ULL, t.get(), nullptr);
  return *(cache[pair_name] = std::move(t));
}

void BM_HypothesisScoreFeatures(benchmark::State& state) {
  const cal::ExperimentTrial& t = trial("velodyne-velodyne");
  cal::CalibrationParams p;
  p.initial = t.initial_guess;
  cal::HypothesisCost cost(t.input, p);
  cal::Pose6 h = t.truth;
  for (auto _ : state) {
    h[0] += 1e-6;
    benchmark::DoNotOptimize(cost(h));
  }
}
BENCHMARK(BM_HypothesisScoreFeatures)->Unit(benchmark::kMillisecond);

void BM_HypothesisScoreRawSick(benchmark::State& state) {
  const cal::ExperimentTrial& t = trial("sick-velodyne");
  cal::CalibrationParams p;
  p.initial = t.initial_guess;
  cal::HypothesisCost cost(t.input, p);
  cal::Pose6 h = t.truth;
  for (auto _ : state) {
    h[0] += 1e-6;
    benchmark::DoNotOptimize(cost(h));
  }
}
BENCHMARK(BM_HypothesisScoreRawSick)->Unit(benchmark::kMillisecond);

void BM_RefinementLinearisation(benchmark::State& state) {
  const cal::ExperimentTrial& t = trial("velodyne-velodyne");
  cal::RefinementParams rp;
  cal::PointVector ref;
  cal::accumulate(t.input.reference, t.input.reference_extrinsic, &ref);
  cal::SurfaceModel model;
  model.build(cal::voxelDownsample(ref, rp.reference_voxel), rp);
  const cal::ScanSet target = cal::refinementTarget(t.input.target, rp);
  for (auto _ : state) {
    benchmark::DoNotOptimize(cal::linearise(model, target, t.truth, 0.5, rp.huber).cost);
  }
}
BENCHMARK(BM_RefinementLinearisation)->Unit(benchmark::kMillisecond);

void BM_DefaultCalibration(benchmark::State& state) {
  const cal::ExperimentTrial& t = trial("velodyne-velodyne");
  cal::CalibrationParams p;
  p.initial = t.initial_guess;
  for (auto _ : state) {
    benchmark::DoNotOptimize(cal::calibrate(t.input, p).extrinsic);
  }
}
BENCHMARK(BM_DefaultCalibration)->Unit(benchmark::kSecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
