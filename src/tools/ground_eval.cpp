// ground_eval: accuracy of the ground models on the simulator's worlds with ground truth,
// printed as a Markdown table (with the command line that produced it).
// (Over 600 lines: one main for the tool's five modes, which share its argument parsing and
// Markdown output; every score it prints is computed in the eval library.)
//
//   ground_eval [--worlds flat,urban,rural,hillside,potholes] [--method NAME[,NAME]]
//               [--noise datasheet|table4.1|none] [--scans N] [--seed S] [--classes]
//               [--sick-scans N] [--at-ground-band M] [--height-bound] [--region-bound]
//               [--region-seed-kept F] [--misses] [--markdown OUT]
// By default every ground model (HDL-64E revolutions) on every standard world, then the vertical
// SICK's ground fits (the Hough fit of 3.3.4 against the 1-DOF vertical scan line), with the
// median core time per scan; then the thesis's findings checked against the table (those whose
// rows were evaluated): the plane (3.1) and analog signal (3.2) baselines fail on the crowned
// road ("rural") and the hillside but not on flat ground, where the vertical scan method does
// not; on the undulating hillside the Hough fit beats the 1-DOF line on the vertical SICK.
// --at-ground-band M (e.g. 0.02): obstacle returns within M in height of a ground surface
// less than 0.3 m away are not scored (ground_evaluation.h); the HDL-64E rows only.
// --height-bound adds, per world, the obstacle recall that a test of each return's height
// against the exact ground surface reaches while keeping 99% of the ground (heightTestBound in
// ground_evaluation.h): what height alone can separate at this noise, for any ground model.
// --region-bound adds, per world, the pothole recall and the ground recall of a region model of
// holes on the exact ground surface (regionModelBound in ground_evaluation.h): seeds found by
// their depth, linked into holes, each hole's convex hull filled. --region-seed-kept F (0 < F < 1,
// default 0.9999): seeds are deeper than all but 1 - F of the ground returns in their range band.
// --misses adds, per world and model, where the missed obstacle returns are: by height to the
// ground next to them and by range (MissBreakdown in ground_evaluation.h).
// ground_eval --semantickitti DIR [--frames a:b] [--sensor-height M] [--compare-masks NAME=DIR]:
// the methods on real labelled scans in the SemanticKITTI layout instead (eval/semantic_kitti.h:
// protocols A and B, per class, per range band, F1 spread over the frames, median ms), with
// other programs' ground masks scored in the same run.
// --markdown also writes the table and the findings to OUT (for the README). Exit status 3 when a
// finding checked is not reproduced (1: an evaluation failed, 2: bad arguments).
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <dirent.h>
#include <unistd.h>
#include <valgrind/callgrind.h>

#include "ladar_perception/eval/phantom_holes.h"
#include "ladar_perception/eval/real_ground_eval.h"
#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/eval/hough_evaluation.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/kitti.h"

using namespace ladar_perception;

namespace {
std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}
// Writes `text` to `path` through a temporary file and a rename; false with a message.
bool writeTextFile(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::ofstream f(tmp);
  f << text;
  f.close();
  if (!f || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::cerr << "ground_eval: cannot write " << path << "\n";
    return false;
  }
  return true;
}

// A ground model by name with the --set overrides (vertical scan models only); nullptr with a
// reason otherwise.
std::unique_ptr<GroundModel> makeModel(const std::string& name, const std::vector<std::string>& sets,
                                       std::string* error) {
  std::unique_ptr<GroundModel> model = makeGroundModel(name, error);
  if (!model || sets.empty()) return model;
  auto* vs = dynamic_cast<VerticalScanGround*>(model.get());
  if (!vs) {
    *error = "--set applies to vertical scan models only (not " + name + ")";
    return nullptr;
  }
  VerticalScanParams params = vs->params();
  for (const std::string& kv : sets) {
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos ||
        !setVerticalScanParam(&params, kv.substr(0, eq), std::atof(kv.c_str() + eq + 1), error)) {
      *error = "bad --set " + kv + " " + *error;
      return nullptr;
    }
  }
  vs->setParams(params);
  return model;
}

