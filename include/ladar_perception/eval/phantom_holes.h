// Phantom holes: negative obstacles a ground model reports on real road that has none. The
// obstacle returns lying below the local ground are clustered; a cluster next to no object
// (no obstacle return standing above the ground beside it) is a hole the model invents, the
// thing a planner would brake or swerve for. Counted per scan and per 100 m of road.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"

namespace ladar_perception {
namespace eval {

struct PhantomHoleParams {
  float max_range = 30.f;       // [m] horizontal range of the returns looked at
  float ground_cell = 1.f;      // [m] local ground: the lowest median height of the ground
                                //     returns in the 3 x 3 cells of this size around a return
  float min_depth = 0.05f;      // [m] an obstacle return this far below the local ground ...
  float max_depth = 1.f;        // [m] ... but not farther (deeper returns are multipath and
                                //     reflection artefacts, SemanticKITTI's "outlier")
  float cluster_cell = 0.25f;   // [m] ... clustered with those in touching cells of this size
  int min_returns = 2;          // a cluster of at least this many returns is a hole
  float object_radius = 0.5f;   // [m] a cluster with an obstacle return within this ...
  float object_height = 0.2f;   // [m] ... and this far above the local ground belongs to an
                                //     object (the foot of a car or a wall), not a hole
  // Road length one scan accounts for: the road within max_range ahead and behind.
  float roadPerScan() const { return 2.f * max_range; }
};

struct PhantomHole {
  Eigen::Vector2f centre;  // sensor frame, horizontal [m]
  int returns = 0;
  float depth = 0.f;       // deepest return below the local ground [m]
};

// The phantom holes of one scan (a level sensor frame, z up). result labels the returns of
// view; the local ground is the model's own ground returns. Returns the number of clusters of
// below-ground obstacle returns found (object or not); *phantoms receives those next to no
// object.
std::size_t findPhantomHoles(const PointCloudView& view, const GroundClassification& result,
                             const PhantomHoleParams& params,
                             std::vector<PhantomHole>* phantoms);

}  // namespace eval
}  // namespace ladar_perception
