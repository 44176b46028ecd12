// libFuzzer target: an arbitrary PointCloud2 (layout + bytes) through PointCloudView::create
// and, when it is accepted, through every ground model of groundModelNames().
// Input: a 16-byte header (width, height, point_step, row_step slack, field count, flags), then
// up to 6 field descriptors of 4 bytes (name index, offset, datatype, count), then the data.
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_model.h"
#include "fuzz_reader.h"

#ifndef LADAR_FUZZ_ENTRY
#define LADAR_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

namespace fuzz_point_cloud {
using namespace ladar_perception;
using ladar_perception::fuzz::Reader;

const char* const kNames[] = {"x", "y", "z", "intensity", "ring", "time", "channel", "t"};

std::vector<std::unique_ptr<GroundModel>>& models() {
  static std::vector<std::unique_ptr<GroundModel>> m = [] {
    std::vector<std::unique_ptr<GroundModel>> out;
    for (const std::string& name : groundModelNames()) {
      std::string error;
      auto model = makeGroundModel(name, &error);
      if (!model) __builtin_trap();  // every advertised name must build
      out.push_back(std::move(model));
    }
    return out;
  }();
  return m;
}

}  // namespace fuzz_point_cloud

extern "C" int LADAR_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  using namespace ladar_perception;
  using namespace fuzz_point_cloud;
  Reader in{data, size};
  CloudLayout layout;
  layout.width = in.get<uint16_t>();
  layout.height = in.get<uint8_t>();
  layout.point_step = in.get<uint8_t>();
  const uint8_t row_slack = in.get<uint8_t>();
  const uint8_t flags = in.get<uint8_t>();
  const int nfields = in.get<uint8_t>() % 7;
  const float sensor_height = static_cast<float>(in.get<int16_t>()) / 1000.f;
  const float roll = static_cast<float>(in.get<int8_t>()) / 100.f;
  const float pitch = static_cast<float>(in.get<int8_t>()) / 100.f;
  (void)in.get<uint32_t>();  // reserved
  layout.row_step = (flags & 1) ? in.get<uint32_t>()
                                : layout.width * layout.point_step + row_slack;
  layout.is_bigendian = (flags & 2) != 0;
  for (int i = 0; i < nfields; ++i) {
    FieldDesc f;
    f.name = kNames[in.get<uint8_t>() % 8];
    f.offset = in.get<uint8_t>();
    f.datatype = in.get<uint8_t>() % 10;
    f.count = in.get<uint8_t>() % 3;
    layout.fields.push_back(f);
  }
  // Keep runs short: at most 4096 points (create() bounds them by the bytes given anyway).
  if (static_cast<uint64_t>(layout.width) * layout.height > 4096) return 0;

  std::vector<uint8_t> bytes(in.p, in.p + in.n);  // exact-size heap copy: ASan sees overreads
  PointCloudView view;
  std::string error;
  const bool ok = PointCloudView::create(bytes.empty() ? nullptr : bytes.data(), bytes.size(),
                                         layout, &view, &error);
  if (!ok) {
    if (error.empty()) __builtin_trap();  // a rejection must say why
    return 0;
  }
  SensorPose pose = SensorPose::fromHeight(sensor_height);
  pose.sensor_to_ground.linear() =
      (Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX()) *
       Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY())).toRotationMatrix();
  GroundClassification result;
  const int which = flags >> 4;
  auto& all = models();
  for (size_t m = 0; m < all.size(); ++m) {
    if (which != 15 && which % all.size() != m) continue;  // 15: every model
    all[m]->classify(view, pose, &result);
    if (result.labels.size() != view.size()) __builtin_trap();
  }
  return 0;
}