// ground_eval --semantickitti DIR: every method over the labelled frames of DIR, and the mask
// files of other programs (--compare-masks NAME=MASK_DIR), scored under protocols A and B.
int evaluateSemanticKitti(const std::string& dir, const std::string& frame_range, float sensor_height,
                          const std::vector<std::string>& methods, const std::vector<std::string>& sets,
                          const std::vector<std::string>& mask_sources, const std::string& png_prefix,
                          const std::string& cmdline, std::string* markdown) {
  long first = 0, last = -1;
  if (!frame_range.empty() && !eval::parseFrameRange(frame_range, &first, &last)) {
    std::cerr << "ground_eval: --frames takes a:b, a:, :b or a frame number\n";
    return 2;
  }
  std::string error;
  std::vector<eval::LabelledFrameFiles> files;
  std::vector<eval::LabelledFrame> frames;
  if (!eval::listLabelledFrames(dir, first, last, &files, &error) ||
      !eval::loadLabelledFrames(files, &frames, &error)) {
    std::cerr << "ground_eval: " << error << "\n";
    return 1;
  }
  std::vector<eval::MethodScore> scores;
  const SensorPose pose = SensorPose::fromHeight(sensor_height);
  for (const std::string& m : methods) {
    std::unique_ptr<GroundModel> model = makeModel(m, sets, &error);
    if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
    eval::MethodScore score;
    std::vector<std::vector<uint8_t>> called;
    if (!eval::scoreGroundModel(model.get(), frames, pose, &score, &error, png_prefix.empty() ? nullptr : &called)) {
      std::cerr << "ground_eval: " << error << "\n";
      return 1;
    }
    for (std::size_t k = 0; k < called.size(); ++k) {
      const std::string path = png_prefix + "_" + score.method + "_" + frames[k].name + ".png";
      if (!eval::writeRealErrorPng(path, frames[k], called[k], sensor_height, &error))
        std::cerr << "ground_eval: " << error << "\n";
    }
    scores.push_back(std::move(score));
  }
  for (const std::string& source : mask_sources) {
    const std::size_t eq = source.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == source.size()) {
      std::cerr << "ground_eval: --compare-masks takes NAME=MASK_DIR\n";
      return 2;
    }
    eval::MethodScore score;
    if (!eval::scoreMaskFiles(source.substr(0, eq), source.substr(eq + 1), frames, sensor_height, &score, &error)) {
      std::cerr << "ground_eval: " << error << "\n";
      return 1;
    }
    scores.push_back(std::move(score));
  }
  std::string names;
  for (const eval::LabelledFrame& f : frames) names += (names.empty() ? "" : ", ") + f.name;
  std::string& out = *markdown;
  out += "`" + cmdline + "`\n\nFrames of " + dir + ": " + names + " (sensor height " +
         std::to_string(sensor_height).substr(0, 4) + " m). Protocol A: ground = road, parking, sidewalk, "
         "other-ground, lane-marking, terrain; vegetation, unlabeled and outlier not scored. Protocol B: "
         "vegetation below -0.75 x the sensor height is ground; unlabeled and outlier called ground are "
         "dropped.\n\n";
  out += eval::realGroundSummaryTable(scores);
  out += "\nProtocol A by class (ground classes: share called ground; non-ground: share called ground, "
         "with the count):\n\n";
  out += eval::realGroundClassTable(scores);
  out += "\nProtocol A by horizontal range:\n\n";
  out += eval::realGroundRangeTable(scores);
  std::fputs(out.c_str(), stdout);
  return 0;
}


// ground_eval --holes: negative obstacles scored per hole (evaluateHoles in ground_evaluation.h)
// on the worlds with holes.
int evaluateHoleTable(const std::vector<std::string>& worlds, const std::vector<std::string>& methods,
                      const std::vector<std::string>& sets, sim::NoiseProfile noise, int scans, uint32_t seed,
                      const std::string& cmdline, std::string* markdown) {
  const HoleParams params;
  std::string& out = *markdown;
  char buf[512];
  out += "`" + cmdline + "`\n\nA hole: pothole cells at least 25 cm across and 5 cm deep; counted in a scan "
         "when within 30 m and at least one return lies inside it; found when one of them is called obstacle.\n\n"
         "| world | method | noise | scans | holes | holes seen (hole x scan) | found | hole recall | "
         "0-10 m | 10-20 m | 20-30 m | returns in holes called obstacle |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& w : worlds) {
    for (const std::string& m : methods) {
      std::string error;
      std::unique_ptr<GroundModel> model = makeModel(m, sets, &error);
      if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
      HoleScore score;
      if (!evaluateHoles(w, model.get(), noise, scans, seed, params, &score, &error)) {
        std::cerr << "ground_eval: " << error << "\n";
        return 1;
      }
      if (score.holes == 0) continue;  // a world without holes
      std::snprintf(buf, sizeof(buf), "| %s | %s | %s | %zu | %zu | %zu | %zu | %.2f%% |", w.c_str(), m.c_str(),
                    sim::noiseProfileName(noise), score.scans, score.holes, score.seen, score.found,
                    100.0 * score.recall());
      out += buf;
      for (int b = 0; b < 3; ++b) {
        std::snprintf(buf, sizeof(buf), " %zu/%zu |", score.found_by_range[b], score.seen_by_range[b]);
        out += buf;
      }
      std::snprintf(buf, sizeof(buf), " %.2f%% |\n",
                    100.0 * GroundAccuracy::ratio(score.returns_called_obstacle, score.returns_in_holes));
      out += buf;
    }
  }
  std::fputs(out.c_str(), stdout);
  return 0;
}

