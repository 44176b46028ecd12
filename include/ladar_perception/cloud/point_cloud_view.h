// Read-only view of a packed point cloud (the memory layout of sensor_msgs/PointCloud2) that
// finds its fields by name and datatype. ROS-free: the ROS adapters describe a message with
// FieldDesc values and the core reads through this view without copying the message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace ladar_perception {

// The datatype codes of sensor_msgs/PointField, so a message's fields map one to one.
enum class FieldType : uint8_t {
  kInt8 = 1,
  kUInt8 = 2,
  kInt16 = 3,
  kUInt16 = 4,
  kInt32 = 5,
  kUInt32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

// Size in bytes of one element of the type, 0 for an unknown code.
std::size_t fieldTypeSize(uint8_t datatype);

// One field of a packed cloud, as sensor_msgs/PointField describes it.
struct FieldDesc {
  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;  // a FieldType code; other values are rejected when the field is needed
  uint32_t count = 1;
};

// The header-level description of a packed cloud buffer.
struct CloudLayout {
  std::vector<FieldDesc> fields;
  uint32_t width = 0;
  uint32_t height = 1;
  uint32_t point_step = 0;
  uint32_t row_step = 0;
  bool is_bigendian = false;
};

// Why a cloud cannot be read: adapters count and report each kind separately.
enum class CloudError : uint8_t {
  kNone = 0,
  kBigEndian,       // is_bigendian clouds are not supported
  kBadStep,         // point_step 0 or row_step smaller than width * point_step
  kTruncated,       // data shorter than the layout needs
  kMissingField,    // x, y or z absent
  kFieldOutside,    // a field does not fit inside point_step
  kBadFieldType,    // x, y or z of an unknown or non-floating datatype, or count 0
};
const char* cloudErrorName(CloudError e);

// Reads one scalar field of a point as double or float, whatever its datatype.
// Invalid accessors (field absent) are never read.
struct FieldAccessor {
  uint32_t offset = 0;
  FieldType type = FieldType::kFloat32;
  bool valid = false;

  template <typename T>
  T read(const uint8_t* point) const {
    const uint8_t* p = point + offset;
    switch (type) {
      case FieldType::kFloat32: { float v; std::memcpy(&v, p, 4); return static_cast<T>(v); }
      case FieldType::kFloat64: { double v; std::memcpy(&v, p, 8); return static_cast<T>(v); }
      case FieldType::kUInt16: { uint16_t v; std::memcpy(&v, p, 2); return static_cast<T>(v); }
      case FieldType::kUInt8: return static_cast<T>(*p);
      case FieldType::kInt8: return static_cast<T>(static_cast<int8_t>(*p));
      case FieldType::kInt16: { int16_t v; std::memcpy(&v, p, 2); return static_cast<T>(v); }
      case FieldType::kInt32: { int32_t v; std::memcpy(&v, p, 4); return static_cast<T>(v); }
      case FieldType::kUInt32: { uint32_t v; std::memcpy(&v, p, 4); return static_cast<T>(v); }
    }
    return T(0);
  }
};

// A validated, read-only view over a packed cloud. Construct with PointCloudView::create, which
// checks the layout against the buffer size so that every read stays inside the buffer.
// Points are indexed 0..size()-1 in row-major order (row r, column c -> r * width + c), the order
// of the message's points; output labels use the same order.
class PointCloudView {
 public:
  PointCloudView() = default;

  // Validates the layout and buffer. On failure returns false and says what is wrong in *error
  // (one sentence, suitable for a throttled log line) and which kind of problem in *code.
  static bool create(const uint8_t* data, std::size_t data_size, const CloudLayout& layout,
                     PointCloudView* view, std::string* error, CloudError* code = nullptr);

