#include "ladar_perception/eval/real_ground_eval.h"

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <set>

#include "ladar_perception/io/image.h"
#include "ladar_perception/io/kitti.h"

namespace ladar_perception {
namespace eval {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t mid = v.size() / 2;
  return v.size() % 2 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
}

void appendf(std::string* out, const char* fmt, ...) {
  char buf[1024];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof(buf), fmt, args);
  va_end(args);
  *out += buf;
}

}  // namespace

bool loadLabelledFrames(const std::vector<LabelledFrameFiles>& files,
                        std::vector<LabelledFrame>* frames, std::string* error) {
  frames->clear();
  frames->reserve(files.size());
  for (const LabelledFrameFiles& f : files) {
    LabelledFrame frame;
    frame.name = f.name;
    if (!readKittiBin(f.scan_path, &frame.cloud, error)) return false;
    if (!readSemanticClasses(f.label_path, frame.cloud.size(), &frame.classes, error)) return false;
    frames->push_back(std::move(frame));
  }
  return true;
}

void calledGround(const GroundClassification& result, std::vector<uint8_t>* called_ground) {
  called_ground->resize(result.size());
  for (std::size_t i = 0; i < result.size(); ++i) (*called_ground)[i] = result.labels[i] == kLabelGround;
}

void addFrameScore(const LabelledFrame& frame, const PointCloudView& view,
                   const std::vector<uint8_t>& called_ground, float sensor_height,
                   MethodScore* score) {
  for (int p = 0; p < 2; ++p) {
    RealGroundScore one;
    scoreGroundScan(view, frame.classes.data(), called_ground.data(), sensor_height,
                    p == 0 ? GroundProtocol::kA : GroundProtocol::kB, &one);
    score->protocol[p].add(one);
    score->frame_f1[p].push_back(one.f1());
  }
}

bool scoreGroundModel(GroundModel* model, const std::vector<LabelledFrame>& frames,
                      const SensorPose& pose, MethodScore* score, std::string* error,
                      std::vector<std::vector<uint8_t>>* per_frame_called) {
  score->method = model->name();
  GroundClassification result;
  std::vector<uint8_t> called;
  bool warm = false;
  for (const LabelledFrame& frame : frames) {
    PointCloudView view;
    if (!frame.cloud.view(&view, error)) {
      *error = frame.name + ": " + *error;
      return false;
    }
    if (!warm) {
      model->classify(view, pose, &result);
      warm = true;
    }
    const auto t0 = std::chrono::steady_clock::now();
    model->classify(view, pose, &result);
    const auto t1 = std::chrono::steady_clock::now();
    score->ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    calledGround(result, &called);
    addFrameScore(frame, view, called, pose.height(), score);
    if (per_frame_called) per_frame_called->push_back(called);
  }
  return true;
}

bool readGroundMask(const std::string& path, std::size_t points, std::vector<uint8_t>* mask,
                    std::string* error) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) {
    *error = "cannot open " + path;
    return false;
  }
  const std::streamsize bytes = in.tellg();
  if (bytes < 0 || static_cast<std::size_t>(bytes) != points) {
    *error = path + ": " + std::to_string(bytes < 0 ? 0 : bytes) + " bytes for a scan of " +
             std::to_string(points) + " returns (one byte per return)";
    return false;
  }
  in.seekg(0);
  mask->resize(points);
  if (!in.read(reinterpret_cast<char*>(mask->data()), bytes)) {
    *error = path + ": read failed";
    return false;
  }
  return true;
}

bool scoreMaskFiles(const std::string& name, const std::string& mask_dir,
                    const std::vector<LabelledFrame>& frames, float sensor_height,
                    MethodScore* score, std::string* error) {
  score->method = name;
  std::vector<uint8_t> called;
  for (const LabelledFrame& frame : frames) {
    if (!readGroundMask(mask_dir + "/" + frame.name + ".mask", frame.cloud.size(), &called, error)) return false;
    PointCloudView view;
    if (!frame.cloud.view(&view, error)) return false;
    addFrameScore(frame, view, called, sensor_height, score);
  }
  return true;
}

std::string realGroundSummaryTable(const std::vector<MethodScore>& methods) {
  std::string out =
      "| method | protocol | frames | precision | recall | F1 | obstacle recall | F1 min / median / max | median ms |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const MethodScore& m : methods) {
    for (int p = 0; p < 2; ++p) {
      const RealGroundScore& s = m.protocol[p];
      const std::vector<double>& f1 = m.frame_f1[p];
      char ms[32] = "-";
      if (!m.ms.empty()) std::snprintf(ms, sizeof(ms), "%.2f", median(m.ms));
      appendf(&out, "| %s | %s | %zu | %.2f | %.2f | %.2f | %.2f | %.2f / %.2f / %.2f | %s |\n",
              m.method.c_str(), p == 0 ? "A" : "B", s.scans, 100.0 * s.precision(),
              100.0 * s.recall(), 100.0 * s.f1(), 100.0 * s.obstacleRecall(),
              f1.empty() ? 0.0 : 100.0 * *std::min_element(f1.begin(), f1.end()),
              100.0 * median(f1), f1.empty() ? 0.0 : 100.0 * *std::max_element(f1.begin(), f1.end()), ms);
    }
  }
  return out;
}