// ground_eval --phantom-holes DIR: the KITTI scans DIR/NNNNNN.bin through each method, and the
// holes it reports where real road has none (eval/phantom_holes.h).
int evaluatePhantomHoles(const std::string& dir, const std::string& frame_range, float sensor_height,
                         const std::vector<std::string>& methods, const std::vector<std::string>& sets,
                         const std::vector<std::string>& mask_sources, const std::string& cmdline,
                         std::string* markdown) {
  long first = 0, last = -1;
  if (!frame_range.empty() && !eval::parseFrameRange(frame_range, &first, &last)) {
    std::cerr << "ground_eval: --frames takes a:b, a:, :b or a frame number\n";
    return 2;
  }
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str())) {
    while (const dirent* e = readdir(d)) {
      const std::string f = e->d_name;
      if (f.size() != 10 || f.compare(6, 4, ".bin") != 0 ||
          !std::all_of(f.begin(), f.begin() + 6, [](char c) { return c >= '0' && c <= '9'; }))
        continue;
      const long k = std::atol(f.substr(0, 6).c_str());
      if (k >= first && (last < 0 || k <= last)) names.push_back(f.substr(0, 6));
    }
    closedir(d);
  }
  std::sort(names.begin(), names.end());
  if (names.empty()) {
    std::cerr << "ground_eval: no NNNNNN.bin scans in " << dir << "\n";
    return 1;
  }
  std::vector<PackedCloud> clouds(names.size());
  std::string error;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!readKittiBin(dir + "/" + names[k] + ".bin", &clouds[k], &error)) {
      std::cerr << "ground_eval: " << error << "\n";
      return 1;
    }
  }
  const eval::PhantomHoleParams params;
  const SensorPose pose = SensorPose::fromHeight(sensor_height);
  std::string& out = *markdown;
  char buf[512];
  out += "`" + cmdline + "`\n\nScans " + names.front() + "-" + names.back() + " of " + dir +
         ". Obstacle returns within 30 m 5 cm to 1 m below the local ground (the lowest of the medians of "
         "the model's ground returns in the 1 m cells of the 3 x 3 m around them), clustered in touching 0.25 m cells; a cluster of 2 or "
         "more returns is a hole, a phantom when no obstacle return 20 cm or more above the ground lies "
         "within 0.5 m (the foot of a car or a wall). A scan accounts for 60 m of road (30 m ahead and "
         "behind).\n\n| method | scans | below-ground clusters | phantom holes | per scan | per 100 m of road | "
         "deepest phantom [m] |\n|---|---|---|---|---|---|---|\n";
  // The methods, then other programs' masks (1 = ground; anything else is taken as obstacle).
  const std::size_t rows = methods.size() + mask_sources.size();
  for (std::size_t row = 0; row < rows; ++row) {
    std::unique_ptr<GroundModel> model;
    std::string m, mask_dir;
    if (row < methods.size()) {
      m = methods[row];
      model = makeModel(m, sets, &error);
      if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
    } else {
      const std::string& source = mask_sources[row - methods.size()];
      const std::size_t eq = source.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == source.size()) {
        std::cerr << "ground_eval: --compare-masks takes NAME=MASK_DIR\n";
        return 2;
      }
      m = source.substr(0, eq);
      mask_dir = source.substr(eq + 1);
    }
    GroundClassification result;
    std::vector<uint8_t> mask;
    std::vector<eval::PhantomHole> phantoms;
    std::size_t clusters = 0, phantom_count = 0;
    float deepest = 0.f;
    for (std::size_t k = 0; k < clouds.size(); ++k) {
      PointCloudView view;
      if (!clouds[k].view(&view, &error)) { std::cerr << "ground_eval: " << error << "\n"; return 1; }
      if (model) {
        model->classify(view, pose, &result);
      } else {
        if (!eval::readGroundMask(mask_dir + "/" + names[k] + ".mask", view.size(), &mask, &error)) {
          std::cerr << "ground_eval: " << error << "\n";
          return 1;
        }
        result.resize(view.size());
        for (std::size_t i = 0; i < view.size(); ++i) {
          result.labels[i] = mask[i] == 1 ? kLabelGround : kLabelObstacle;
          result.p_obstacle[i] = mask[i] == 1 ? 0.f : 1.f;
        }
      }
      clusters += eval::findPhantomHoles(view, result, params, &phantoms);
      phantom_count += phantoms.size();
      for (const eval::PhantomHole& h : phantoms) deepest = std::max(deepest, h.depth);
    }
    const double scans = static_cast<double>(clouds.size());
    std::snprintf(buf, sizeof(buf), "| %s | %zu | %zu | %zu | %.2f | %.2f | %.2f |\n", m.c_str(), clouds.size(),
                  clusters, phantom_count, phantom_count / scans,
                  100.0 * phantom_count / (scans * params.roadPerScan()), deepest);
    out += buf;
  }
  std::fputs(out.c_str(), stdout);
  return 0;
}
}  // namespace

// The per-sensor table (--sensor): every sensor x world x method on the evaluation's scans,
// with P/R/F1, obstacle recall, the median time per scan and, with --instructions, the
// instructions of one classify call (callgrind, one run per sensor and world: the middle scan).
struct SensorRow {
  std::string sensor, world, method;
  int beams = 0;
  GroundAccuracy acc;
  double ms = 0.0;
  double points_per_scan = 0.0;
  long long instructions = -1;
};

// --mount-rpy R,P: the sensor rolled and pitched on its mount [deg] (SensorPose::fromMount); the
// model is given the tilted pose, as tf would give it.
void tiltMount(const std::vector<double>& rpy, EvaluationSensor* sensor) {
  if (rpy.size() == 2) sensor->tilt(rpy[0], rpy[1]);
}

double f1Of(const GroundAccuracy& a) {
  const double p = a.groundPrecision(), r = a.groundRecall();
  return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0;
}

// Instructions of one cold classify call on the middle scan (the budget's convention: the first
// call of a fresh model, as ground_vertical_scan_bench --callgrind-once), counted by running
// this program under callgrind in --callgrind-scan mode; -1 when valgrind is not there.
long long countInstructions(const std::string& sensor, const std::string& world, const std::string& method,
                            const std::vector<std::string>& sets, const std::string& noise, int scans,
                            uint32_t seed, const std::vector<double>& mount_rpy) {
  char exe[4096];
  const ssize_t len = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  if (len <= 0) return -1;
  exe[len] = 0;
  char tmp[] = "/tmp/ground_eval_callgrind_XXXXXX";
  const int fd = mkstemp(tmp);
  if (fd < 0) return -1;
  close(fd);
  std::string cmd = "valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=" + std::string(tmp) + " " +
                    exe + " --callgrind-scan " + sensor + " --worlds " + world + " --method " + method +
                    " --noise " + noise + " --scans " + std::to_string(scans) + " --seed " + std::to_string(seed);
  for (const std::string& kv : sets) cmd += " --set " + kv;
  if (mount_rpy.size() == 2) cmd += " --mount-rpy " + std::to_string(mount_rpy[0]) + "," + std::to_string(mount_rpy[1]);
  cmd += " > /dev/null 2>&1";
  long long total = -1;
  if (std::system(cmd.c_str()) == 0) {
    std::ifstream f(tmp);
    std::string line;
    while (std::getline(f, line)) {
      if (line.rfind("summary:", 0) == 0 || line.rfind("totals:", 0) == 0) total = std::atoll(line.c_str() + line.find(':') + 1);
    }
  }
  std::remove(tmp);
  return total;
}

