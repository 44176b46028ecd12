// Laser elevation tables of multi-beam ladars. The one HDL-64E table of the package: the
// simulator's sensor model and the vertical scan row assignment both use it.
#pragma once

#include <vector>

namespace ladar_perception {

// Velodyne HDL-64E laser elevations [deg], 64 values sorted ascending, so index == `ring` as the
// ROS velodyne driver numbers its lasers (ring 0 = lowest beam). Nominal datasheet geometry:
// vertical field of view +2.0 deg to -24.8 deg; the upper block (32 lasers) spaced 1/3 deg from
// +2.0 deg down, the lower block (32 lasers) spaced evenly from -8.83 deg down to -24.8 deg
// (about 0.52 deg). Real units deviate by a few tenths of a degree per laser (KITTI's 000000.bin
// shows per-laser medians from +2.5 to -23.5 deg); consumers must tolerate that.
const std::vector<float>& hdl64eElevationsDeg();

}  // namespace ladar_perception
