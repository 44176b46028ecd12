#include "ladar_perception/cloud/point_cloud_view.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ladar_perception {

std::size_t fieldTypeSize(uint8_t datatype) {
  switch (static_cast<FieldType>(datatype)) {
    case FieldType::kInt8:
    case FieldType::kUInt8: return 1;
    case FieldType::kInt16:
    case FieldType::kUInt16: return 2;
    case FieldType::kInt32:
    case FieldType::kUInt32:
    case FieldType::kFloat32: return 4;
    case FieldType::kFloat64: return 8;
  }
  return 0;
}

const FieldDesc* findField(const CloudLayout& layout, const std::string& name) {
  for (const FieldDesc& f : layout.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

namespace {

// Makes an accessor for a scalar numeric field that lies inside point_step.
// Returns false with a reason when the field exists but cannot be read.
bool makeAccessor(const CloudLayout& layout, const std::string& name, bool required,
                  FieldAccessor* out, std::string* error, CloudError* code = nullptr) {
  *out = FieldAccessor();
  const FieldDesc* f = findField(layout, name);
  if (f == nullptr) {
    if (required && error) *error = "field '" + name + "' is missing";
    if (required && code) *code = CloudError::kMissingField;
    return !required;
  }
  const std::size_t size = fieldTypeSize(f->datatype);
  std::ostringstream why;
  CloudError kind = CloudError::kBadFieldType;
  if (size == 0) {
    why << "field '" << name << "' has unknown datatype " << static_cast<int>(f->datatype);
  } else if (f->count < 1) {
    why << "field '" << name << "' has count 0";
  } else if (static_cast<uint64_t>(f->offset) + size > layout.point_step) {
    why << "field '" << name << "' (offset " << f->offset << ", " << size
        << " bytes) does not fit in point_step " << layout.point_step;
    kind = CloudError::kFieldOutside;
  }
  const std::string reason = why.str();
  if (!reason.empty()) {
    if (required) {
      if (error) *error = reason;
      if (code) *code = kind;
      return false;
    }
    return true;  // an optional field we cannot read is ignored
  }
  out->offset = f->offset;
  out->type = static_cast<FieldType>(f->datatype);
  out->valid = true;
  return true;
}

bool isFloatType(const FieldAccessor& a) {
  return a.type == FieldType::kFloat32 || a.type == FieldType::kFloat64;
}

}  // namespace

const char* cloudErrorName(CloudError e) {
  switch (e) {
    case CloudError::kNone: return "none";
    case CloudError::kBigEndian: return "big-endian";
    case CloudError::kBadStep: return "bad point_step/row_step";
    case CloudError::kTruncated: return "truncated data";
    case CloudError::kMissingField: return "missing x/y/z";
    case CloudError::kFieldOutside: return "field outside point_step";
    case CloudError::kBadFieldType: return "bad x/y/z datatype";
  }
  return "unknown";
}

bool PointCloudView::create(const uint8_t* data, std::size_t data_size, const CloudLayout& layout,
                            PointCloudView* view, std::string* error, CloudError* code) {
  std::string dummy;
  std::string& err = error ? *error : dummy;
  CloudError dummy_code = CloudError::kNone;
  CloudError& why = code ? *code : dummy_code;
  why = CloudError::kNone;
  *view = PointCloudView();
  if (layout.is_bigendian) {
    err = "big-endian clouds are not supported";
    why = CloudError::kBigEndian;
    return false;
  }
  const uint64_t npoints = static_cast<uint64_t>(layout.width) * layout.height;
  if (npoints > 0) {
    if (layout.point_step == 0) {
      err = "point_step is 0";
      why = CloudError::kBadStep;
      return false;
    }
    if (static_cast<uint64_t>(layout.row_step) <
        static_cast<uint64_t>(layout.width) * layout.point_step) {
      std::ostringstream s;
      s << "row_step " << layout.row_step << " is smaller than width " << layout.width
        << " * point_step " << layout.point_step;
      err = s.str();
      why = CloudError::kBadStep;
      return false;
    }
    const uint64_t needed = static_cast<uint64_t>(layout.row_step) * (layout.height - 1) +
                            static_cast<uint64_t>(layout.width) * layout.point_step;
    if (data == nullptr || data_size < needed) {
      std::ostringstream s;
      s << "data holds " << data_size << " bytes but " << layout.width << "x" << layout.height
        << " points with point_step " << layout.point_step << " and row_step " << layout.row_step
        << " need " << needed;
      err = s.str();
      why = CloudError::kTruncated;
      return false;
    }
  }
  PointCloudView v;
  if (!makeAccessor(layout, "x", true, &v.x_, &err, &why) ||
      !makeAccessor(layout, "y", true, &v.y_, &err, &why) ||
      !makeAccessor(layout, "z", true, &v.z_, &err, &why)) {
    return false;
  }
  if (!isFloatType(v.x_) || !isFloatType(v.y_) || !isFloatType(v.z_)) {
    err = "fields x, y, z must be float32 or float64";
    why = CloudError::kBadFieldType;
    return false;
  }
  makeAccessor(layout, "ring", false, &v.ring_, nullptr);
  if (v.ring_.valid && isFloatType(v.ring_)) v.ring_.valid = false;  // a ring is an integer
  if (v.ring_.valid) v.ring_source_ = RingSource::kRingField;
  if (!v.ring_.valid) {
    makeAccessor(layout, "channel", false, &v.ring_, nullptr);  // Ouster name
    if (v.ring_.valid && isFloatType(v.ring_)) v.ring_.valid = false;
    if (v.ring_.valid) v.ring_source_ = RingSource::kChannelField;
  }
  if (!v.ring_.valid && layout.height >= 2 && layout.height <= 128 && layout.width > 0) {
    v.ring_source_ = RingSource::kRows;
  }
  makeAccessor(layout, "intensity", false, &v.intensity_, nullptr);
  v.data_ = data;
  v.layout_ = &layout;
  v.width_ = layout.width;
  v.height_ = layout.height;
  v.point_step_ = layout.point_step;
  v.row_step_ = layout.row_step;
  v.contiguous_ = layout.height <= 1 ||
                  static_cast<uint64_t>(layout.row_step) ==
                      static_cast<uint64_t>(layout.width) * layout.point_step;
  v.fast_xyz_ = v.x_.type == FieldType::kFloat32 && v.y_.type == FieldType::kFloat32 &&
                v.z_.type == FieldType::kFloat32;
  *view = v;
  return true;
}

const char* ringSourceName(PointCloudView::RingSource source) {
  switch (source) {
    case PointCloudView::RingSource::kRingField: return "ring field";
    case PointCloudView::RingSource::kChannelField: return "channel field";
    case PointCloudView::RingSource::kRows: return "organised rows";
    case PointCloudView::RingSource::kNone: break;
  }
  return "none";
}

FieldAccessor PointCloudView::field(const std::string& name) const {
  FieldAccessor a;
  if (layout_ != nullptr) makeAccessor(*layout_, name, false, &a, nullptr);
  return a;
}

bool PackedCloud::view(PointCloudView* out, std::string* error) const {
  return PointCloudView::create(data.data(), data.size(), layout, out, error);
}

uint32_t appendField(CloudLayout* layout, const std::string& name, FieldType type) {
  FieldDesc f;
  f.name = name;
  f.offset = layout->point_step;
  f.datatype = static_cast<uint8_t>(type);
  f.count = 1;
  layout->fields.push_back(f);
  layout->point_step += static_cast<uint32_t>(fieldTypeSize(f.datatype));
  layout->row_step = layout->point_step * layout->width;
  return f.offset;
}

void writeField(uint8_t* point, const FieldDesc& field, double value) {
  uint8_t* p = point + field.offset;
  switch (static_cast<FieldType>(field.datatype)) {
    case FieldType::kFloat32: { float v = static_cast<float>(value); std::memcpy(p, &v, 4); break; }
    case FieldType::kFloat64: { std::memcpy(p, &value, 8); break; }
    case FieldType::kUInt8: *p = static_cast<uint8_t>(value); break;
    case FieldType::kInt8: *p = static_cast<uint8_t>(static_cast<int8_t>(value)); break;
    case FieldType::kUInt16: { uint16_t v = static_cast<uint16_t>(value); std::memcpy(p, &v, 2); break; }
    case FieldType::kInt16: { int16_t v = static_cast<int16_t>(value); std::memcpy(p, &v, 2); break; }
    case FieldType::kUInt32: { uint32_t v = static_cast<uint32_t>(value); std::memcpy(p, &v, 4); break; }
    case FieldType::kInt32: { int32_t v = static_cast<int32_t>(value); std::memcpy(p, &v, 4); break; }
  }
}

namespace {
CloudLayout emptyLayout(uint32_t num_points) {
  CloudLayout l;
  l.width = num_points;
  l.height = 1;
  return l;
}
}  // namespace

CloudLayout velodyneXYZIRTLayout(uint32_t num_points) {
  CloudLayout l = emptyLayout(num_points);
  appendField(&l, "x", FieldType::kFloat32);
  appendField(&l, "y", FieldType::kFloat32);
  appendField(&l, "z", FieldType::kFloat32);
  appendField(&l, "intensity", FieldType::kFloat32);
  appendField(&l, "ring", FieldType::kUInt16);
  appendField(&l, "time", FieldType::kFloat32);
  return l;  // point_step 22, as the ROS 1 velodyne driver packs it
}

CloudLayout pclXYZILayout(uint32_t num_points) {
  CloudLayout l = emptyLayout(num_points);
  appendField(&l, "x", FieldType::kFloat32);
  appendField(&l, "y", FieldType::kFloat32);
  appendField(&l, "z", FieldType::kFloat32);
  l.point_step = 16;  // PCL's 16-byte aligned xyz + padding
  appendField(&l, "intensity", FieldType::kFloat32);
  l.point_step = 32;
  l.row_step = l.point_step * l.width;
  return l;
}

CloudLayout xyziLayout(uint32_t num_points) {
  CloudLayout l = emptyLayout(num_points);
  appendField(&l, "x", FieldType::kFloat32);
  appendField(&l, "y", FieldType::kFloat32);
  appendField(&l, "z", FieldType::kFloat32);
  appendField(&l, "intensity", FieldType::kFloat32);
  return l;
}

CloudLayout ousterLayout(uint32_t rows, uint32_t columns) {
  CloudLayout l = emptyLayout(columns);
  appendField(&l, "x", FieldType::kFloat32);
  appendField(&l, "y", FieldType::kFloat32);
  appendField(&l, "z", FieldType::kFloat32);
  l.point_step = 16;
  appendField(&l, "intensity", FieldType::kFloat32);
  appendField(&l, "t", FieldType::kUInt32);
  appendField(&l, "reflectivity", FieldType::kUInt16);
  appendField(&l, "ring", FieldType::kUInt16);
  appendField(&l, "ambient", FieldType::kUInt16);
  l.point_step = 32;
  appendField(&l, "range", FieldType::kUInt32);
  l.point_step = 48;
  l.height = rows;
  l.row_step = l.point_step * l.width;
  return l;
}

}  // namespace ladar_perception