// --callgrind-scan SENSOR: one instrumented classify call on the middle scan of the first world.
int callgrindScan(const std::string& sensor_name, const std::string& world_name, const std::string& method,
                  const std::vector<std::string>& sets, sim::NoiseProfile noise, int scans, uint32_t seed,
                  const std::vector<double>& mount_rpy) {
  EvaluationSensor sensor;
  std::string error;
  sim::World world;
  if (!makeEvaluationSensor(sensor_name, noise, &sensor, &error) ||
      !sim::makeStandardWorld(world_name, seed, &world, &error)) {
    std::cerr << "ground_eval: " << error << "\n";
    return 2;
  }
  tiltMount(mount_rpy, &sensor);
  std::unique_ptr<GroundModel> model = makeModel(method, sets, &error);
  if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
  model->setLidarModel(sensor.lidar);
  const int k = scans / 2;
  const double t = world.driveDuration() * (k + 0.5) / scans;
  sim::SimulatedScan scan;
  sim::simulateVelodyneRevolution(world, world.drivePose(t) * sensor.mount, sensor.model, seed * 1000u + k, &scan);
  PointCloudView view;
  if (!scan.cloud.view(&view, &error)) return 1;
  SensorPose pose;
  pose.sensor_to_ground = sensor.mount.cast<float>();
  GroundClassification result;
  CALLGRIND_START_INSTRUMENTATION;
  model->classify(view, pose, &result);
  CALLGRIND_STOP_INSTRUMENTATION;
  std::printf("%zu points\n", view.size());
  return 0;
}

int evaluateSensorTable(const std::vector<std::string>& sensors, const std::vector<std::string>& worlds,
                        const std::vector<std::string>& methods, const std::vector<std::string>& sets,
                        const std::string& noise_name, sim::NoiseProfile noise, int scans, uint32_t seed,
                        bool instructions, const std::vector<double>& mount_rpy, const std::string& cmdline,
                        std::string* markdown) {
  std::vector<SensorRow> rows;
  int status = 0;
  for (const std::string& s : sensors) {
    EvaluationSensor sensor;
    std::string error;
    if (!makeEvaluationSensor(s, noise, &sensor, &error)) {
      std::cerr << "ground_eval: " << error << "\n";
      return 2;
    }
    tiltMount(mount_rpy, &sensor);
    for (const std::string& m : methods) {
      std::unique_ptr<GroundModel> model = makeModel(m, sets, &error);
      if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
      TimedGroundModel timed(model.get());
      for (const std::string& w : worlds) {
        SensorRow row;
        row.sensor = s;
        row.world = w;
        row.method = model->name();
        row.beams = sensor.lidar.beams();
        timed.reset();
        if (!evaluateGroundModel(sensor, w, &timed, scans, seed, &row.acc, &error)) {
          std::cerr << "ground_eval: " << s << " " << w << ": " << error << "\n";
          status = 1;
          continue;
        }
        row.points_per_scan = static_cast<double>(row.acc.points) / std::max<std::size_t>(row.acc.scans, 1);
        row.ms = medianMs(timed.milliseconds());
        if (instructions) row.instructions = countInstructions(s, w, m, sets, noise_name, scans, seed, mount_rpy);
        std::fprintf(stderr, "%s %s %s: F1 %.2f%%\n", s.c_str(), w.c_str(), row.method.c_str(), 100.0 * f1Of(row.acc));
        rows.push_back(row);
      }
    }
  }
  std::string& out = *markdown;
  char buf[1024];
  out += "`" + cmdline + "`\n\n";
  out += "| sensor | beams | world | method | scans | returns per scan | ground precision | ground recall | F1 | "
         "obstacle recall | median ms/scan | instructions/scan | instructions/return |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const SensorRow& r : rows) {
    char ins[64] = "-", per[64] = "-";
    if (r.instructions >= 0) {
      std::snprintf(ins, sizeof(ins), "%.2f M", r.instructions / 1e6);
      std::snprintf(per, sizeof(per), "%.0f", r.instructions / std::max(r.points_per_scan, 1.0));
    }
    std::snprintf(buf, sizeof(buf), "| %s | %d | %s | %s | %zu | %.0f | %.2f%% | %.2f%% | %.2f%% | %.2f%% | %.2f | %s | %s |\n",
                  r.sensor.c_str(), r.beams, r.world.c_str(), r.method.c_str(), r.acc.scans, r.points_per_scan,
                  100.0 * r.acc.groundPrecision(), 100.0 * r.acc.groundRecall(), 100.0 * f1Of(r.acc),
                  100.0 * r.acc.obstacleRecall(), r.ms, ins, per);
    out += buf;
  }
  // The targets: F1 >= 97 % for 32 beams or more, >= 95 % below, on the urban and rural worlds.
  std::string missed;
  for (const SensorRow& r : rows) {
    if (r.world != "urban" && r.world != "rural") continue;
    const double target = r.beams >= 32 ? 97.0 : 95.0;
    if (100.0 * f1Of(r.acc) < target) {
      std::snprintf(buf, sizeof(buf), "%s%s on %s (%s): F1 %.2f%% < %.0f%%", missed.empty() ? "" : "; ",
                    r.sensor.c_str(), r.world.c_str(), r.method.c_str(), 100.0 * f1Of(r.acc), target);
      missed += buf;
    }
  }
  out += missed.empty() ? "\nF1 targets (>= 97 % from 32 beams, >= 95 % below, urban and rural): all met.\n"
                        : "\nF1 targets (>= 97 % from 32 beams, >= 95 % below, urban and rural) missed: " + missed + ".\n";
  std::fputs(out.c_str(), stdout);
  return status;
}

