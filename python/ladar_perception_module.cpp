// ladar_perception._core: the ROS-free core from NumPy. Every call goes to the core libraries
// (ground, sim, eval, io); nothing of the core is copied here. An (N, 3|4) float32 C-contiguous
// array is read in place through a PointCloudView; the labels and P(obstacle) are the core's
// own result buffers handed to NumPy. The core calls run without the GIL.
// (Over 600 lines: one compiled module for one import; its functions are argument checks and
// NumPy conversions around core calls, and the definitions with their docstrings.)
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "ladar_perception/cloud/lidar_models.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/eval/real_ground_eval.h"
#include "ladar_perception/eval/semantic_kitti.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/vertical_scan.h"
#include "ladar_perception/io/image.h"
#include "ladar_perception/io/kitti.h"
#include "ladar_perception/sim/scan_simulator.h"
#include "ladar_perception/sim/sensor_models.h"
#include "ladar_perception/sim/world.h"

namespace py = pybind11;
using namespace ladar_perception;

namespace {

constexpr float kKittiSensorHeight = 1.73f;  // ground_segment's --sensor-height default

std::string shapeText(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s << (d ? ", " : "") << a.shape(d);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

// A NumPy cloud as the core sees it: the array it views (the caller's own when it was float32
// and C-contiguous), its layout and the validated view.
struct NumpyCloud {
  py::array array;              // keeps the viewed buffer alive
  std::vector<uint8_t> packed;  // points and ring packed together (ring array given)
  CloudLayout layout;
  PointCloudView view;
  std::size_t size = 0;
};

bool isNumeric(const py::dtype& dt) {
  const char k = dt.kind();
  return k == 'f' || k == 'i' || k == 'u';
}

// The FieldType of a scalar NumPy dtype; false for any other.
bool fieldTypeOf(const py::dtype& dt, FieldType* type) {
  const char k = dt.kind();
  const auto size = dt.itemsize();
  if (k == 'f' && size == 4) *type = FieldType::kFloat32;
  else if (k == 'f' && size == 8) *type = FieldType::kFloat64;
  else if (k == 'u' && size == 1) *type = FieldType::kUInt8;
  else if (k == 'i' && size == 1) *type = FieldType::kInt8;
  else if (k == 'u' && size == 2) *type = FieldType::kUInt16;
  else if (k == 'i' && size == 2) *type = FieldType::kInt16;
  else if (k == 'u' && size == 4) *type = FieldType::kUInt32;
  else if (k == 'i' && size == 4) *type = FieldType::kInt32;
  else return false;
  return true;
}

// Index of the first return labelled unknown whose x, y or z is NaN or Inf, else view.size().
std::size_t firstNonFinite(const PointCloudView& view, const GroundClassification& result) {
  const uint8_t* labels = result.labels.data();
  const std::size_t n = view.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (labels[i] == kLabelUnknown && !view.xyz(i).allFinite()) return i;
  }
  return n;
}

[[noreturn]] void nonFiniteError(std::size_t i) {
  throw py::value_error("points: row " + std::to_string(i) +
                        " has a NaN or Inf coordinate (pass allow_nonfinite=True to have such "
                        "returns labelled unknown, as the core does)");
}

// Views `points` for the core. Structured arrays (fields x, y, z and optionally ring,
// intensity, ...) and float32 C-contiguous (N, 3|4) arrays are viewed in place; other dtypes
// and layouts are converted to float32 C order once; a ring array is packed with x, y, z into
// one buffer (one copy). ValueError for anything the core cannot read.
void viewPoints(const py::object& points, const py::object& ring, NumpyCloud* cloud) {
  if (!py::isinstance<py::array>(points)) {
    throw py::value_error("points must be a NumPy array of shape (N, 3) or (N, 4), got " +
                          std::string(py::str(points.get_type())));
  }
  py::array arr = py::reinterpret_borrow<py::array>(points);
  const py::dtype dt = arr.dtype();
  CloudLayout& layout = cloud->layout;
  if (!dt.attr("names").is_none()) {
    if (!dt.attr("isnative").cast<bool>()) {
      throw py::value_error("a structured points array must be in the machine's byte order "
                            "(points.astype(points.dtype.newbyteorder('=')))");
    }
    // A structured array: its fields are the cloud's fields, read in place.
    if (arr.ndim() != 1) throw py::value_error("a structured points array must be 1-D, got shape " + shapeText(arr));
    if (!ring.is_none()) throw py::value_error("ring= is for (N, 3|4) arrays; a structured array carries a 'ring' field");
    if (!(arr.flags() & py::array::c_style)) arr = py::array::ensure(arr, py::array::c_style);
    const py::dict fields = dt.attr("fields");
    for (auto item : fields) {
      const py::tuple desc = py::reinterpret_borrow<py::tuple>(item.second);
      const py::dtype fdt = py::reinterpret_borrow<py::dtype>(desc[0]);
      FieldType type;
      if (!fieldTypeOf(fdt, &type)) continue;  // not a scalar number: not a field the core reads
      FieldDesc f;
      f.name = py::str(item.first);
      f.offset = desc[1].cast<uint32_t>();
      f.datatype = static_cast<uint8_t>(type);
      layout.fields.push_back(f);
    }
    layout.point_step = static_cast<uint32_t>(dt.itemsize());
  } else {
    if (arr.ndim() != 2 || (arr.shape(1) != 3 && arr.shape(1) != 4)) {
      throw py::value_error("points must have shape (N, 3) or (N, 4) (x, y, z[, intensity]), got " +
                            shapeText(arr));
    }
    if (!isNumeric(dt)) {
      throw py::value_error("points must hold numbers (float32 is read in place), got dtype " +
                            std::string(py::str(static_cast<const py::handle&>(dt))));
    }
    // The one conversion: other dtypes and layouts become float32 C order.
    if (!py::array_t<float, py::array::c_style>::check_(arr)) {
      arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(arr);
    }
    if (!arr) throw py::error_already_set();
    const uint32_t cols = static_cast<uint32_t>(arr.shape(1));
    const char* names[4] = {"x", "y", "z", "intensity"};
    for (uint32_t c = 0; c < cols; ++c) {
      FieldDesc f;
      f.name = names[c];
      f.offset = 4 * c;
      f.datatype = static_cast<uint8_t>(FieldType::kFloat32);
      layout.fields.push_back(f);
    }
    layout.point_step = 4 * cols;
  }
  const std::size_t n = static_cast<std::size_t>(arr.shape(0));
  if (n > 0xFFFFFFFFu) throw py::value_error("points: more than 2^32 - 1 points");
  cloud->size = n;
  layout.width = static_cast<uint32_t>(n);
  layout.height = 1;
  layout.row_step = layout.point_step * layout.width;
  const uint8_t* data = static_cast<const uint8_t*>(arr.data());
  std::size_t data_size = static_cast<std::size_t>(arr.nbytes());

  if (!ring.is_none()) {
    if (!py::isinstance<py::array>(ring)) throw py::value_error("ring must be a NumPy array of N integers");
    py::array r = py::reinterpret_borrow<py::array>(ring);
    if (r.ndim() != 1 || static_cast<std::size_t>(r.shape(0)) != n) {
      throw py::value_error("ring must have shape (" + std::to_string(n) + ",) like points, got " + shapeText(r));
    }
    if (r.dtype().kind() != 'i' && r.dtype().kind() != 'u') {
      throw py::value_error("ring must hold integers (laser numbers, 0 = lowest), got dtype " + std::string(py::str(static_cast<py::handle>(r.dtype()))));
    }
    auto rings = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(r);
    const int64_t* rv = rings.data();
    const float* xyz = static_cast<const float*>(arr.data());
    const std::size_t stride = layout.point_step / 4;
    // x, y, z float32 and ring uint16 in 16 bytes.
    cloud->packed.resize(16 * n);
    for (std::size_t i = 0; i < n; ++i) {
      if (rv[i] < 0 || rv[i] > 65535) {
        throw py::value_error("ring[" + std::to_string(i) + "] = " + std::to_string(rv[i]) + " is outside 0..65535");
      }
      uint8_t* dst = cloud->packed.data() + 16 * i;
      std::memcpy(dst, xyz + i * stride, 12);
      const uint16_t ring16 = static_cast<uint16_t>(rv[i]);
      std::memcpy(dst + 12, &ring16, 2);
      dst[14] = dst[15] = 0;
    }
    layout.fields.resize(3);
    FieldDesc f;
    f.name = "ring";
    f.offset = 12;
    f.datatype = static_cast<uint8_t>(FieldType::kUInt16);
    layout.fields.push_back(f);
    layout.point_step = 16;
    layout.row_step = 16 * layout.width;
    data = cloud->packed.data();
    data_size = cloud->packed.size();
  }
  cloud->array = arr;
  if (n == 0) return;
  std::string error;
  if (!PointCloudView::create(data, data_size, layout, &cloud->view, &error)) {
    throw py::value_error("points: " + error);
  }
}

SensorPose poseFrom(const py::object& sensor_height, const py::object& sensor_to_ground) {
  if (!sensor_to_ground.is_none()) {
    auto m = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(sensor_to_ground);
    if (!m || m.ndim() != 2 || m.shape(0) != 4 || m.shape(1) != 4) {
      throw py::value_error("sensor_to_ground must be a 4x4 homogeneous matrix");
    }
    Eigen::Matrix4f t;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = static_cast<float>(m.at(r, c));
    if (!t.allFinite()) throw py::value_error("sensor_to_ground holds NaN or Inf");
    SensorPose pose;
    pose.sensor_to_ground.matrix() = t;
    return pose;
  }
  const float h = sensor_height.is_none() ? kKittiSensorHeight : sensor_height.cast<float>();
  if (!std::isfinite(h) || h <= 0.f) throw py::value_error("sensor_height must be a finite height above the ground > 0 [m]");
  return SensorPose::fromHeight(h);
}

// Result buffers that NumPy has let go of, for the next call: a loop over scans then reuses
// warm memory as the C++ tools do (one GroundClassification per stream) instead of allocating
// and faulting in fresh pages for every scan.
struct ResultPool {
  std::mutex mutex;
  std::vector<std::unique_ptr<GroundClassification>> free;

