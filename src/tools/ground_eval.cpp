// ground_eval: accuracy of the ground models on the simulator's worlds with ground truth,
// printed as a Markdown table (with the command line that produced it).
//
//   ground_eval [--worlds flat,urban,hillside,potholes] [--method NAME[,NAME]]
//               [--noise datasheet|table4.1|none] [--scans N] [--seed S] [--classes]
//               [--sick-scans N] [--markdown OUT]
// By default every ground model (HDL-64E revolutions) on every standard world, then the vertical
// SICK's ground fits (the Hough fit of 3.3.4 against the 1-DOF vertical scan line), with the
// median core time per scan; --markdown also writes the table to OUT (for the README).
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "ladar_perception/ground/ground_evaluation.h"
#include "ladar_perception/ground/hough_evaluation.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/image.h"

using namespace ladar_perception;

namespace {
std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}
}  // namespace

// Top-down picture of the middle scan of the evaluation: correct ground dark green, correct
// obstacle dark red, missed obstacle magenta, false obstacle yellow, unknown grey; 80 m wide.
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
  const int size = 1000;
  const float ppm = size / 80.f;
  RgbImage img(size, size, 10, 10, 14);
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < res.size(); ++i) {
      const auto c = static_cast<sim::SurfaceClass>(scan.truth[i]);
      const bool g = sim::isGroundClass(c);
      const uint8_t l = res.labels[i];
      const bool wrong = (g && l != kLabelGround) || (!g && l != kLabelObstacle);
      if (wrong != (pass == 1)) continue;
      uint8_t rgb[3] = {110, 110, 110};
      if (l == kLabelUnknown) {
      } else if (!wrong) {
        rgb[0] = g ? 20 : 120; rgb[1] = g ? 90 : 20; rgb[2] = g ? 30 : 20;
      } else if (g) {
        rgb[0] = 255; rgb[1] = 230; rgb[2] = 0;
      } else {
        rgb[0] = 255; rgb[1] = 0; rgb[2] = 255;
      }
      const Eigen::Vector3f p = view.xyz(i);
      img.set(static_cast<int>(size / 2 - p.y() * ppm), static_cast<int>(size / 2 - p.x() * ppm),
              rgb[0], rgb[1], rgb[2]);
    }
  }
  writePng(path, img, &error);
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
  std::vector<std::string> sets;
  std::string png_prefix;  // PREFIX_<world>.png: the middle scan's errors, top-down  // key=value overrides of the vertical scan params
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
    else if (a == "--noise") noise_name = next();
    else if (a == "--scans") scans = std::atoi(next().c_str());
    else if (a == "--seed") seed = static_cast<uint32_t>(std::strtoul(next().c_str(), nullptr, 10));
    else if (a == "--classes") per_class = true;
    else if (a == "--set") sets.push_back(next());
    else if (a == "--png-errors") png_prefix = next();
    else if (a == "--sick-scans") sick_scans = std::atoi(next().c_str());
    else if (a == "--markdown") markdown_path = next();
    else {
      std::cerr << "usage: ground_eval [--worlds a,b] [--method m1,m2] "
                   "[--noise datasheet|table4.1|none] [--scans N] [--seed S] [--classes] [--set key=value]... "
                   "[--sick-scans N] [--markdown OUT]\n";
      return a == "-h" || a == "--help" ? 0 : 2;
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
  if (per_class) {
    for (int c = 0; c < sim::kNumSurfaceClasses; ++c)
      emit(" %s |", sim::className(static_cast<sim::SurfaceClass>(c)));
  }
  emit("\n|---|---|---|---|---|---|---|---|---|");
  if (per_class) for (int c = 0; c < sim::kNumSurfaceClasses; ++c) emit("---|");
  emit("\n");
  auto row = [&](const std::string& w, const std::string& name, const GroundAccuracy& acc, double ms) {
    char obstacle[32] = "-";  // no obstacle in view (the vertical SICK on an open drive)
    if (acc.truth_obstacle > 0) std::snprintf(obstacle, sizeof(obstacle), "%.2f%%", 100.0 * acc.obstacleRecall());
    emit("| %s | %s | %s | %zu | %zu | %.2f%% | %.2f%% | %s | %.3f |", w.c_str(), name.c_str(),
         noise_name.c_str(), acc.scans, acc.points, 100.0 * acc.groundPrecision(),
         100.0 * acc.groundRecall(), obstacle, ms);
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
  for (const std::string& m : methods) {
    std::string error;
    std::unique_ptr<GroundModel> model = makeGroundModel(m, &error);
    if (!model) { std::cerr << "ground_eval: " << error << "\n"; return 2; }
    if (!sets.empty()) {
      auto* vs = dynamic_cast<VerticalScanGround*>(model.get());
      if (!vs) { std::cerr << "ground_eval: --set applies to vertical scan models only\n"; return 2; }
      VerticalScanParams params = vs->params();
      for (const std::string& kv : sets) {
        const std::size_t eq = kv.find('=');
        if (eq == std::string::npos ||
            !setVerticalScanParam(&params, kv.substr(0, eq), std::atof(kv.c_str() + eq + 1), &error)) {
          std::cerr << "ground_eval: bad --set " << kv << " " << error << "\n";
          return 2;
        }
      }
      vs->setParams(params);
    }
    TimedGroundModel timed(model.get());
    for (const std::string& w : worlds) {
      GroundAccuracy acc;
      timed.reset();
      if (!evaluateGroundModel(w, &timed, noise, scans, seed, &acc, &error)) {
        std::cerr << "ground_eval: " << w << ": " << error << "\n";
        status = 1;
        continue;
      }
      const double ms = medianMs(timed.milliseconds());
      if (!png_prefix.empty()) writeErrorPng(png_prefix + "_" + w + ".png", w, model.get(), noise, scans, seed);
      row(w, model->name(), acc, ms);
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
          std::cerr << "ground_eval: " << w << ": " << error << "\n";
          status = 1;
          continue;
        }
        row(w, sickGroundFitName(fit), acc, medianMs(ms));
      }
    }
  }
  if (!markdown_path.empty()) {
    const std::string tmp = markdown_path + ".tmp";
    std::ofstream f(tmp);
    f << markdown;
    f.close();
    if (!f || std::rename(tmp.c_str(), markdown_path.c_str()) != 0) {
      std::cerr << "ground_eval: cannot write " << markdown_path << "\n";
      return 1;
    }
  }
  return status;
}