// Top-down picture of the middle scan of the evaluation (eval::writeOutcomePng): correct ground
// dark green, correct obstacle dark red, missed obstacle magenta, false obstacle yellow,
// unknown grey; 80 m wide.
void writeErrorPng(const std::string& path, const std::string& world_name, GroundModel* model,
                   sim::NoiseProfile noise, int scans, uint32_t seed) {
  sim::World world;
  std::string error;
  if (!sim::makeStandardWorld(world_name, seed, &world, &error)) return;
  const int k = scans / 2;
  const double t = world.driveDuration() * (k + 0.5) / scans;
  const Eigen::Isometry3d mount = evaluationSensorMount();
  sim::SimulatedScan scan;
  sim::simulateVelodyneRevolution(world, world.drivePose(t) * mount,
                                  sim::VelodyneModel::hdl64e(noise), seed * 1000u + k, &scan);
  PointCloudView view;
  if (!scan.cloud.view(&view, &error)) return;
  SensorPose pose;
  pose.sensor_to_ground = mount.cast<float>();
  GroundClassification res;
  model->classify(view, pose, &res);
  std::vector<eval::PointOutcome> outcome(res.size(), eval::PointOutcome::kUnscored);
  for (std::size_t i = 0; i < res.size(); ++i) {
    const bool g = sim::isGroundClass(static_cast<sim::SurfaceClass>(scan.truth[i]));
    const uint8_t l = res.labels[i];
    if (l == kLabelUnknown) continue;
    outcome[i] = g ? (l == kLabelGround ? eval::PointOutcome::kGround : eval::PointOutcome::kMissedGround)
                   : (l == kLabelObstacle ? eval::PointOutcome::kObstacle : eval::PointOutcome::kFalseGround);
  }
  eval::writeOutcomePng(path, view, outcome, &error);
}