  std::unique_ptr<GroundClassification> take() {
    std::lock_guard<std::mutex> lock(mutex);
    if (free.empty()) return std::make_unique<GroundClassification>();
    auto r = std::move(free.back());
    free.pop_back();
    return r;
  }
  void give(std::unique_ptr<GroundClassification> r) {
    std::lock_guard<std::mutex> lock(mutex);
    if (free.size() < 2) free.push_back(std::move(r));
  }
};

// What the labels and P(obstacle) arrays own: the core's result, returned to the pool when
// both arrays are gone.
struct PooledResult {
  std::shared_ptr<ResultPool> pool;
  std::unique_ptr<GroundClassification> result;
};

// A ground model of the core and the lock that keeps one call at a time in its workspace.
struct PyGroundModel {
  std::unique_ptr<GroundModel> model;
  std::mutex mutex;
  float sensor_height = kKittiSensorHeight;
  std::shared_ptr<ResultPool> pool = std::make_shared<ResultPool>();

  py::tuple segment(const py::object& points, const py::object& ring, const py::object& sensor_height,
                    const py::object& sensor_to_ground, bool allow_nonfinite) {
    NumpyCloud cloud;
    viewPoints(points, ring, &cloud);
    const SensorPose pose = poseFrom(sensor_height.is_none() ? py::cast(this->sensor_height) : sensor_height,
                                     sensor_to_ground);
    auto owned = std::make_unique<PooledResult>();
    owned->pool = pool;
    owned->result = pool->take();
    GroundClassification* result = owned->result.get();
    std::size_t non_finite = cloud.size;
    if (cloud.size > 0) {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex);
      model->classify(cloud.view, pose, result);
      // Every model labels a NaN/Inf return unknown (GroundModel::classify), so only the
      // unknown returns are looked at: no pass over all the points before the core call.
      if (!allow_nonfinite) non_finite = firstNonFinite(cloud.view, *result);
    }
    if (non_finite < cloud.size) nonFiniteError(non_finite);
    // NumPy owns the core's result buffers (no copy).
    if (cloud.size == 0) result->resize(0);
    GroundClassification* res = result;
    py::capsule owner(owned.release(), [](void* p) {
      std::unique_ptr<PooledResult> r(static_cast<PooledResult*>(p));
      r->pool->give(std::move(r->result));
    });
    const py::ssize_t n = static_cast<py::ssize_t>(res->size());
    py::array_t<uint8_t> labels({n}, {py::ssize_t(1)}, res->labels.data(), owner);
    py::array_t<float> p_obstacle({n}, {py::ssize_t(sizeof(float))}, res->p_obstacle.data(), owner);
    return py::make_tuple(labels, p_obstacle);
  }
};