  std::size_t size() const { return static_cast<std::size_t>(width_) * height_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  bool empty() const { return size() == 0; }

  const uint8_t* pointData(std::size_t i) const {
    if (contiguous_) return data_ + i * point_step_;
    const std::size_t row = i / width_;
    const std::size_t col = i - row * width_;
    return data_ + row * row_step_ + col * point_step_;
  }

  // True when x, y and z are all float32: the fast path of xyz().
  bool packedFloatXYZ() const { return fast_xyz_; }

  Eigen::Vector3f xyz(std::size_t i) const {
    const uint8_t* p = pointData(i);
    if (fast_xyz_) {
      float v[3];
      std::memcpy(&v[0], p + x_.offset, 4);
      std::memcpy(&v[1], p + y_.offset, 4);
      std::memcpy(&v[2], p + z_.offset, 4);
      return Eigen::Vector3f(v[0], v[1], v[2]);
    }
    return Eigen::Vector3f(x_.read<float>(p), y_.read<float>(p), z_.read<float>(p));
  }

  // The beam (row) of a return: the `ring` field (Velodyne's driver), else the `channel` field
  // (Ouster's), else, for an organised cloud of 2..128 rows without either, its row (Ouster's
  // driver publishes one row per beam). Integer fields only.
  enum class RingSource { kNone, kRingField, kChannelField, kRows };
  bool hasRing() const { return ring_source_ != RingSource::kNone; }
  RingSource ringSource() const { return ring_source_; }
  int ring(std::size_t i) const {
    return ring_.valid ? ring_.read<int>(pointData(i)) : static_cast<int>(i / width_);
  }
  bool hasIntensity() const { return intensity_.valid; }
  float intensity(std::size_t i) const { return intensity_.read<float>(pointData(i)); }

  // Accessor for any other field by name (invalid when absent or not a scalar number).
  FieldAccessor field(const std::string& name) const;

  const CloudLayout& layout() const { return *layout_; }

 private:
  const uint8_t* data_ = nullptr;
  const CloudLayout* layout_ = nullptr;
  uint32_t width_ = 0;
  uint32_t height_ = 0;
  uint32_t point_step_ = 0;
  uint32_t row_step_ = 0;
  FieldAccessor x_, y_, z_, ring_, intensity_;
  RingSource ring_source_ = RingSource::kNone;
  bool fast_xyz_ = false;
  bool contiguous_ = false;  // row_step == width * point_step (or one row)
};
const char* ringSourceName(PointCloudView::RingSource source);

// An owned packed cloud: the ROS-free twin of sensor_msgs/PointCloud2 used by the simulator,
// the file readers and the tests. view() borrows it.
struct PackedCloud {
  CloudLayout layout;
  std::vector<uint8_t> data;

  std::size_t size() const {
    return static_cast<std::size_t>(layout.width) * layout.height;
  }
  // A view of this cloud; aborts with an error message in *error when the layout is invalid.
  bool view(PointCloudView* out, std::string* error = nullptr) const;
};

// Layouts commonly met on vehicles, for the simulator, readers and tests.
// The ROS 1 velodyne driver's packed 22-byte XYZIRT: x,y,z,intensity float32, ring uint16,
// time float32.
CloudLayout velodyneXYZIRTLayout(uint32_t num_points);
// PCL-aligned PointXYZI (32 bytes: x,y,z at 0,4,8; intensity at 16).
CloudLayout pclXYZILayout(uint32_t num_points);
// KITTI's x,y,z,intensity float32 (16 bytes).
CloudLayout xyziLayout(uint32_t num_points);
// The ROS 1 Ouster driver's organised PointXYZIRT-like layout, `rows` x `columns` (one row per
// beam, the top beam first; empty slots x = y = z = 0): x,y,z at 0,4,8 (16-byte aligned),
// intensity float32 at 16, t uint32 at 20, reflectivity uint16 at 24, ring uint16 at 26 (the
// row), ambient uint16 at 28, range uint32 at 32; point_step 48.
CloudLayout ousterLayout(uint32_t rows, uint32_t columns);

// Appends a field, returning its offset; the point_step grows to hold it (packed, no padding).
uint32_t appendField(CloudLayout* layout, const std::string& name, FieldType type);

// Writes a scalar value into a point of a packed buffer at a field's offset and type.
void writeField(uint8_t* point, const FieldDesc& field, double value);

// Finds a field by name; nullptr when absent.
const FieldDesc* findField(const CloudLayout& layout, const std::string& name);

}  // namespace ladar_perception
