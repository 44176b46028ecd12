// Speed of the vertical scan ground extraction (one core call per iteration):
//  - KITTI HDL-64 scans from /work/shared/data/kitti_hdl64 (or $LADAR_KITTI_DIR), skipped when
//    the folder is absent;
//  - a simulated HDL-64E revolution of the urban world (always available).
//
// Instruction count of one call (callgrind):
//   valgrind --tool=callgrind --instr-atstart=no ground_vertical_scan_bench --callgrind-once FILE.bin
// loads the file, warms nothing, and instruments exactly one classify call (--thesis: the thesis
// mode; --bins: the default without laser_neighbours; --curb-ground: the default with
// curb_policy ground; --no-local-ground: the default without local_ground; --set key=value: one
// parameter of the table on top, as ground_eval's --set; --warm: after one uninstrumented call,
// as in a running stream).
// Output of one call for comparisons between builds:
//   ground_vertical_scan_bench --dump FILE.bin OUT [--thesis|--bins|--curb-ground|--no-local-ground]
//   [--set key=value ...]
//   (n label bytes, n floats)
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include <benchmark/benchmark.h>
#include <valgrind/callgrind.h>

#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/kitti.h"
#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/world.h"

using namespace ladar_perception;

namespace {

enum class Mode { kDefault, kThesis, kBins, kCurbGround, kNoLocalGround };

VerticalScanParams paramsOf(Mode mode) {
  switch (mode) {
    case Mode::kThesis: return verticalScanThesisParams();
    case Mode::kBins: return verticalScanBinsParams();
    case Mode::kCurbGround: {
      VerticalScanParams p = verticalScanDefaultParams();
      p.curb_policy = kCurbGround;
      return p;
    }
    case Mode::kNoLocalGround: {
      VerticalScanParams p = verticalScanDefaultParams();
      p.local_ground = false;
      return p;
    }
    default: return verticalScanDefaultParams();
  }
}

Mode modeOf(int argc, char** argv, int from) {
  Mode mode = Mode::kDefault;
  for (int a = from; a < argc; ++a) {
    if (std::strcmp(argv[a], "--thesis") == 0) mode = Mode::kThesis;
    if (std::strcmp(argv[a], "--bins") == 0) mode = Mode::kBins;
    if (std::strcmp(argv[a], "--curb-ground") == 0) mode = Mode::kCurbGround;
    if (std::strcmp(argv[a], "--no-local-ground") == 0) mode = Mode::kNoLocalGround;
  }
  return mode;
}

std::string kittiDir() {
  const char* env = std::getenv("LADAR_KITTI_DIR");
  return env ? env : "/work/shared/data/kitti_hdl64";
}

void runClassify(benchmark::State& state, const PackedCloud& cloud, const SensorPose& pose,
                 const VerticalScanParams& params) {
  PointCloudView view;
  std::string error;
  if (!cloud.view(&view, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  VerticalScanGround model(params);
  GroundClassification out;
  model.classify(view, pose, &out);  // workspace warm-up
  for (auto _ : state) {
    model.classify(view, pose, &out);
    benchmark::DoNotOptimize(out.labels.data());
    benchmark::ClobberMemory();
  }
  state.counters["points"] = static_cast<double>(view.size());
  state.counters["obstacle_fraction"] =
      static_cast<double>(out.count(kLabelObstacle)) / std::max<std::size_t>(1, view.size());
}

void BM_Kitti(benchmark::State& state, const std::string& file, Mode mode) {
  PackedCloud cloud;
  std::string error;
  if (!readKittiBin(kittiDir() + "/" + file, &cloud, &error)) {
    state.SkipWithError(("KITTI data absent: " + error).c_str());
    for (auto _ : state) {
    }
    return;
  }
  runClassify(state, cloud, SensorPose::fromHeight(1.73f), paramsOf(mode));
}

void BM_SimulatedUrban(benchmark::State& state, Mode mode) {
  static sim::SimulatedScan scan;
  static bool made = false;
  if (!made) {
    sim::World world;
    std::string error;
    if (!sim::makeStandardWorld("urban", 1, &world, &error)) {
      state.SkipWithError(error.c_str());
      return;
    }
    Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
    mount.translation().z() = 1.73;
    sim::simulateVelodyneRevolution(world, world.drivePose(0.5 * world.driveDuration()) * mount,
                                    sim::VelodyneModel::hdl64e(sim::NoiseProfile::kDatasheet), 7,
                                    &scan);
    made = true;
  }
  runClassify(state, scan.cloud, SensorPose::fromHeight(1.73f), paramsOf(mode));
}

int callgrindOnce(const std::string& path, const VerticalScanParams& params, bool warm) {
  PackedCloud cloud;
  std::string error;
  PointCloudView view;
  if (!readKittiBin(path, &cloud, &error) || !cloud.view(&view, &error)) {
    std::cerr << error << "\n";
    return 1;
  }
  VerticalScanGround model(params);
  GroundClassification out;
  // --warm: the workspace of a steady-state call (allocated and touched once before), e.g. for
  // --cache-sim=yes.
  if (warm) model.classify(view, SensorPose::fromHeight(1.73f), &out);
  CALLGRIND_START_INSTRUMENTATION;
  model.classify(view, SensorPose::fromHeight(1.73f), &out);
  CALLGRIND_STOP_INSTRUMENTATION;
  std::cout << view.size() << " points, " << out.count(kLabelObstacle) << " obstacles\n";
  return 0;
}

// Writes the labels and P(obstacle) of one classify call (n label bytes, then n floats): a
// byte-for-byte comparison of two builds, e.g. before and after a speed change.
int dumpOnce(const std::string& path, const std::string& out_path, const VerticalScanParams& params) {
  PackedCloud cloud;
  std::string error;
  PointCloudView view;
  if (!readKittiBin(path, &cloud, &error) || !cloud.view(&view, &error)) {
    std::cerr << error << "\n";
    return 1;
  }
  VerticalScanGround model(params);
  GroundClassification out;
  model.classify(view, SensorPose::fromHeight(1.73f), &out);
  std::FILE* f = std::fopen(out_path.c_str(), "wb");
  if (!f) {
    std::cerr << "cannot write " << out_path << "\n";
    return 1;
  }
  const bool ok = std::fwrite(out.labels.data(), 1, out.size(), f) == out.size() &&
                  std::fwrite(out.p_obstacle.data(), sizeof(float), out.size(), f) == out.size();
  std::fclose(f);
  return ok ? 0 : 1;
}

// The mode's params with each --set key=value of argv[from..] on top; false after a message.
bool paramsOfArgs(int argc, char** argv, int from, VerticalScanParams* params) {
  *params = paramsOf(modeOf(argc, argv, from));
  for (int a = from; a < argc; ++a) {
    if (std::strcmp(argv[a], "--set") == 0 && a + 1 < argc) {
      const std::string kv = argv[++a];
      const std::size_t eq = kv.find('=');
      std::string error;
      if (eq == std::string::npos ||
          !setVerticalScanParam(params, kv.substr(0, eq), std::atof(kv.c_str() + eq + 1), &error)) {
        std::cerr << "--set " << kv << ": " << (error.empty() ? "expected key=value" : error) << "\n";
        return false;
      }
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  VerticalScanParams params;
  if (argc >= 3 && std::strcmp(argv[1], "--callgrind-once") == 0) {
    bool warm = false;
    for (int a = 3; a < argc; ++a) warm = warm || std::strcmp(argv[a], "--warm") == 0;
    if (!paramsOfArgs(argc, argv, 3, &params)) return 2;
    return callgrindOnce(argv[2], params, warm);
  }
  if (argc >= 4 && std::strcmp(argv[1], "--dump") == 0) {
    if (!paramsOfArgs(argc, argv, 4, &params)) return 2;
    return dumpOnce(argv[2], argv[3], params);
  }
  for (const char* f : {"000000.bin", "000001.bin"}) {
    benchmark::RegisterBenchmark((std::string("VerticalScan/kitti/") + f).c_str(),
                                 [f](benchmark::State& s) { BM_Kitti(s, f, Mode::kDefault); })
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("VerticalScanThesis/kitti/000000.bin",
                               [](benchmark::State& s) { BM_Kitti(s, "000000.bin", Mode::kThesis); })
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("VerticalScanBins/kitti/000000.bin",
                               [](benchmark::State& s) { BM_Kitti(s, "000000.bin", Mode::kBins); })
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("VerticalScanNoLocalGround/kitti/000000.bin",
                               [](benchmark::State& s) { BM_Kitti(s, "000000.bin", Mode::kNoLocalGround); })
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("VerticalScan/simulated_urban",
                               [](benchmark::State& s) { BM_SimulatedUrban(s, Mode::kDefault); })
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("VerticalScanThesis/simulated_urban",
                               [](benchmark::State& s) { BM_SimulatedUrban(s, Mode::kThesis); })
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("VerticalScanBins/simulated_urban",
                               [](benchmark::State& s) { BM_SimulatedUrban(s, Mode::kBins); })
      ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
