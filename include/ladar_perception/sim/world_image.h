// A top-down picture of a world for people: class colours shaded by height, with a trajectory
// and the vehicle poses drawn on it.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "ladar_perception/io/image.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

struct TopDownOptions {
  int max_pixels = 2000;     // the longer side of the image at most this many pixels
  bool hillshade = true;     // shade by the height gradient (light from the north-west)
};

// North is up. `path` is drawn as a white line with a green start and red end marker; each of
// `poses` as a small yellow arrow (position and heading).
RgbImage renderTopDown(const World& world, const std::vector<Eigen::Vector2d>& path,
                       const std::vector<Eigen::Isometry3d>& poses,
                       const TopDownOptions& options = {});

}  // namespace sim
}  // namespace ladar_perception
