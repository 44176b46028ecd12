#include "ladar_perception/ros/cloud_conversion.h"

#include <cstring>

namespace ladar_perception {

CloudLayout layoutOf(const sensor_msgs::PointCloud2& msg) {
  CloudLayout layout;
  layout.fields.reserve(msg.fields.size());
  for (const sensor_msgs::PointField& f : msg.fields) {
    layout.fields.push_back(FieldDesc{f.name, f.offset, f.datatype, f.count});
  }
  layout.width = msg.width;
  layout.height = msg.height;
  layout.point_step = msg.point_step;
  layout.row_step = msg.row_step;
  layout.is_bigendian = msg.is_bigendian;
  return layout;
}

bool viewOf(const sensor_msgs::PointCloud2& msg, CloudLayout* layout, PointCloudView* view,
            std::string* error, CloudError* code) {
  *layout = layoutOf(msg);
  return PointCloudView::create(msg.data.data(), msg.data.size(), *layout, view, error, code);
}


sensor_msgs::PointCloud2Ptr subsetCloud(const sensor_msgs::PointCloud2& in,
                                        const PointCloudView& view,
                                        const GroundClassification& result, Label label) {
  sensor_msgs::PointCloud2Ptr out(new sensor_msgs::PointCloud2);
  out->header = in.header;
  out->fields = in.fields;
  out->is_bigendian = in.is_bigendian;
  out->point_step = in.point_step;
  const std::size_t n = view.size();
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) count += (result.labels[i] == label);
  out->height = 1;
  out->width = static_cast<uint32_t>(count);
  out->row_step = out->point_step * out->width;
  out->is_dense = in.is_dense || label != kLabelUnknown;
  out->data.resize(static_cast<std::size_t>(out->row_step));
  uint8_t* dst = out->data.data();
  const std::size_t step = in.point_step;
  for (std::size_t i = 0; i < n; ++i) {
    if (result.labels[i] != label) continue;
    std::memcpy(dst, view.pointData(i), step);
    dst += step;
  }
  return out;
}

sensor_msgs::PointCloud2Ptr classifiedCloud(const sensor_msgs::PointCloud2& in,
                                            const PointCloudView& view,
                                            const GroundClassification& result) {
  sensor_msgs::PointCloud2Ptr out(new sensor_msgs::PointCloud2);
  out->header = in.header;
  out->fields = in.fields;
  out->is_bigendian = in.is_bigendian;
  out->height = in.height;
  out->width = in.width;
  out->is_dense = in.is_dense;
  // Drop input fields that clash with the two we add, then append them.
  for (auto it = out->fields.begin(); it != out->fields.end();) {
    it = (it->name == "p_obstacle" || it->name == "label") ? out->fields.erase(it) : it + 1;
  }
  const uint32_t p_offset = in.point_step;
  const uint32_t label_offset = in.point_step + 4;
  sensor_msgs::PointField pf;
  pf.name = "p_obstacle";
  pf.offset = p_offset;
  pf.datatype = sensor_msgs::PointField::FLOAT32;
  pf.count = 1;
  out->fields.push_back(pf);
  pf.name = "label";
  pf.offset = label_offset;
  pf.datatype = sensor_msgs::PointField::UINT8;
  out->fields.push_back(pf);
  out->point_step = in.point_step + 5;
  out->row_step = out->point_step * out->width;
  out->data.resize(static_cast<std::size_t>(out->row_step) * out->height);
  uint8_t* dst = out->data.data();
  const std::size_t n = view.size();
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(dst, view.pointData(i), in.point_step);
    std::memcpy(dst + p_offset, &result.p_obstacle[i], 4);
    dst[label_offset] = result.labels[i];
    dst += out->point_step;
  }
  return out;
}

void applyLayout(const CloudLayout& layout, sensor_msgs::PointCloud2* out) {
  out->fields.clear();
  for (const FieldDesc& f : layout.fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.datatype;
    pf.count = f.count;
    out->fields.push_back(pf);
  }
  out->width = layout.width;
  out->height = layout.height;
  out->point_step = layout.point_step;
  out->row_step = layout.row_step;
  out->is_bigendian = layout.is_bigendian;
}

sensor_msgs::PointCloud2Ptr toMessage(const PackedCloud& cloud) {
  sensor_msgs::PointCloud2Ptr out(new sensor_msgs::PointCloud2);
  applyLayout(cloud.layout, out.get());
  out->is_dense = false;
  out->data = cloud.data;
  return out;
}

}  // namespace ladar_perception