// The lidar table's model of that name (lidar_models()); ValueError for another.
const LidarModel& lidarFrom(const std::string& name) {
  const LidarModel* m = findLidarModel(name);
  if (!m) throw py::value_error("unknown lidar model '" + name + "' (known: " + lidarModelNames() + ")");
  return *m;
}

// What both model constructors share: the sensor (a name of lidar_models(), None: HDL-64E) and
// the default sensor height, checked.
void setUp(PyGroundModel* g, float sensor_height, const py::object& lidar) {
  if (!lidar.is_none()) g->model->setLidarModel(lidarFrom(lidar.cast<std::string>()));
  if (!std::isfinite(sensor_height) || sensor_height <= 0.f) throw py::value_error("sensor_height must be > 0 [m]");
  g->sensor_height = sensor_height;
}

struct PyVerticalScanGround : PyGroundModel {
  VerticalScanGround* vs() { return static_cast<VerticalScanGround*>(model.get()); }
};

VerticalScanParams presetParams(const std::string& name) {
  if (name == "default" || name == "vertical_scan") return verticalScanDefaultParams();
  if (name == "thesis" || name == "vertical_scan_thesis") return verticalScanThesisParams();
  if (name == "bins" || name == "vertical_scan_bins") return verticalScanBinsParams();
  throw py::value_error("unknown vertical scan settings '" + name + "' (known: default, thesis, bins)");
}

const ParamInfo* paramInfo(const std::string& key) {
  for (const ParamInfo& p : verticalScanParamTable()) {
    if (key == p.name || key == p.member) return &p;
  }
  return nullptr;
}