int main(int argc, char** argv) {
  std::vector<std::string> worlds = sim::standardWorldNames();
  std::vector<std::string> methods = groundModelNames();
  int sick_scans = 200;       // vertical SICK scans per world (0: no SICK rows)
  std::string markdown_path;  // --markdown OUT: the table also written to OUT
  std::string noise_name = "datasheet";
  int scans = 10;
  uint32_t seed = 1;
  bool per_class = false;
  double at_ground_band = 0.0;
  bool height_bound = false;
  bool region_bound = false;
  RegionModelParams region_params;
  bool misses = false;
  std::vector<std::string> sets;
  std::string png_prefix;  // PREFIX_<world>.png: the middle scan's errors, top-down  // key=value overrides of the vertical scan params
  std::string semantickitti_dir, frame_range;  // --semantickitti DIR [--frames a:b]
  float sensor_height = 1.73f;                    // real scans: metres above the ground
  std::vector<std::string> mask_sources;          // --compare-masks NAME=MASK_DIR
  bool holes = false;                             // --holes: the per-hole table
  std::string phantom_dir;                        // --phantom-holes DIR (KITTI .bin scans)
  std::vector<std::string> sensors;                // --sensor NAME[,NAME] | all: the per-sensor table
  bool instructions = false;                      // --instructions: callgrind counts in that table
  std::string callgrind_sensor;                   // --callgrind-scan SENSOR (used by --instructions)
  std::vector<double> mount_rpy;                  // --mount-rpy R,P [deg] of the --sensor table
  std::string cmdline = "ground_eval";
  for (int i = 1; i < argc; ++i) cmdline += std::string(" ") + argv[i];
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) { std::cerr << "ground_eval: " << a << " needs a value\n"; std::exit(2); }
      return argv[++i];
    };
    if (a == "--worlds") worlds = split(next());
    else if (a == "--method") methods = split(next());
    else if (a == "--semantickitti") semantickitti_dir = next();
    else if (a == "--frames") frame_range = next();
    else if (a == "--sensor-height") sensor_height = std::strtof(next().c_str(), nullptr);
    else if (a == "--compare-masks") mask_sources.push_back(next());
    else if (a == "--holes") holes = true;
    else if (a == "--phantom-holes") phantom_dir = next();
    else if (a == "--noise") noise_name = next();
    else if (a == "--scans") scans = std::atoi(next().c_str());
    else if (a == "--seed") seed = static_cast<uint32_t>(std::strtoul(next().c_str(), nullptr, 10));
    else if (a == "--classes") per_class = true;
    else if (a == "--set") sets.push_back(next());
    else if (a == "--png-errors") png_prefix = next();
    else if (a == "--sick-scans") sick_scans = std::atoi(next().c_str());
    else if (a == "--at-ground-band") at_ground_band = std::atof(next().c_str());
    else if (a == "--height-bound") height_bound = true;
    else if (a == "--region-bound") region_bound = true;
    else if (a == "--region-seed-kept") {
      region_params.seed_ground_kept = std::atof(next().c_str());
      if (!(region_params.seed_ground_kept > 0.0 && region_params.seed_ground_kept < 1.0)) {
        std::cerr << "ground_eval: --region-seed-kept needs a fraction between 0 and 1\n";
        return 2;
      }
    }
    else if (a == "--misses") misses = true;
    else if (a == "--sensor") {
      sensors = split(next());
      if (sensors.size() == 1 && sensors[0] == "all") {
        sensors.clear();
        for (const LidarModel& m : lidarModels()) sensors.push_back(m.name);
      }
    }
    else if (a == "--instructions") instructions = true;
    else if (a == "--mount-rpy") {
      for (const std::string& v : split(next())) mount_rpy.push_back(std::atof(v.c_str()));
      if (mount_rpy.size() != 2) { std::cerr << "ground_eval: --mount-rpy needs R,P in degrees\n"; return 2; }
    }
    else if (a == "--callgrind-scan") callgrind_sensor = next();
    else if (a == "--markdown") markdown_path = next();
    else {
      const bool help = a == "-h" || a == "--help";
      std::ostream& out = help ? std::cout : std::cerr;
      if (!help) out << "ground_eval: unknown argument " << a << "\n";
      out << "usage: ground_eval [--worlds a,b] [--method m1,m2] "
             "[--noise datasheet|table4.1|none] [--scans N] [--seed S] [--classes] [--set key=value]... "
             "[--png-errors PREFIX] [--sick-scans N] [--at-ground-band M] [--height-bound] [--region-bound] [--region-seed-kept F] [--misses] [--markdown OUT]\n"
             "       ground_eval --sensor NAME[,NAME]|all [--worlds a,b] [--method m1,m2] [--noise N] [--scans N] [--seed S] "
             "[--set key=value]... [--mount-rpy R,P] [--instructions] [--markdown OUT]\n"
             "       ground_eval --semantickitti DIR [--frames a:b] [--sensor-height M] [--method m1,m2] [--set key=value]... "
             "[--compare-masks NAME=MASK_DIR]... [--png-errors PREFIX] [--markdown OUT]\n"
             "       ground_eval --holes [--worlds a,b] [--method m1,m2] [--noise N] [--scans N] [--seed S] [--markdown OUT]\n"
             "       ground_eval --phantom-holes KITTI_DIR [--frames a:b] [--sensor-height M] [--method m1,m2] "
             "[--compare-masks NAME=MASK_DIR]... [--markdown OUT]\n"
             "  --semantickitti DIR: real labelled scans (DIR/velodyne/NNNNNN.bin, DIR/labels/NNNNNN.label) scored\n"
             "    under protocols A and B, by class and by range; --compare-masks scores another program's\n"
             "    MASK_DIR/NNNNNN.mask (one byte per return, 1 = ground) in the same run\n"
             "  --sensor: the per-sensor table (sensor x world x method: P/R/F1, obstacle recall, ms per scan;\n"
             "    --instructions adds callgrind's instructions per scan and per return; --mount-rpy tilts the\n"
             "    sensor on its mount [deg]), default worlds urban,rural,\n"
             "    default method vertical_scan; sensors: " + lidarModelNames() + "\n"
             "  --holes: negative obstacles per hole (>= 25 cm across, >= 5 cm deep, within 30 m, in sight)\n"
             "  --phantom-holes KITTI_DIR: holes reported on real road (clusters below the local ground, no object)\n"
             "  worlds (default all):";
      for (const std::string& w : sim::standardWorldNames()) out << " " << w;
      out << "\n  methods (default all):";
      for (const std::string& m : groundModelNames()) out << " " << m;
      out << "\n  --sick-scans N: vertical SICK scans per world for the Hough / 1-DOF rows (default 200, 0: none)\n"
             "  After the table: the thesis's findings (3.1-3.3.4) checked on the rows evaluated.\n"
             "  Exit status: 0 ok, 1 an evaluation failed, 2 bad arguments, 3 a finding not reproduced.\n";
      return help ? 0 : 2;
    }
  }
  sim::NoiseProfile noise;
  if (!sim::noiseProfileFromName(noise_name, &noise)) {
    std::cerr << "ground_eval: unknown noise profile " << noise_name << "\n";
    return 2;
  }
  if (scans < 1 || sick_scans < 0) { std::cerr << "ground_eval: --scans must be >= 1, --sick-scans >= 0\n"; return 2; }
  // The table goes to stdout and, with --markdown, into `markdown` for OUT.
  std::string markdown;
  const bool default_worlds = worlds == sim::standardWorldNames();
  const bool default_methods = methods == groundModelNames();
  if (!callgrind_sensor.empty()) {
    return callgrindScan(callgrind_sensor, worlds.front(), methods.front(), sets, noise, scans, seed, mount_rpy);
  }
  if (!sensors.empty()) {
    if (default_worlds) worlds = {"urban", "rural"};
    if (default_methods) methods = {"vertical_scan"};
    const int status = evaluateSensorTable(sensors, worlds, methods, sets, noise_name, noise, scans, seed,
                                           instructions, mount_rpy, cmdline, &markdown);
    if (status == 0 && !markdown_path.empty() && !writeTextFile(markdown_path, markdown)) return 1;
    return status;
  }
  if (holes || !phantom_dir.empty()) {
    const int status =
        holes ? evaluateHoleTable(default_worlds ? std::vector<std::string>{"potholes"} : worlds, methods, sets,
                                  noise, scans, seed, cmdline, &markdown)
              : evaluatePhantomHoles(phantom_dir, frame_range, sensor_height, methods, sets, mask_sources, cmdline,
                                     &markdown);
    if (status == 0 && !markdown_path.empty() && !writeTextFile(markdown_path, markdown)) return 1;
    return status;
  }
  if (!semantickitti_dir.empty()) {
    if (!std::isfinite(sensor_height) || sensor_height <= 0.f) {
      std::cerr << "ground_eval: --sensor-height must be positive\n";
      return 2;
    }
    const int real_status = evaluateSemanticKitti(semantickitti_dir, frame_range, sensor_height, methods, sets,
                                                  mask_sources, png_prefix, cmdline, &markdown);
    if (real_status == 0 && !markdown_path.empty() && !writeTextFile(markdown_path, markdown)) return 1;
    return real_status;
  }
  auto emit = [&markdown](const char* fmt, ...) {
    char buf[1024];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf, sizeof(buf), fmt, args);
    va_end(args);
    markdown += buf;
    std::fputs(buf, stdout);
  };
  emit("`%s`\n\n", cmdline.c_str());
  emit("| world | method | noise | scans | points | ground precision | ground recall | obstacle recall | median ms/scan |");
  if (at_ground_band > 0.0) emit(" not scored (at the ground) |");
  if (per_class) {
    for (int c = 0; c < sim::kNumSurfaceClasses; ++c)
      emit(" %s |", sim::className(static_cast<sim::SurfaceClass>(c)));
  }
  emit("\n|---|---|---|---|---|---|---|---|---|");
  if (at_ground_band > 0.0) emit("---|");
  if (per_class) for (int c = 0; c < sim::kNumSurfaceClasses; ++c) emit("---|");
  emit("\n");
  std::map<std::pair<std::string, std::string>, GroundAccuracy> results;  // (world, row name)
  auto row = [&](const std::string& w, const std::string& name, const GroundAccuracy& acc, double ms) {
    results[{w, name}] = acc;
    char obstacle[32] = "-";  // no obstacle in view (the vertical SICK on an open drive)
    if (acc.truth_obstacle > 0) std::snprintf(obstacle, sizeof(obstacle), "%.2f%%", 100.0 * acc.obstacleRecall());
    emit("| %s | %s | %s | %zu | %zu | %.2f%% | %.2f%% | %s | %.3f |", w.c_str(), name.c_str(),
         noise_name.c_str(), acc.scans, acc.points, 100.0 * acc.groundPrecision(),
         100.0 * acc.groundRecall(), obstacle, ms);
    if (at_ground_band > 0.0) emit(" %zu |", acc.not_scored);
    if (per_class) {
      for (int c = 0; c < sim::kNumSurfaceClasses; ++c) {
        if (acc.class_points[c]) emit(" %.1f%% of %zu |", 100.0 * GroundAccuracy::ratio(acc.class_correct[c], acc.class_points[c]), acc.class_points[c]);
        else emit(" - |");
      }
    }
    emit("\n");
    std::fflush(stdout);
  };
  int status = 0;
  // A world that could not be evaluated: said on stderr, the exit status 1, the other rows go on.
  auto evaluation_failed = [&status](const std::string& world, const std::string& error) {
    std::cerr << "ground_eval: " << world << ": " << error << "\n";
    status = 1;
  };
  std::vector<std::pair<std::string, MissBreakdown>> miss_rows;  // ("world | model", breakdown)
  for (const std::string& m : methods) {
    std::string error;
    std::unique_ptr<GroundModel> model = makeModel(m, sets, &error);
    if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
    TimedGroundModel timed(model.get());
    for (const std::string& w : worlds) {
      GroundAccuracy acc;
      timed.reset();
      MissBreakdown miss;
      if (!evaluateGroundModel(w, &timed, noise, scans, seed, &acc, &error, at_ground_band,
                               misses ? &miss : nullptr)) {
        evaluation_failed(w, error);
        continue;
      }
      const double ms = medianMs(timed.milliseconds());
      if (!png_prefix.empty()) writeErrorPng(png_prefix + "_" + w + ".png", w, model.get(), noise, scans, seed);
      row(w, model->name(), acc, ms);
      if (misses) miss_rows.emplace_back(w + " | " + model->name(), miss);
    }
  }
  if (misses) {
    emit("\nMissed obstacle returns by height to the ground next to them (within %.1f m) and by range:\n\n"
         "| world | method | missed | below 2 cm | 2-4 cm | 4-6 cm | 6-8 cm | 8 cm or more, or no ground near | "
         "missed within %.0f m | missed beyond |\n|---|---|---|---|---|---|---|---|---|---|\n",
         kAtGroundRadius, MissBreakdown::kNearRange);
    for (const auto& [name, b] : miss_rows) {
      emit("| %s | %zu |", name.c_str(), b.near_missed + b.far_missed);
      for (std::size_t h : b.missed_by_height) emit(" %zu |", h);
      emit(" %zu of %zu | %zu of %zu |\n", b.near_missed, b.near_obstacles, b.far_missed, b.far_obstacles);
    }
  }
  // The vertical SICK (thesis 3.3.4): the Hough fit against the 1-DOF vertical scan line.
  if (sick_scans > 0) {
    for (const std::string& w : worlds) {
      for (SickGroundFit fit : {SickGroundFit::kHough, SickGroundFit::kHoughThesis, SickGroundFit::kOneDof}) {
        GroundAccuracy acc;
        std::vector<double> ms;
        std::string error;
        if (!evaluateVerticalSick(w, fit, noise, sick_scans, seed, &acc, &ms, &error)) {
          evaluation_failed(w, error);
          continue;
        }
        row(w, sickGroundFitName(fit), acc, medianMs(ms));
      }
    }
  }
  // The thesis's findings, checked on the rows above (those whose rows were evaluated).
  // A baseline "fails" on a world where one of its accuracies (ground precision, ground recall,
  // obstacle recall) is at least kFailPoints below the vertical scan method's on the same scans,
  // and "holds up" where none is more than kHoldPoints below.
  constexpr double kFailPoints = 5.0, kHoldPoints = 1.0;
  auto find = [&](const std::string& w, const std::string& name) -> const GroundAccuracy* {
    auto it = results.find({w, name});
    return it == results.end() ? nullptr : &it->second;
  };
  // The largest deficit of `a` against `ref` in points, and the measure it is in.
  auto deficit = [](const GroundAccuracy& a, const GroundAccuracy& ref, const char** measure) {
    double worst = 100.0 * (ref.groundPrecision() - a.groundPrecision());
    *measure = "ground precision";
    const double recall = 100.0 * (ref.groundRecall() - a.groundRecall());
    if (recall > worst) { worst = recall; *measure = "ground recall"; }
    if (ref.truth_obstacle > 0) {
      const double obstacle = 100.0 * (ref.obstacleRecall() - a.obstacleRecall());
      if (obstacle > worst) { worst = obstacle; *measure = "obstacle recall"; }
    }
    return worst;
  };
  auto value = [](const GroundAccuracy& a, const std::string& measure) {
    if (measure == "ground precision") return 100.0 * a.groundPrecision();
    if (measure == "ground recall") return 100.0 * a.groundRecall();
    return 100.0 * a.obstacleRecall();
  };
  std::vector<std::string> findings;  // table rows
  int reproduced = 0, checked = 0;
  auto finding = [&](const char* fmt, ...) {
    char buf[512];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf, sizeof(buf), fmt, args);
    va_end(args);
    findings.emplace_back(buf);
  };
  for (const char* baseline : {"plane", "analog_signal"}) {
    for (const char* w : {"rural", "hillside", "flat"}) {
      const GroundAccuracy* a = find(w, baseline);
      const GroundAccuracy* ref = find(w, "vertical_scan");
      if (!a || !ref) continue;
      const bool expect_fail = std::string(w) != "flat";
      const char* measure = "";
      const double d = deficit(*a, *ref, &measure);
      const bool ok = expect_fail ? d >= kFailPoints : d <= kHoldPoints;
      ++checked;
      reproduced += ok;
      finding("| %s %s on %s%s | %s %.2f%% vs vertical_scan %.2f%% (%+.1f points) | %s |\n", baseline,
              expect_fail ? "fails" : "holds up", w, std::string(w) == "rural" ? " (crowned road)" : "",
              measure, value(*a, measure), value(*ref, measure), -d + 0.0, ok ? "yes" : "NO");
    }
  }
  {
    const GroundAccuracy* hough = find("hillside", sickGroundFitName(SickGroundFit::kHough));
    const GroundAccuracy* one_dof = find("hillside", sickGroundFitName(SickGroundFit::kOneDof));
    if (hough && one_dof) {
      const bool ok = hough->groundRecall() > one_dof->groundRecall() &&
                      hough->groundPrecision() >= one_dof->groundPrecision() - 0.001;
      ++checked;
      reproduced += ok;
      finding("| Hough fit beats the 1-DOF line on the hillside (vertical SICK) | ground recall %.2f%% vs "
              "%.2f%%, ground precision %.2f%% vs %.2f%% | %s |\n",
              100.0 * hough->groundRecall(), 100.0 * one_dof->groundRecall(), 100.0 * hough->groundPrecision(),
              100.0 * one_dof->groundPrecision(), ok ? "yes" : "NO");
    }
  }
  if (checked > 0) {
    emit("\nThesis findings (a baseline fails: an accuracy >= %.0f points below vertical_scan's; holds up: "
         "none more than %.0f point below), %d of %d reproduced:\n\n"
         "| finding | measured | reproduced |\n|---|---|---|\n",
         kFailPoints, kHoldPoints, reproduced, checked);
    for (const std::string& f : findings) emit("%s", f.c_str());
    if (reproduced < checked && status == 0) status = 3;
  }
  if (height_bound) {
    constexpr double kGroundKept = 0.99;  // the ground recall target
    emit("\nObstacle recall reachable by height alone (a test of each return's height against the exact "
         "ground surface within %.1f m, keeping %.0f%% of the ground returns in each range band):\n\n"
         "| world | obstacle returns | separable by height |",
         kAtGroundRadius, 100.0 * kGroundKept);
    for (int c = 0; c < sim::kNumSurfaceClasses; ++c) {
      if (sim::isObstacleClass(static_cast<sim::SurfaceClass>(c)))
        emit(" %s |", sim::className(static_cast<sim::SurfaceClass>(c)));
    }
    emit("\n|---|---|---|");
    for (int c = 0; c < sim::kNumSurfaceClasses; ++c)
      if (sim::isObstacleClass(static_cast<sim::SurfaceClass>(c))) emit("---|");
    emit("\n");
    for (const std::string& w : worlds) {
      HeightTestBound bound;
      std::string error;
      if (!heightTestBound(w, noise, scans, seed, kGroundKept, &bound, &error)) {
        evaluation_failed(w, error);
        continue;
      }
      emit("| %s | %zu | %.2f%% |", w.c_str(), bound.obstacle_returns, 100.0 * bound.recall());
      for (int c = 0; c < sim::kNumSurfaceClasses; ++c) {
        if (!sim::isObstacleClass(static_cast<sim::SurfaceClass>(c))) continue;
        if (bound.class_returns[c]) {
          emit(" %.1f%% of %zu |", 100.0 * GroundAccuracy::ratio(bound.class_separable[c], bound.class_returns[c]),
               bound.class_returns[c]);
        } else {
          emit(" - |");
        }
      }
      emit("\n");
      std::fflush(stdout);
    }
  }
  if (region_bound) {
    emit("\nPothole recall reachable by a region model of holes on the exact ground (seeds deeper below the "
         "nearest ground cell than %.2f%% of the ground returns in their range band; seeds less than %.2f m "
         "apart form a hole; a hole of %d or more seeds takes the returns in its seeds' convex hull or within "
         "%.2f m of a seed, unless more than %.3f m above the ground):\n\n"
         "| world | holes | ground recall | pothole returns | pothole recall | other obstacle returns in holes |\n"
         "|---|---|---|---|---|---|\n",
         100.0 * region_params.seed_ground_kept, region_params.link, region_params.min_seeds,
         region_params.margin, region_params.max_rise);
    const int pothole = static_cast<int>(sim::SurfaceClass::kPothole);
    for (const std::string& w : worlds) {
      RegionModelBound bound;
      std::string error;
      if (!regionModelBound(w, noise, scans, seed, region_params, &bound, &error)) {
        evaluation_failed(w, error);
        continue;
      }
      const std::size_t n = bound.class_returns[pothole];
      char recall[32] = "-";
      if (n) std::snprintf(recall, sizeof(recall), "%.2f%%", 100.0 * GroundAccuracy::ratio(bound.class_found[pothole], n));
      emit("| %s | %zu | %.2f%% | %zu | %s | %zu |\n", w.c_str(), bound.holes, 100.0 * bound.groundRecall(), n,
           recall, bound.obstacles_found - bound.class_found[pothole]);
      std::fflush(stdout);
    }
  }
  if (!markdown_path.empty() && !writeTextFile(markdown_path, markdown)) return 1;
  return status;
}
