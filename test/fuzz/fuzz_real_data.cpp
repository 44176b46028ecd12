// libFuzzer target: the readers of real labelled data and their scoring: a KITTI .bin scan
// (readKittiBin), a SemanticKITTI .label file (readSemanticClasses), a ground mask
// (readGroundMask), both protocols' scoring of one scan (scoreGroundScan), the frame range of
// ground_eval --frames (parseFrameRange), and a SemanticKITTI-layout folder
// (listLabelledFrames, loadLabelledFrames).
// Input: one byte selects the reader, two bytes give the length of the scan's bytes; the scan's
// bytes follow, the rest is the label (or mask) file.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "ladar_perception/eval/real_ground_eval.h"
#include "ladar_perception/eval/semantic_kitti.h"
#include "ladar_perception/io/kitti.h"
#include "fuzz_reader.h"

#ifndef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

namespace fuzz_real_data {
using namespace ladar_perception;

std::string tempDir() { return "/tmp/ladar_fuzz_real_" + std::to_string(getpid()); }
void writeFile(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

// Scores the scan with the mask as the model's call under both protocols, and checks that every
// scored return lands in exactly one count.
void scoreBothProtocols(const PackedCloud& cloud, const std::vector<uint16_t>& classes,
                        const std::vector<uint8_t>& called, float sensor_height) {
  PointCloudView view;
  std::string error;
  if (!cloud.view(&view, &error)) {
    if (error.empty()) __builtin_trap();
    return;
  }
  if (view.size() != classes.size()) return;
  for (const eval::GroundProtocol protocol : {eval::GroundProtocol::kA, eval::GroundProtocol::kB}) {
    eval::RealGroundScore score;
    eval::scoreGroundScan(view, classes.data(), called.data(), sensor_height, protocol, &score);
    const std::size_t counted = score.true_ground + score.false_ground + score.missed_ground +
                                score.true_obstacle + score.dropped_ground;
    if (counted > view.size() || score.scans != 1) __builtin_trap();
    std::size_t by_class = 0;
    for (const auto& c : score.classes) by_class += c.second.points;
    if (by_class + score.dropped_ground != counted) __builtin_trap();
    const double f1 = score.f1();
    if (!(f1 >= 0.0 && f1 <= 1.0)) __builtin_trap();
  }
}

}  // namespace fuzz_real_data

extern "C" int LADAR_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  using namespace ladar_perception;
  using namespace fuzz_real_data;
  fuzz::Reader in{data, size};
  const uint8_t kind = in.get<uint8_t>() % 3;
  const float sensor_height = static_cast<float>(in.get<uint8_t>()) / 50.f;
  std::size_t scan_bytes = in.get<uint16_t>();
  if (scan_bytes > in.n) scan_bytes = in.n;
  const uint8_t* scan = in.p;
  const uint8_t* rest = in.p + scan_bytes;
  const std::size_t rest_bytes = in.n - scan_bytes;
  std::string error;

  const std::string dir = tempDir();
  mkdir(dir.c_str(), 0700);
  switch (kind) {
    case 0: {  // a scan, its labels and a mask of the same bytes, then the scores
      const std::string bin = dir + "/scan.bin", label = dir + "/scan.label";
      writeFile(bin, scan, scan_bytes);
      writeFile(label, rest, rest_bytes);
      PackedCloud cloud;
      if (!readKittiBin(bin, &cloud, &error)) {
        if (error.empty()) __builtin_trap();
        break;
      }
      const std::size_t points = cloud.layout.width * cloud.layout.height;
      std::vector<uint16_t> classes;
      if (!eval::readSemanticClasses(label, points, &classes, &error)) {
        if (error.empty()) __builtin_trap();
        break;
      }
      if (classes.size() != points) __builtin_trap();
      std::vector<uint8_t> mask;
      const std::string mask_path = dir + "/scan.mask";
      writeFile(mask_path, rest, rest_bytes < points ? rest_bytes : points);
      if (!eval::readGroundMask(mask_path, points, &mask, &error)) {
        if (error.empty()) __builtin_trap();
        mask.assign(points, 0);
        for (std::size_t i = 0; i < points; ++i) mask[i] = classes[i] & 1;
      }
      if (mask.size() != points) __builtin_trap();
      scoreBothProtocols(cloud, classes, mask, sensor_height);
      std::remove(mask_path.c_str());
      std::remove(bin.c_str());
      std::remove(label.c_str());
      break;
    }
    case 1: {  // the frame range text
      const std::string text(reinterpret_cast<const char*>(scan), scan_bytes);
      long first = 0, last = 0;
      // An accepted range is never empty: "a:b" with a > b is refused.
      if (eval::parseFrameRange(text, &first, &last) && (first > last || first < 0)) {
        __builtin_trap();
      }
      break;
    }
    case 2: {  // a SemanticKITTI-layout folder with one frame
      const std::string velodyne = dir + "/velodyne", labels = dir + "/labels";
      mkdir(velodyne.c_str(), 0700);
      mkdir(labels.c_str(), 0700);
      writeFile(velodyne + "/000007.bin", scan, scan_bytes);
      writeFile(labels + "/000007.label", rest, rest_bytes);
      std::vector<eval::LabelledFrameFiles> files;
      if (!eval::listLabelledFrames(dir, 0, 10, &files, &error)) {
        if (error.empty()) __builtin_trap();
      } else {
        if (files.size() != 1) __builtin_trap();
        std::vector<eval::LabelledFrame> frames;
        if (!eval::loadLabelledFrames(files, &frames, &error)) {
          if (error.empty()) __builtin_trap();
        } else if (frames.size() != 1 ||
                   frames[0].classes.size() !=
                       std::size_t(frames[0].cloud.layout.width) * frames[0].cloud.layout.height) {
          __builtin_trap();
        }
      }
      std::remove((velodyne + "/000007.bin").c_str());
      std::remove((labels + "/000007.label").c_str());
      rmdir(velodyne.c_str());
      rmdir(labels.c_str());
      break;
    }
  }
  rmdir(dir.c_str());
  return 0;
}