py::object getParam(const VerticalScanParams& params, const std::string& key) {
  if (key == "laser_elevations_deg") return py::cast(params.laser_elevations_deg);
  const ParamInfo* info = paramInfo(key);
  double v = 0.0;
  if (!info || !getVerticalScanParam(params, key, &v)) throw py::key_error("unknown vertical scan parameter '" + key + "'");
  if (std::strcmp(info->type, "bool") == 0) return py::bool_(v != 0.0);
  if (std::strcmp(info->type, "int") == 0) return py::int_(static_cast<long>(v));
  char text[32];  // a float32 as its shortest decimal (0.35, not 0.3499999940395355)
  std::snprintf(text, sizeof text, "%.7g", v);
  return py::float_(std::strtod(text, nullptr));
}

void setParam(VerticalScanParams* params, const std::string& key, const py::object& value) {
  if (key == "laser_elevations_deg") {
    params->laser_elevations_deg = value.cast<std::vector<float>>();
    return;
  }
  double v;
  try {
    v = py::float_(value).cast<double>();
  } catch (const py::error_already_set&) {
    throw py::value_error("parameter '" + key + "' takes a number");
  }
  if (!paramInfo(key)) throw py::key_error("unknown vertical scan parameter '" + key + "'");
  std::string error;
  if (!setVerticalScanParam(params, key, v, &error)) throw py::value_error(error);
}

VerticalScanParams paramsFrom(const py::object& params) {
  if (params.is_none()) return verticalScanDefaultParams();
  if (py::isinstance<py::str>(params)) return presetParams(params.cast<std::string>());
  if (py::isinstance<VerticalScanParams>(params)) return params.cast<VerticalScanParams>();
  if (py::isinstance<py::dict>(params)) {
    VerticalScanParams p = verticalScanDefaultParams();
    for (auto item : py::reinterpret_borrow<py::dict>(params)) setParam(&p, py::str(item.first), py::reinterpret_borrow<py::object>(item.second));
    return p;
  }
  throw py::value_error("params must be None, a settings name ('default', 'thesis', 'bins'), a dict or VerticalScanParams");
}

sim::NoiseProfile noiseFrom(const std::string& name) {
  sim::NoiseProfile p;
  if (!sim::noiseProfileFromName(name, &p)) throw py::value_error("unknown noise profile '" + name + "' (datasheet, table4.1, none)");
  return p;
}

py::array_t<double> matrixOut(const Eigen::Isometry3d& t) {
  py::array_t<double> m({4, 4});
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.mutable_at(r, c) = t.matrix()(r, c);
  return m;
}

Eigen::Isometry3d matrixIn(const py::object& o, const char* what) {
  auto m = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(o);
  if (!m || m.ndim() != 2 || m.shape(0) != 4 || m.shape(1) != 4) {
    throw py::value_error(std::string(what) + " must be a 4x4 homogeneous matrix");
  }
  Eigen::Isometry3d t;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t.matrix()(r, c) = m.at(r, c);
  if (!t.matrix().allFinite()) throw py::value_error(std::string(what) + " holds NaN or Inf");
  return t;
}

// A simulated scan as (points (N, 4) float32 x y z intensity, ring (N,) uint16, truth (N,) uint8).
py::tuple scanOut(const sim::SimulatedScan& scan) {
  PointCloudView view;
  std::string error;
  if (!scan.cloud.view(&view, &error)) throw std::runtime_error(error);
  const py::ssize_t n = static_cast<py::ssize_t>(view.size());
  py::array_t<float> points({n, py::ssize_t(4)});
  py::array_t<uint16_t> ring(n);
  py::array_t<uint8_t> truth(n);
  float* p = points.mutable_data();
  uint16_t* r = ring.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Eigen::Vector3f q = view.xyz(i);
    p[4 * i] = q.x();
    p[4 * i + 1] = q.y();
    p[4 * i + 2] = q.z();
    p[4 * i + 3] = view.hasIntensity() ? view.intensity(i) : 0.f;
    r[i] = static_cast<uint16_t>(view.hasRing() ? view.ring(i) : 0);
  }
  std::memcpy(truth.mutable_data(), scan.truth.data(), scan.truth.size());
  return py::make_tuple(points, ring, truth);
}

struct PyWorld {
  sim::World world;
  std::string name;
  uint32_t seed = 0;
};

py::tuple simulate(const PyWorld& w, const py::object& pose, const sim::VelodyneModel& model, uint64_t seed) {
  Eigen::Isometry3d sensor;
  if (py::isinstance<py::float_>(pose) || py::isinstance<py::int_>(pose)) {
    // A time on the world's standard drive, the sensor 1.73 m above base_link (ground_eval's mount).
    const double t = pose.cast<double>();
    if (!std::isfinite(t) || t < 0.0 || t > w.world.driveDuration()) {
      throw py::value_error("drive time must lie in [0, " + std::to_string(w.world.driveDuration()) + "] s");
    }
    Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
    mount.translation().z() = kKittiSensorHeight;
    sensor = w.world.drivePose(t) * mount;
  } else {
    sensor = matrixIn(pose, "pose");
  }
  const std::string why = model.validate();
  if (!why.empty()) throw py::value_error("sensor model: " + why);
  sim::SimulatedScan scan;
  {
    py::gil_scoped_release release;
    sim::simulateVelodyneRevolution(w.world, sensor, model, seed, &scan);
  }
  return scanOut(scan);
}

