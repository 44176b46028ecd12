#include "ladar_perception/io/kitti.h"

#include <fstream>

namespace ladar_perception {

bool readKittiBin(const std::string& path, PackedCloud* cloud, std::string* error) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) {
    if (error) *error = "cannot open " + path;
    return false;
  }
  const std::streamsize bytes = in.tellg();
  if (bytes < 0 || bytes % 16 != 0) {
    if (error) *error = path + ": size is not a multiple of 16 bytes (float32 x,y,z,intensity)";
    return false;
  }
  in.seekg(0);
  const uint32_t n = static_cast<uint32_t>(bytes / 16);
  cloud->layout = xyziLayout(n);
  cloud->data.resize(static_cast<std::size_t>(bytes));
  if (!in.read(reinterpret_cast<char*>(cloud->data.data()), bytes)) {
    if (error) *error = path + ": read failed";
    return false;
  }
  return true;
}

}  // namespace ladar_perception
