// Ground models run over the frames of a SemanticKITTI-layout folder and scored under both
// protocols of semantic_kitti.h; the tables ground_eval --semantickitti prints.
#pragma once

#include <string>
#include <vector>

#include "ladar_perception/eval/semantic_kitti.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"

namespace ladar_perception {
namespace eval {

// A frame in memory: the scan and its semantic classes.
struct LabelledFrame {
  std::string name;  // "000000"
  PackedCloud cloud;
  std::vector<uint16_t> classes;
};

// Reads every frame; false with the first reason when one cannot be read.
bool loadLabelledFrames(const std::vector<LabelledFrameFiles>& files,
                        std::vector<LabelledFrame>* frames, std::string* error);

// One method over the frames: both protocols summed over the frames, the F1 of each frame, and
// the core time of each frame's classify call (empty for a method read from mask files).
struct MethodScore {
  std::string method;
  RealGroundScore protocol[2];            // [0] A, [1] B
  std::vector<double> frame_f1[2];        // per frame, in frame order
  std::vector<double> ms;                 // per frame

  const RealGroundScore& a() const { return protocol[0]; }
  const RealGroundScore& b() const { return protocol[1]; }
};

// called_ground[i] = 1 where the label is ground (unknown and obstacle are not ground).
void calledGround(const GroundClassification& result, std::vector<uint8_t>* called_ground);

// Scores one frame's call for both protocols into *score (one F1 per protocol appended).
void addFrameScore(const LabelledFrame& frame, const PointCloudView& view,
                   const std::vector<uint8_t>& called_ground, float sensor_height,
                   MethodScore* score);

// Runs `model` on every frame (one untimed warm-up call on the first) and scores it.
// per_frame_called, when given, receives each frame's called-ground mask.
bool scoreGroundModel(GroundModel* model, const std::vector<LabelledFrame>& frames,
                      const SensorPose& pose, MethodScore* score, std::string* error,
                      std::vector<std::vector<uint8_t>>* per_frame_called = nullptr);

// Reads a ground mask file (one byte per return, 1 = ground, the format of ground_segment
// --mask) of a scan of `points` returns; false with a reason when it is missing or its size
// does not match.
bool readGroundMask(const std::string& path, std::size_t points, std::vector<uint8_t>* mask,
                    std::string* error);

// Scores masks written by another program (one byte per return, 1 = ground, the format of
// ground_segment --mask): MASK_DIR/NNNNNN.mask for each frame. False with a reason when a mask
// is missing or its size does not match the frame.
bool scoreMaskFiles(const std::string& name, const std::string& mask_dir,
                    const std::vector<LabelledFrame>& frames, float sensor_height,
                    MethodScore* score, std::string* error);

// Markdown tables: the summary (one row per method and protocol: P / R / F1 / obstacle
// recall, F1 min / median / max over frames, median ms), then, when asked, per-class and
// per-range-band tables for protocol A.
std::string realGroundSummaryTable(const std::vector<MethodScore>& methods);
std::string realGroundClassTable(const std::vector<MethodScore>& methods);
std::string realGroundRangeTable(const std::vector<MethodScore>& methods);

// What a return's label is against the truth, for the error pictures.
enum class PointOutcome : uint8_t { kUnscored, kGround, kObstacle, kMissedGround, kFalseGround };

// Top-down picture of a scan's outcomes, 80 m wide, 1000 px, x forward up: ground called ground
// dark green, an obstacle called obstacle dark red, missed ground (a false obstacle) yellow,
// false ground (a missed obstacle) magenta, not scored grey; the errors drawn over the rest.
// The one picture of ground_eval's real and simulated modes.
bool writeOutcomePng(const std::string& path, const PointCloudView& view,
                     const std::vector<PointOutcome>& outcome, std::string* error);

// The picture of one labelled frame's outcomes under protocol A.
bool writeRealErrorPng(const std::string& path, const LabelledFrame& frame,
                       const std::vector<uint8_t>& called_ground, float sensor_height,
                       std::string* error);

}  // namespace eval
}  // namespace ladar_perception