std::unique_ptr<PyWorld> makeWorld(const std::string& name, uint32_t seed) {
  auto w = std::make_unique<PyWorld>();
  std::string error;
  bool ok;
  {
    py::gil_scoped_release release;
    ok = sim::makeStandardWorld(name, seed, &w->world, &error);
  }
  if (!ok) throw py::value_error(error);
  w->name = name;
  w->seed = seed;
  return w;
}

std::vector<uint16_t> classesFrom(const py::object& classes, std::size_t n) {
  if (!py::isinstance<py::array>(classes)) throw py::value_error("classes must be a NumPy array of SemanticKITTI labels");
  py::array a = py::reinterpret_borrow<py::array>(classes);
  if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
    throw py::value_error("classes must have shape (" + std::to_string(n) + ",) like points, got " + shapeText(a));
  }
  if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u') throw py::value_error("classes must hold integers");
  auto v = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  std::vector<uint16_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<uint16_t>(v.data()[i] & 0xFFFF);  // label & 0xFFFF
  return out;
}

std::vector<uint8_t> calledGroundFrom(const py::object& labels, std::size_t n) {
  if (!py::isinstance<py::array>(labels)) throw py::value_error("labels must be the NumPy array segment() returned");
  py::array a = py::reinterpret_borrow<py::array>(labels);
  if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
    throw py::value_error("labels must have shape (" + std::to_string(n) + ",) like points, got " + shapeText(a));
  }
  auto v = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
  std::vector<uint8_t> called(n);
  for (std::size_t i = 0; i < n; ++i) called[i] = v.data()[i] == kLabelGround;  // eval::calledGround
  return called;
}

eval::GroundProtocol protocolFrom(const std::string& p) {
  if (p == "A" || p == "a") return eval::GroundProtocol::kA;
  if (p == "B" || p == "b") return eval::GroundProtocol::kB;
  throw py::value_error("protocol must be 'A' (without vegetation) or 'B' (with vegetation)");
}

py::dict scoreDict(const eval::RealGroundScore& s) {
  py::dict d;
  d["precision"] = s.precision();
  d["recall"] = s.recall();
  d["f1"] = s.f1();
  d["obstacle_recall"] = s.obstacleRecall();
  d["true_ground"] = s.true_ground;
  d["false_ground"] = s.false_ground;
  d["missed_ground"] = s.missed_ground;
  d["true_obstacle"] = s.true_obstacle;
  d["dropped_ground"] = s.dropped_ground;
  return d;
}

