// Exact ray casting onto the World's height field of flat-topped cell columns: a grid
// traversal that visits every cell the ray's x-y projection crosses (no fixed-step marching),
// skipping whole blocks of the max-height pyramid the ray passes above.
#pragma once

#include <Eigen/Core>

#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

struct RayHit {
  double range = 0.0;                       // metres along the unit direction
  SurfaceClass surface = SurfaceClass::kNone;
  // Outward normal of the face hit: +z for a cell top, +-x or +-y for a side face.
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
};

// Casts a ray from `origin` along the unit vector `direction` (world frame) up to max_range.
// True with the first surface hit, false when the ray leaves the world or max_range first, or
// starts inside a cell column. Side faces of steps between ground cells of at least
// SurfaceModel::curb_min_step are kCurb; the walls of a pothole are kPothole; other faces
// carry their cell's class. The world must be finalize()d.
bool castRay(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
             double max_range, RayHit* hit);

// The same, starting the pyramid traversal at `start_level` instead of the top (any level gives
// the same result; a good one saves descents). startLevelFor() picks one for rays from a
// sensor origin: the largest block around it whose highest cell is below the origin (-1: top).
bool castRay(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
             double max_range, int start_level, RayHit* hit);
int startLevelFor(const World& world, const Eigen::Vector3d& origin);

// Reference implementation for tests: visits every cell along the ray (no pyramid). Same
// results as castRay, slower.
bool castRayBruteForce(const World& world, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double max_range, RayHit* hit);

}  // namespace sim
}  // namespace ladar_perception