std::string realGroundClassTable(const std::vector<MethodScore>& methods) {
  // Classes present in any method's protocol A score, ground classes first.
  std::set<uint16_t> ground, other;
  for (const MethodScore& m : methods) {
    for (const auto& [c, n] : m.a().classes) (semantic_kitti::isGroundClass(c) ? ground : other).insert(c);
  }
  std::string out = "| class | returns |";
  for (const MethodScore& m : methods) appendf(&out, " %s |", m.method.c_str());
  out += "\n|---|---|";
  for (std::size_t k = 0; k < methods.size(); ++k) out += "---|";
  out += "\n";
  for (const std::set<uint16_t>* group : {&ground, &other}) {
    for (uint16_t c : *group) {
      std::size_t points = 0;
      for (const MethodScore& m : methods) {
        auto it = m.a().classes.find(c);
        if (it != m.a().classes.end()) points = std::max(points, it->second.points);
      }
      appendf(&out, "| %s (%s) | %zu |", semantic_kitti::className(c).c_str(),
              group == &ground ? "ground: recall" : "non-ground: called ground", points);
      for (const MethodScore& m : methods) {
        auto it = m.a().classes.find(c);
        if (it == m.a().classes.end() || !it->second.points) {
          out += " - |";
          continue;
        }
        const double called = RealGroundScore::ratio(it->second.called_ground, it->second.points);
        if (group == &ground) appendf(&out, " %.2f%% |", 100.0 * called);
        else appendf(&out, " %.2f%% (%zu) |", 100.0 * called, it->second.called_ground);
      }
      out += "\n";
    }
  }
  return out;
}

std::string realGroundRangeTable(const std::vector<MethodScore>& methods) {
  std::string out = "| method | measure |";
  for (int b = 0; b < RangeBands::kCount; ++b) appendf(&out, " %s |", RangeBands::name(b).c_str());
  out += "\n|---|---|";
  for (int b = 0; b < RangeBands::kCount; ++b) out += "---|";
  out += "\n";
  for (const MethodScore& m : methods) {
    const auto& bands = m.a().bands;
    appendf(&out, "| %s | ground recall |", m.method.c_str());
    for (const auto& b : bands) {
      if (b.ground) appendf(&out, " %.2f%% of %zu |", 100.0 * RealGroundScore::ratio(b.ground_called_ground, b.ground), b.ground);
      else out += " - |";
    }
    appendf(&out, "\n| %s | obstacle recall |", m.method.c_str());
    for (const auto& b : bands) {
      if (b.non_ground) {
        appendf(&out, " %.2f%% of %zu |",
                100.0 * RealGroundScore::ratio(b.non_ground - b.non_ground_called_ground, b.non_ground), b.non_ground);
      } else {
        out += " - |";
      }
    }
    out += "\n";
  }
  return out;
}

bool writeOutcomePng(const std::string& path, const PointCloudView& view,
                     const std::vector<PointOutcome>& outcome, std::string* error) {
  const int size = 1000;
  const float ppm = size / 80.f;
  RgbImage img(size, size, 10, 10, 14);
  // Correct returns first, errors on top so that they stay visible.
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < view.size() && i < outcome.size(); ++i) {
      const PointOutcome o = outcome[i];
      const bool wrong = o == PointOutcome::kMissedGround || o == PointOutcome::kFalseGround;
      if (wrong != (pass == 1)) continue;
      const Eigen::Vector3f p = view.xyz(i);
      if (!p.allFinite()) continue;
      uint8_t rgb[3] = {90, 90, 90};
      switch (o) {
        case PointOutcome::kGround: rgb[0] = 20; rgb[1] = 110; rgb[2] = 35; break;
        case PointOutcome::kObstacle: rgb[0] = 130; rgb[1] = 25; rgb[2] = 25; break;
        case PointOutcome::kMissedGround: rgb[0] = 255; rgb[1] = 230; rgb[2] = 0; break;
        case PointOutcome::kFalseGround: rgb[0] = 255; rgb[1] = 0; rgb[2] = 255; break;
        case PointOutcome::kUnscored: break;
      }
      img.set(static_cast<int>(size / 2 - p.y() * ppm), static_cast<int>(size / 2 - p.x() * ppm),
              rgb[0], rgb[1], rgb[2]);
    }
  }
  return writePng(path, img, error);
}

bool writeRealErrorPng(const std::string& path, const LabelledFrame& frame,
                       const std::vector<uint8_t>& called_ground, float sensor_height,
                       std::string* error) {
  PointCloudView view;
  if (!frame.cloud.view(&view, error)) return false;
  std::vector<PointOutcome> outcome(view.size(), PointOutcome::kUnscored);
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    if (!p.allFinite()) continue;
    const TruthRole role = truthRole(frame.classes[i], p.z(), sensor_height, GroundProtocol::kA);
    if (role != TruthRole::kGround && role != TruthRole::kNonGround) continue;
    const bool truth_ground = role == TruthRole::kGround;
    const bool ground = called_ground[i] != 0;
    outcome[i] = truth_ground ? (ground ? PointOutcome::kGround : PointOutcome::kMissedGround)
                              : (ground ? PointOutcome::kFalseGround : PointOutcome::kObstacle);
  }
  return writeOutcomePng(path, view, outcome, error);
}

}  // namespace eval
}  // namespace ladar_perception
