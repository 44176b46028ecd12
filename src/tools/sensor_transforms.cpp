// sensor_transforms: prints one sensor's mount from a sensor rig YAML (config/sensors.yaml) as a
// TransformStamped-shaped YAML dict (header.frame_id, child_frame_id, transform.translation,
// transform.rotation), the form tf2_ros's static_transform_publisher reads from a single
// parameter name. The launch files set that parameter with
//   <param name="..." type="yaml" command="$(find ladar_perception)/scripts/sensor_transforms_param SENSORS NAME"/>
// so config/sensors.yaml stays the one source of the numbers (the simulator reads the same file
// through the same parser, sim::loadSensorRig).
#include <cstdio>
#include <cstring>
#include <string>

#include <Eigen/Geometry>

#include "ladar_perception/sim/sensor_rig.h"

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: sensor_transforms SENSORS_YAML NAME   (NAME: a sensor's name or frame_id)\n"
               "       sensor_transforms SENSORS_YAML --list (the sensors' names)\n"
               "Prints the sensor's base frame -> sensor frame mount as a TransformStamped YAML\n"
               "dict for static_transform_publisher's single-parameter form.\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ladar_perception::sim;
  if (argc != 3 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage();
    return argc == 2 && argv[1][0] == '-' && argv[1][1] == 'h' ? 0 : 2;
  }
  SensorRig rig;
  std::string error;
  if (!loadSensorRig(argv[1], &rig, &error)) {
    std::fprintf(stderr, "sensor_transforms: %s: %s\n", argv[1], error.c_str());
    return 1;
  }
  const std::string name = argv[2];
  if (name == "--list") {
    for (const SensorMount& s : rig.sensors) std::printf("%s\n", s.name.c_str());
    return 0;
  }
  for (const SensorMount& s : rig.sensors) {
    if (s.name != name && s.frame_id != name) continue;
    const Eigen::Vector3d t = s.base_to_sensor.translation();
    const Eigen::Quaterniond q(s.base_to_sensor.linear());
    // %.17g round-trips every double; always with a '.' or exponent so XmlRpc reads a double.
    const auto num = [](double v) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.17g", v);
      std::string out = buf;
      if (out.find_first_of(".eEn") == std::string::npos) out += ".0";
      return out;
    };
    std::printf("header: {frame_id: \"%s\"}\n", rig.base_frame.c_str());
    std::printf("child_frame_id: \"%s\"\n", s.frame_id.c_str());
    std::printf("transform:\n");
    std::printf("  translation: {x: %s, y: %s, z: %s}\n", num(t.x()).c_str(), num(t.y()).c_str(),
                num(t.z()).c_str());
    std::printf("  rotation: {x: %s, y: %s, z: %s, w: %s}\n", num(q.x()).c_str(),
                num(q.y()).c_str(), num(q.z()).c_str(), num(q.w()).c_str());
    return 0;
  }
  std::fprintf(stderr, "sensor_transforms: no sensor named '%s' in %s (sensors:", name.c_str(),
               argv[1]);
  for (const SensorMount& s : rig.sensors) std::fprintf(stderr, " %s", s.name.c_str());
  std::fprintf(stderr, ")\n");
  return 1;
}
