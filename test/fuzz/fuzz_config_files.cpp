// libFuzzer target: the file loaders of the simulator and the calibration: height/class images
// for sim::World::fromImage (PGM and PNG through io::readImage), the sensor rig YAML
// (loadSensorRig) and the trajectory YAML (loadTrajectoryYaml). The first byte selects the
// loader, the rest is the file's content.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "ladar_perception/io/image.h"
#include "ladar_perception/sim/sensor_rig.h"
#include "ladar_perception/sim/trajectory.h"
#include "ladar_perception/sim/world.h"

#ifndef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

namespace fuzz_config_files {
using namespace ladar_perception;

std::string tempPath(const char* ext) {
  return "/tmp/ladar_fuzz_config_" + std::to_string(getpid()) + ext;
}
void writeFile(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}
}  // namespace fuzz_config_files

extern "C" int LADAR_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  using namespace ladar_perception;
  using namespace ladar_perception::sim;
  using namespace fuzz_config_files;
  if (size < 1) return 0;
  const uint8_t kind = data[0] % 5;
  ++data;
  --size;
  std::string error;
  switch (kind) {
    case 0:    // height image (PGM or PNG: readImage decides by content)
    case 1: {  // height image plus the same bytes as a class image
      const std::string path = tempPath(kind == 0 ? ".pgm" : ".png");
      writeFile(path, data, size);
      ImageWorldOptions options;
      options.metres_per_pixel = 0.5;
      World world;
      const bool ok = World::fromImage(path, kind == 1 ? path : std::string(), options, &world,
                                       &error);
      if (!ok && error.empty()) __builtin_trap();
      if (ok) (void)world.height(0.0, 0.0);
      std::remove(path.c_str());
      break;
    }
    case 2: {
      const std::string path = tempPath(".yaml");
      writeFile(path, data, size);
      SensorRig rig;
      if (!loadSensorRig(path, &rig, &error) && error.empty()) __builtin_trap();
      std::remove(path.c_str());
      break;
    }
    case 3: {
      const std::string path = tempPath(".yaml");
      writeFile(path, data, size);
      Trajectory trajectory;
      const bool ok = loadTrajectoryYaml(path, &trajectory, &error);
      if (!ok && error.empty()) __builtin_trap();
      if (ok) (void)trajectory.length();
      std::remove(path.c_str());
      break;
    }
    case 4: {  // the raw image reader alone (no world size limits in the way)
      const std::string path = tempPath(".img");
      writeFile(path, data, size);
      GrayImage image;
      if (!readImage(path, &image, &error) && error.empty()) __builtin_trap();
      std::remove(path.c_str());
      break;
    }
  }
  return 0;
}