[[noreturn]] void throwOSError(const std::string& message) {
  PyErr_SetString(PyExc_OSError, message.c_str());
  throw py::error_already_set();
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "ladar_perception's ROS-free core: ground extraction, the simulator, the SemanticKITTI scorer.";

  m.attr("LABEL_GROUND") = static_cast<int>(kLabelGround);
  m.attr("LABEL_OBSTACLE") = static_cast<int>(kLabelObstacle);
  m.attr("LABEL_UNKNOWN") = static_cast<int>(kLabelUnknown);
  m.def("ground_model_names", &groundModelNames,
        "Names of the ground models (ground_segment --list-methods), the default first.");

  // --- Parameters of the vertical scan method, from the core's parameter table.
  py::class_<VerticalScanParams> params(m, "VerticalScanParams",
      "Settings of the vertical scan method. Every row of the core's parameter table "
      "(vertical_scan_params.def; table() lists them) is an attribute and a key; values are "
      "checked against the table's range (ValueError). laser_elevations_deg: the laser table "
      "used to find a return's row when no ring is given (empty = HDL-64E).");
  params.def(py::init([](const std::string& name) { return presetParams(name); }), py::arg("settings") = "default",
             "Named settings: 'default', 'thesis' (the thesis's method) or 'bins'.");
  for (const ParamInfo& info : verticalScanParamTable()) {
    const std::string key = info.name;
    params.def_property(info.name, [key](const VerticalScanParams& p) { return getParam(p, key); },
                        [key](VerticalScanParams& p, const py::object& v) { setParam(&p, key, v); },
                        (std::string(info.meaning) + (info.unit[0] ? std::string(" [") + info.unit + "]" : "")).c_str());
  }
  params.def_property("laser_elevations_deg", [](const VerticalScanParams& p) { return p.laser_elevations_deg; },
                      [](VerticalScanParams& p, const std::vector<float>& v) { p.laser_elevations_deg = v; },
                      "Laser elevations [deg] for rows when no ring is given; empty = the HDL-64E table.");
  params.def("__getitem__", [](const VerticalScanParams& p, const std::string& k) { return getParam(p, k); });
  params.def("__setitem__", [](VerticalScanParams& p, const std::string& k, const py::object& v) { setParam(&p, k, v); });
  params.def("keys", [](const VerticalScanParams&) {
    std::vector<std::string> k;
    for (const ParamInfo& info : verticalScanParamTable()) k.push_back(info.name);
    return k;
  });
  params.def("to_dict", [](const VerticalScanParams& p) {
    py::dict d;
    for (const ParamInfo& info : verticalScanParamTable()) d[info.name] = getParam(p, info.name);
    d["laser_elevations_deg"] = p.laser_elevations_deg;
    return d;
  });
  params.def("copy", [](const VerticalScanParams& p) { return p; });
  params.def_static("table", []() {
    py::list rows;
    for (const ParamInfo& info : verticalScanParamTable()) {
      py::dict r;
      r["name"] = info.name;
      r["type"] = info.type;
      r["default"] = info.default_value;
      r["min"] = info.min;
      r["max"] = info.max;
      r["unit"] = info.unit;
      r["meaning"] = info.meaning;
      rows.append(r);
    }
    return rows;
  }, "The core's parameter table: name, type, default, min, max, unit, meaning per row.");
  params.def("__repr__", [](const VerticalScanParams& p) {
    return "VerticalScanParams(" + std::string(py::str(py::cast(p).attr("to_dict")())) + ")";
  });

  // --- Ground models.
  const char* segment_doc =
      "segment(points, ring=None, sensor_height=None, sensor_to_ground=None, allow_nonfinite=False)\n"
      "    -> (labels, p_obstacle)\n\n"
      "points: (N, 3) or (N, 4) array of x, y, z[, intensity] in the sensor frame [m]. A float32\n"
      "C-contiguous array is read in place (no copy); any other numeric dtype or memory layout\n"
      "(float64, a slice, Fortran order) is converted to float32 C order once per call. A NumPy\n"
      "structured array with fields x, y, z (and ring, intensity, ...) is read in place too.\n"
      "ring: optional (N,) integers, the laser of each return (0 = lowest); points and ring are\n"
      "then packed into one buffer (one copy). Without a ring, rows come from the elevation.\n"
      "sensor_height: height of the sensor above the ground [m] (default: the model's, 1.73, KITTI);\n"
      "sensor_to_ground: a 4x4 sensor-to-ground transform instead (ground frame z up).\n"
      "NaN or Inf coordinates raise ValueError unless allow_nonfinite=True (they are then unknown).\n"
      "Returns labels (N,) uint8 (LABEL_GROUND 0, LABEL_OBSTACLE 1, LABEL_UNKNOWN 2) and\n"
      "P(obstacle) (N,) float32, in input order. The core call runs without the GIL; one call at a\n"
      "time per model object (use one object per thread to run in parallel).";
  py::class_<PyGroundModel> model(m, "GroundModel", "A ground model of the core by name (ground_model_names()).");
  model.def(py::init([](const std::string& method, float sensor_height, const py::object& lidar) {
              auto g = std::make_unique<PyGroundModel>();
              std::string error;
              g->model = makeGroundModel(method, &error);
              if (!g->model) throw py::value_error(error);
              setUp(g.get(), sensor_height, lidar);
              return g;
            }),
            py::arg("method") = "vertical_scan", py::arg("sensor_height") = kKittiSensorHeight,
            py::arg("lidar") = py::none(),
            "lidar: a name of lidar_models() (the beam geometry; default the HDL-64E).");
  model.def_property_readonly("name", [](PyGroundModel& g) { return g.model->name(); });
  model.def_readwrite("sensor_height", &PyGroundModel::sensor_height, "Default sensor height above the ground [m].");
  model.def("segment", &PyGroundModel::segment, py::arg("points"), py::arg("ring") = py::none(),
            py::arg("sensor_height") = py::none(), py::arg("sensor_to_ground") = py::none(),
            py::arg("allow_nonfinite") = false, segment_doc);
  model.def("__repr__", [](PyGroundModel& g) { return "GroundModel('" + g.model->name() + "')"; });

  py::class_<PyVerticalScanGround, PyGroundModel> vsg(m, "VerticalScanGround",
      "The vertical scan ground model (thesis 3.3) with settings: VerticalScanGround(params=None) where "
      "params is None (default settings), 'default' | 'thesis' | 'bins', a dict of overrides of the "
      "default settings, or a VerticalScanParams.");
  vsg.def(py::init([](const py::object& params, float sensor_height, const py::object& lidar) {
            auto g = std::make_unique<PyVerticalScanGround>();
            g->model = makeVerticalScanModel(paramsFrom(params));
            setUp(g.get(), sensor_height, lidar);
            return g;
          }),
          py::arg("params") = py::none(), py::arg("sensor_height") = kKittiSensorHeight,
          py::arg("lidar") = py::none());
  vsg.def_property("params", [](PyVerticalScanGround& g) { return g.vs()->params(); },
                   [](PyVerticalScanGround& g, const py::object& p) {
                     const VerticalScanParams params = paramsFrom(p);
                     py::gil_scoped_release release;
                     std::lock_guard<std::mutex> lock(g.mutex);
                     g.vs()->setParams(params);
                   },
                   "A copy of the settings; assign a VerticalScanParams, a dict or a name to change them.");

  // --- The simulator.
  py::class_<sim::VelodyneModel>(m, "VelodyneModel", "A spinning multi-laser ladar of the simulator (HDL-64E by default).")
      .def(py::init([](const std::string& noise) { return sim::VelodyneModel::hdl64e(noiseFrom(noise)); }),
           py::arg("noise") = "datasheet")
      .def_static("hdl64e", [](const std::string& noise) { return sim::VelodyneModel::hdl64e(noiseFrom(noise)); },
                  py::arg("noise") = "datasheet", "HDL-64E; noise 'datasheet' (2 cm), 'table4.1' (0.2 m) or 'none'.")
      .def_static("named", [](const std::string& name, const std::string& noise) {
                    return sim::VelodyneModel::fromLidarModel(lidarFrom(name), noiseFrom(noise));
                  }, py::arg("name"), py::arg("noise") = "datasheet", "A model of lidar_models() by name.")
      .def_readwrite("elevations_deg", &sim::VelodyneModel::elevations_deg)
      .def_readwrite("azimuth_steps", &sim::VelodyneModel::azimuth_steps)
      .def_readwrite("rate_hz", &sim::VelodyneModel::rate_hz)
      .def_readwrite("min_range", &sim::VelodyneModel::min_range)
      .def_readwrite("max_range", &sim::VelodyneModel::max_range)
      .def_readwrite("noise_sigma", &sim::VelodyneModel::noise_sigma)
      .def_readwrite("start_azimuth", &sim::VelodyneModel::start_azimuth)
      .def_property_readonly("lasers", &sim::VelodyneModel::lasers)
      .def("validate", &sim::VelodyneModel::validate, "Empty when the model can be simulated, else the reason.");
  m.def("lidar_models", []() {
    py::list out;
    for (const LidarModel& l : lidarModels()) {
      py::dict d;
      d["name"] = l.name;
      d["description"] = l.description;
      d["source"] = l.source;
      d["elevations_deg"] = l.elevations_deg;
      d["azimuth_steps"] = l.azimuth_steps;
      d["rate_hz"] = l.rate_hz;
      d["min_range"] = l.min_range;
      d["max_range"] = l.max_range;
      d["noise_sigma"] = l.noise_sigma;
      d["mount_height"] = l.mount_height;
      out.append(d);
    }
    return out;
  }, "The lidar table (cloud/lidar_models.h): name, description, source, elevations_deg, ... per model.");
  m.def("hdl64e_elevations_deg", &sim::hdl64eElevationsDeg, "The HDL-64E's 64 laser elevations [deg], ring order.");

  py::class_<PyWorld>(m, "World", "A standard world of the simulator (world_names()), deterministic for a seed.")
      .def(py::init(&makeWorld), py::arg("name"), py::arg("seed") = 1)
      .def_readonly("name", &PyWorld::name)
      .def_property_readonly("drive_duration", [](const PyWorld& w) { return w.world.driveDuration(); })
      .def("drive_pose", [](const PyWorld& w, double t) { return matrixOut(w.world.drivePose(t)); }, py::arg("t"),
           "4x4 pose of base_link on the world's standard drive at time t [s].")
      .def("vehicle_pose", [](const PyWorld& w, double x, double y, double yaw) { return matrixOut(w.world.vehiclePose(x, y, yaw)); },
           py::arg("x"), py::arg("y"), py::arg("yaw"), "4x4 pose of base_link standing at (x, y) heading yaw.")
      .def("height", [](const PyWorld& w, double x, double y) { return w.world.height(x, y); }, py::arg("x"), py::arg("y"))
      .def("scan", [](const PyWorld& w, const py::object& pose, const py::object& model, uint64_t seed) {
             return simulate(w, pose, model.is_none() ? sim::VelodyneModel::hdl64e(sim::NoiseProfile::kDatasheet)
                                                      : model.cast<sim::VelodyneModel>(), seed);
           },
           py::arg("pose"), py::arg("model") = py::none(), py::arg("seed") = 0,
           "One revolution: pose is the sensor's 4x4 pose in the world, or a time [s] on the standard drive "
           "(sensor 1.73 m above base_link). Returns (points (N, 4) float32 x y z intensity in the sensor "
           "frame, ring (N,) uint16, truth (N,) uint8 surface class, see surface_classes()).");
  m.def("world_names", &sim::standardWorldNames, "Names of the simulator's standard worlds.");
  m.def("surface_classes", []() {
    py::list out;
    for (int c = 0; c < sim::kNumSurfaceClasses; ++c) {
      const auto sc = static_cast<sim::SurfaceClass>(c);
      out.append(py::make_tuple(c, sim::className(sc), sim::isGroundClass(sc)));
    }
    return out;
  }, "The simulator's truth classes: (code, name, is ground) per class.");

  // --- The SemanticKITTI scorer of ground_eval --semantickitti.
  m.def("score_ground", [](const py::object& points, const py::object& classes, const py::object& labels,
                           float sensor_height, const std::string& protocol) {
          NumpyCloud cloud;
          viewPoints(points, py::none(), &cloud);
          const std::vector<uint16_t> cls = classesFrom(classes, cloud.size);
          const std::vector<uint8_t> called = calledGroundFrom(labels, cloud.size);
          if (!std::isfinite(sensor_height) || sensor_height <= 0.f) throw py::value_error("sensor_height must be > 0 [m]");
          eval::RealGroundScore score;
          if (cloud.size > 0) {
            eval::scoreGroundScan(cloud.view, cls.data(), called.data(), sensor_height, protocolFrom(protocol), &score);
          }
          return scoreDict(score);
        },
        py::arg("points"), py::arg("classes"), py::arg("labels"), py::arg("sensor_height") = kKittiSensorHeight,
        py::arg("protocol") = "A",
        "Scores one scan's labels (segment()'s) against SemanticKITTI classes (the .label's uint32, or label & "
        "0xFFFF) under protocol 'A' or 'B' (ground_eval --semantickitti). Returns precision, recall, f1 "
        "(of the ground), obstacle_recall and the counts.");
  m.def("semantic_kitti_class_name", &eval::semantic_kitti::className, py::arg("semantic_class"));
  m.def("semantic_kitti_is_ground", &eval::semantic_kitti::isGroundClass, py::arg("semantic_class"));

  // --- Files and pictures.
  m.def("read_kitti_bin", [](const std::string& path) {
          auto cloud = std::make_unique<PackedCloud>();
          std::string error;
          if (!readKittiBin(path, cloud.get(), &error)) throwOSError(error);
          PackedCloud* c = cloud.release();
          py::capsule owner(c, [](void* p) { delete static_cast<PackedCloud*>(p); });
          const py::ssize_t n = static_cast<py::ssize_t>(c->size());
          return py::array_t<float>({n, py::ssize_t(4)}, {py::ssize_t(16), py::ssize_t(4)},
                                    reinterpret_cast<const float*>(c->data.data()), owner);
        },
        py::arg("path"), "A KITTI .bin as an (N, 4) float32 array x, y, z, intensity.");
  m.def("read_semantic_kitti_label", [](const std::string& path, std::size_t points) {
          std::vector<uint16_t> classes;
          std::string error;
          if (!eval::readSemanticClasses(path, points, &classes, &error)) throwOSError(error);
          return py::array_t<uint16_t>(static_cast<py::ssize_t>(classes.size()), classes.data());
        },
        py::arg("path"), py::arg("points"), "A SemanticKITTI .label's classes (label & 0xFFFF) as (N,) uint16.");
  m.def("write_png", [](const std::string& path, const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& rgb) {
          if (rgb.ndim() != 3 || rgb.shape(2) != 3 || rgb.shape(0) < 1 || rgb.shape(1) < 1) {
            throw py::value_error("rgb must have shape (height, width, 3)");
          }
          RgbImage img(static_cast<int>(rgb.shape(1)), static_cast<int>(rgb.shape(0)));
          std::memcpy(img.rgb.data(), rgb.data(), img.rgb.size());
          std::string error;
          if (!writePng(path, img, &error)) throwOSError(error);
        },
        py::arg("path"), py::arg("rgb"), "Writes an (H, W, 3) uint8 image with the core's PNG writer.");
  m.def("write_outcome_png", [](const std::string& path, const py::object& points, const py::object& classes,
                                const py::object& labels, float sensor_height) {
          NumpyCloud cloud;
          viewPoints(points, py::none(), &cloud);
          eval::LabelledFrame frame;
          frame.classes = classesFrom(classes, cloud.size);
          const std::vector<uint8_t> called = calledGroundFrom(labels, cloud.size);
          frame.cloud.layout = cloud.layout;
          const uint8_t* data = static_cast<const uint8_t*>(cloud.array.data());
          frame.cloud.data.assign(data, data + cloud.layout.point_step * cloud.size);
          std::string error;
          if (!eval::writeRealErrorPng(path, frame, called, sensor_height, &error)) throwOSError(error);
        },
        py::arg("path"), py::arg("points"), py::arg("classes"), py::arg("labels"),
        py::arg("sensor_height") = kKittiSensorHeight,
        "ground_eval's error picture under protocol A: correct ground and obstacle, missed ground, false ground.");
}
