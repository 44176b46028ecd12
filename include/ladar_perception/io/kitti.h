// KITTI Velodyne binary scans: float32 x, y, z, intensity per return, little endian.
#pragma once

#include <string>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace ladar_perception {

// Reads a KITTI .bin into a packed x,y,z,intensity cloud. False with a reason on error.
bool readKittiBin(const std::string& path, PackedCloud* cloud, std::string* error);

}  // namespace ladar_perception
