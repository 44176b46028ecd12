// ground_segment: offline ground extraction on a KITTI .bin or a .pcd file (interfaces.md).
//
//   ground_segment SCAN [--sensor-height M] [--sensor-model NAME | --laser-elevations-deg A,B,..]
//                       [--mount-rpy R,P] [--sensor-origin X,Y,Z] [--estimate-mount]
//                       [--method NAME] [--mask OUT] [--repeat N]
//                       [--png OUT] [--color label|p] [--png-range M] [--png-size PX]
//
// A thin main over the core: read the file, describe it as a CloudLayout, one classify call.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include "ladar_perception/cloud/lidar_models.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/plane_fit.h"
#include "ladar_perception/io/image.h"
#include "ladar_perception/io/kitti.h"

using namespace ladar_perception;

namespace {

void usage() {
  std::cerr
      << "usage: ground_segment SCAN(.bin|.pcd) [options]\n"
         "  --sensor-height M   sensor height above the ground [m] (default 1.73, KITTI)\n"
         "  --sensor-model NAME the lidar (default hdl64e): " + lidarModelNames() + "\n"
         "  --laser-elevations-deg A,B,...  a sensor's own beam elevations (instead of --sensor-model)\n"
         "  --laser-elevations-from-rings  measure the beam elevations from a cloud with rings\n"
         "                      (median per ring), print them and use them\n"
         "  --mount-rpy R,P     the sensor's roll and pitch on its mount [deg] (default 0,0)\n"
         "  --sensor-origin X,Y,Z  the cloud is in a vehicle frame at the ground: the sensor sits at\n"
         "                      X,Y,Z in it (Z its height; replaces --sensor-height)\n"
         "  --estimate-mount    height, roll and pitch from the scan's ground plane (Algorithm 1,\n"
         "                      seeded with --sensor-height), printed and used\n"
         "  --method NAME       ground model (default: the first of --list-methods)\n"
         "  --list-methods      print the ground model names and exit\n"
         "  --mask OUT          one byte per input point: 1 = ground, 0 = not ground\n"
         "  --repeat N          run the core call N times, print median_ms=X min_ms=Y\n"
         "  --png OUT           top-down view of the scan coloured by --color\n"
         "  --color label|p     label (ground green, obstacle red, unknown grey) or P(obstacle)\n"
         "  --png-range M       half width of the top-down view [m] (default 40)\n"
         "  --png-size PX       image width and height [px] (default 1000)\n";
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool readPcd(const std::string& path, PackedCloud* cloud, std::string* error) {
  pcl::PCLPointCloud2 msg;
  if (pcl::io::loadPCDFile(path, msg) < 0) {
    *error = "cannot read PCD file " + path;
    return false;
  }
  cloud->layout = CloudLayout();
  for (const pcl::PCLPointField& f : msg.fields) {
    FieldDesc d;
    d.name = f.name;
    d.offset = f.offset;
    d.datatype = f.datatype;
    d.count = f.count;
    cloud->layout.fields.push_back(d);
  }
  cloud->layout.width = msg.width;
  cloud->layout.height = msg.height;
  cloud->layout.point_step = msg.point_step;
  cloud->layout.row_step = msg.row_step;
  cloud->layout.is_bigendian = msg.is_bigendian != 0;
  cloud->data = std::move(msg.data);
  return true;
}

// Blue (0) -> yellow (0.5) -> red (1).
void rampColour(float p, uint8_t* rgb) {
  p = std::min(std::max(p, 0.f), 1.f);
  if (p < 0.5f) {
    const float t = p * 2.f;
    rgb[0] = static_cast<uint8_t>(40 + 215 * t);
    rgb[1] = static_cast<uint8_t>(80 + 150 * t);
    rgb[2] = static_cast<uint8_t>(255 * (1.f - t));
  } else {
    const float t = (p - 0.5f) * 2.f;
    rgb[0] = 255;
    rgb[1] = static_cast<uint8_t>(230 * (1.f - t));
    rgb[2] = 0;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, method, mask_path, png_path, color = "label", sensor_model = "hdl64e";
  float sensor_height = 1.73f, png_range = 40.f;
  std::vector<float> elevations, mount_rpy, sensor_origin;
  bool estimate_mount = false, elevations_from_rings = false;
  auto numbers = [](const std::string& list) {
    std::vector<float> out;
    std::size_t start = 0;
    while (start <= list.size()) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      const std::string item = list.substr(start, comma - start);
      char* end = nullptr;
      const float v = std::strtof(item.c_str(), &end);
      if (item.empty() || *end != 0 || !std::isfinite(v)) return std::vector<float>();
      out.push_back(v);
      start = comma + 1;
    }
    return out;
  };
  int repeat = 0, png_size = 1000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&](const char* what) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "ground_segment: " << a << " needs " << what << "\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--sensor-height") sensor_height = std::strtof(next("metres").c_str(), nullptr);
    else if (a == "--method") method = next("a name");
    else if (a == "--sensor-model") sensor_model = next("a name");
    else if (a == "--laser-elevations-deg") {
      elevations = numbers(next("a list of degrees"));
      if (elevations.empty()) { std::cerr << "ground_segment: --laser-elevations-deg needs numbers A,B,...\n"; return 2; }
    } else if (a == "--mount-rpy") {
      mount_rpy = numbers(next("roll,pitch"));
      if (mount_rpy.size() != 2) { std::cerr << "ground_segment: --mount-rpy needs R,P in degrees\n"; return 2; }
    } else if (a == "--sensor-origin") {
      sensor_origin = numbers(next("x,y,z"));
      if (sensor_origin.size() != 3 || !(sensor_origin[2] > 0.f)) {
        std::cerr << "ground_segment: --sensor-origin needs X,Y,Z in metres, Z > 0\n";
        return 2;
      }
    } else if (a == "--estimate-mount") estimate_mount = true;
    else if (a == "--laser-elevations-from-rings") elevations_from_rings = true;
    else if (a == "--mask") mask_path = next("a path");
    else if (a == "--repeat") repeat = std::atoi(next("a count").c_str());
    else if (a == "--png") png_path = next("a path");
    else if (a == "--color") color = next("label or p");
    else if (a == "--png-range") png_range = std::strtof(next("metres").c_str(), nullptr);
    else if (a == "--png-size") png_size = std::atoi(next("pixels").c_str());
    else if (a == "--list-methods") {
      for (const std::string& n : groundModelNames()) std::cout << n << "\n";
      return 0;
    } else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      std::cerr << "ground_segment: unknown option " << a << "\n";
      usage();
      return 2;
    } else if (input.empty()) {
      input = a;
    } else {
      std::cerr << "ground_segment: more than one input file given\n";
      return 2;
    }
  }
  if (input.empty()) {
    usage();
    return 2;
  }
  if (color != "label" && color != "p") {
    std::cerr << "ground_segment: --color must be label or p\n";
    return 2;
  }
  if (!std::isfinite(sensor_height) || sensor_height <= 0.f || png_size < 16 || png_size > 20000 ||
      !(png_range > 0.f) || repeat < 0) {
    std::cerr << "ground_segment: bad numeric option\n";
    return 2;
  }
  if (method.empty()) method = groundModelNames().front();

  PackedCloud cloud;
  std::string error;
  bool ok;
  if (endsWith(input, ".pcd")) ok = readPcd(input, &cloud, &error);
  else ok = readKittiBin(input, &cloud, &error);
  if (!ok) {
    std::cerr << "ground_segment: " << error << "\n";
    return 1;
  }
  PointCloudView view;
  if (!cloud.view(&view, &error)) {
    std::cerr << "ground_segment: " << input << ": " << error << "\n";
    return 1;
  }
  if (!sensor_origin.empty()) {
    // A vehicle-frame cloud: moved into a frame at the sensor (axes kept), which the core
    // expects; empty slots (0, 0, 0) stay empty.
    const FieldDesc* fx = findField(cloud.layout, "x");
    const FieldDesc* fy = findField(cloud.layout, "y");
    const FieldDesc* fz = findField(cloud.layout, "z");
    for (std::size_t i = 0; i < view.size(); ++i) {
      const Eigen::Vector3f p = view.xyz(i);
      if (p.isZero()) continue;
      uint8_t* point = const_cast<uint8_t*>(view.pointData(i));
      writeField(point, *fx, p.x() - sensor_origin[0]);
      writeField(point, *fy, p.y() - sensor_origin[1]);
      writeField(point, *fz, p.z() - sensor_origin[2]);
    }
    sensor_height = sensor_origin[2];
  }
  std::unique_ptr<GroundModel> model = makeGroundModel(method, &error);
  if (!model) {
    std::cerr << "ground_segment: " << error << "\n";
    return 2;
  }
  LidarModel lidar;
  if (elevations_from_rings) {
    if (!measureRingElevations(view, &elevations, &error)) {
      std::cerr << "ground_segment: cannot measure the beam elevations: " << error << "\n";
      return 1;
    }
    std::printf("laser_elevations_deg: [");
    for (std::size_t k = 0; k < elevations.size(); ++k) std::printf("%s%.3f", k ? ", " : "", elevations[k]);
    std::printf("]\n");
  }
  if (!elevations.empty()) {
    if (!lidarModelFromElevations(elevations, &lidar, &error)) {
      std::cerr << "ground_segment: " << error << "\n";
      return 2;
    }
  } else if (const LidarModel* named = findLidarModel(sensor_model)) {
    lidar = *named;
  } else {
    std::cerr << "ground_segment: unknown sensor model " << sensor_model << " (known: " << lidarModelNames() << ")\n";
    return 2;
  }
  model->setLidarModel(lidar);
  const std::string mismatch = checkCloudAgainstLidarModel(view, lidar);
  if (!mismatch.empty()) std::fprintf(stderr, "ground_segment: warning: %s\n", mismatch.c_str());
  SensorPose pose = SensorPose::fromHeight(sensor_height);
  if (estimate_mount) {
    MountEstimate mount;
    if (!estimateMountFromGround(view, sensor_height, &mount)) {
      std::cerr << "ground_segment: no ground plane found to estimate the mount from\n";
      return 1;
    }
    std::printf("mount: height %.3f m, roll %.2f deg, pitch %.2f deg (%zu returns, %.1f%% within 0.2 m of the plane)\n",
                mount.height, mount.roll_deg, mount.pitch_deg, mount.returns, 100.0 * mount.inlier_fraction);
    pose = SensorPose::fromMount(mount.height, mount.roll_deg, mount.pitch_deg);
  } else if (!mount_rpy.empty()) {
    pose = SensorPose::fromMount(sensor_height, mount_rpy[0], mount_rpy[1]);
  }

  GroundClassification result;
  model->classify(view, pose, &result);  // also warms the workspace
  if (repeat > 0) {
    std::vector<double> ms;
    for (int k = 0; k < repeat; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      model->classify(view, pose, &result);
      const auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    const double median = (ms.size() % 2) ? ms[ms.size() / 2]
                                          : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
    std::printf("median_ms=%.3f min_ms=%.3f\n", median, ms.front());
  }
  std::fprintf(stderr, "%s: %zu points, method %s: ground %zu, obstacle %zu, unknown %zu\n",
               input.c_str(), result.size(), model->name().c_str(), result.count(kLabelGround),
               result.count(kLabelObstacle), result.count(kLabelUnknown));

  if (!mask_path.empty()) {
    std::vector<uint8_t> mask(result.size());
    for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = result.labels[i] == kLabelGround;
    const std::string tmp = mask_path + ".tmp";
    std::ofstream f(tmp, std::ios::binary);
    f.write(reinterpret_cast<const char*>(mask.data()), static_cast<std::streamsize>(mask.size()));
    f.close();
    if (!f || std::rename(tmp.c_str(), mask_path.c_str()) != 0) {
      std::cerr << "ground_segment: cannot write " << mask_path << "\n";
      return 1;
    }
  }
  if (!png_path.empty()) {
    RgbImage img(png_size, png_size, 18, 18, 24);
    const float px_per_m = static_cast<float>(png_size) / (2.f * png_range);
    // Range rings every 10 m.
    for (int ring = 10; ring <= static_cast<int>(png_range * 1.5f); ring += 10) {
      for (int a = 0; a < 3600; ++a) {
        const float t = static_cast<float>(a) * 3.14159265f / 1800.f;
        img.set(static_cast<int>(png_size / 2 + ring * px_per_m * std::cos(t)),
                static_cast<int>(png_size / 2 + ring * px_per_m * std::sin(t)), 60, 60, 70);
      }
    }
    // Ground first, obstacles on top. x forward = up, y left = left.
    for (int pass = 0; pass < 3; ++pass) {
      for (std::size_t i = 0; i < result.size(); ++i) {
        const uint8_t label = result.labels[i];
        const int want = pass == 0 ? kLabelUnknown : (pass == 1 ? kLabelGround : kLabelObstacle);
        if (label != want) continue;
        const Eigen::Vector3f p = view.xyz(i);
        if (!p.allFinite()) continue;
        const int u = static_cast<int>(png_size / 2 - p.y() * px_per_m);
        const int v = static_cast<int>(png_size / 2 - p.x() * px_per_m);
        uint8_t rgb[3];
        if (color == "p") {
          if (label == kLabelUnknown) { rgb[0] = rgb[1] = rgb[2] = 110; }
          else rampColour(result.p_obstacle[i], rgb);
        } else if (label == kLabelGround) {
          rgb[0] = 40; rgb[1] = 200; rgb[2] = 70;
        } else if (label == kLabelObstacle) {
          rgb[0] = 255; rgb[1] = 50; rgb[2] = 40;
        } else {
          rgb[0] = rgb[1] = rgb[2] = 110;
        }
        img.set(u, v, rgb[0], rgb[1], rgb[2]);
      }
    }
    // The sensor.
    for (int d = -3; d <= 3; ++d) {
      img.set(png_size / 2 + d, png_size / 2, 255, 255, 255);
      img.set(png_size / 2, png_size / 2 + d, 255, 255, 255);
    }
    if (!writePng(png_path, img, &error)) {
      std::cerr << "ground_segment: " << error << "\n";
      return 1;
    }
  }
  return 0;
}
