// A ground model's accuracy on one of the simulator's worlds, as the baseline tests measure it:
// 3 revolutions, seed 1, datasheet noise (what ground_eval tabulates, shorter).
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "ladar_perception/eval/ground_evaluation.h"
#include "ladar_perception/ground/ground_model.h"

namespace ladar_perception {
namespace testing_support {

inline GroundAccuracy evaluateWorld(const std::string& world, GroundModel* model) {
  GroundAccuracy acc;
  std::string error;
  EXPECT_TRUE(evaluateGroundModel(world, model, sim::NoiseProfile::kDatasheet, 3, 1, &acc, &error))
      << error;
  return acc;
}

// Fraction of the returns of one surface class labelled right.
inline double classRecall(const GroundAccuracy& acc, sim::SurfaceClass c) {
  const int k = static_cast<int>(c);
  return GroundAccuracy::ratio(acc.class_correct[k], acc.class_points[k]);
}

}  // namespace testing_support
}  // namespace ladar_perception
