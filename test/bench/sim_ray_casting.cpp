// Ray-casting rate of the simulator (issue: >= 2 M rays/s on one core, so a 10 Hz HDL-64E with
// 115,200 rays per revolution runs faster than real time). items_per_second = rays per second.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/world.h"

namespace {

using namespace ladar_perception::sim;

const World& worldNamed(const std::string& name) {
  static std::map<std::string, World> worlds;
  auto it = worlds.find(name);
  if (it == worlds.end()) {
    World w;
    std::string error;
    if (!makeStandardWorld(name, 1, &w, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      std::abort();
    }
    it = worlds.emplace(name, std::move(w)).first;
  }
  return it->second;
}

// One HDL-64E revolution from the roof (1.9 m above base_link) at the middle of the world's
// standard drive; Table 4.1's 60 m range unless the argument says otherwise.
void velodyneRevolution(benchmark::State& state, const std::string& name) {
  const World& world = worldNamed(name);
  VelodyneModel model = VelodyneModel::hdl64e();
  model.max_range = static_cast<double>(state.range(0));
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  mount.translation() = Eigen::Vector3d(0, 0, 1.9);
  const Eigen::Isometry3d sensor = world.drivePose(0.5 * world.driveDuration()) * mount;
  SimulatedScan scan;
  uint64_t seed = 0;
  std::size_t returns = 0;
  for (auto _ : state) {
    simulateVelodyneRevolution(world, sensor, model, ++seed, &scan);
    returns += scan.truth.size();
    benchmark::DoNotOptimize(scan.cloud.data.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * model.raysPerRevolution()));
  state.counters["returns_per_rev"] =
      static_cast<double>(returns) / static_cast<double>(state.iterations());
  state.counters["revs_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK_CAPTURE(velodyneRevolution, urban, std::string("urban"))->Arg(60)->Arg(120)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(velodyneRevolution, thesis, std::string("thesis"))->Arg(60)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(velodyneRevolution, hillside, std::string("hillside"))->Arg(60)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(velodyneRevolution, flat, std::string("flat"))->Arg(60)->Arg(120)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
