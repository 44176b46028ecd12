#include "ladar_perception/sim/scan_simulator.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "ladar_perception/sim/random.h"
#include "ladar_perception/sim/ray_caster.h"

namespace ladar_perception {
namespace sim {

namespace {

constexpr double kTwoPi = 6.283185307179586;

inline void putFloat(uint8_t* p, float v) { std::memcpy(p, &v, 4); }

// Sets *layout to `make(0)`'s fields unless it already has them, then sizes it to n points, so
// a reused scan does not rebuild its field table.
template <typename MakeLayout>
void sizeLayout(CloudLayout* layout, uint32_t n, MakeLayout make) {
  const CloudLayout ref = make(0);
  bool same = layout->fields.size() == ref.fields.size() && layout->point_step == ref.point_step;
  for (std::size_t k = 0; same && k < ref.fields.size(); ++k) {
    same = layout->fields[k].name == ref.fields[k].name &&
           layout->fields[k].offset == ref.fields[k].offset &&
           layout->fields[k].datatype == ref.fields[k].datatype;
  }
  if (!same) *layout = ref;
  layout->width = n;
  layout->height = 1;
  layout->row_step = layout->point_step * n;
  layout->is_bigendian = false;
}

CloudLayout xyzLayout(uint32_t n) {
  CloudLayout l;
  l.width = n;
  l.height = 1;
  appendField(&l, "x", FieldType::kFloat32);
  appendField(&l, "y", FieldType::kFloat32);
  appendField(&l, "z", FieldType::kFloat32);
  return l;
}

void clearScan(SimulatedScan* out, CloudLayout (*make)(uint32_t)) {
  sizeLayout(&out->cloud.layout, 0, make);
  out->cloud.data.clear();
  out->truth.clear();
}

// Noisy range of ray `counter`, false when it falls outside [min, max].
inline bool noisyRange(double true_range, double sigma, double min_range, double max_range,
                       GaussianStream* noise, uint64_t counter, double* range) {
  double r = true_range;
  if (sigma > 0.0) r += sigma * noise->at(counter);
  *range = r;
  return r >= min_range && r <= max_range;
}

// Pass 2 of an organised model (Ouster's driver): row 0 is the top laser, column k the k-th
// firing; every slot is written, empty ones (no return in range) with x = y = z = 0 and truth
// kNone. The same noise per ray as the returns-only output.
void writeOrganised(const VelodyneModel& model, int lasers, int steps, const std::vector<double>& cos_el,
                    const std::vector<double>& sin_el, const std::vector<double>& cos_az,
                    const std::vector<double>& sin_az, const std::vector<double>& hit_range,
                    const std::vector<float>& hit_cos, const std::vector<uint8_t>& hit_class,
                    uint64_t seed, SimulatedScan* out) {
  const CloudLayout ref = ousterLayout(static_cast<uint32_t>(lasers), static_cast<uint32_t>(steps));
  if (out->cloud.layout.point_step != ref.point_step || out->cloud.layout.fields.size() != ref.fields.size()) {
    out->cloud.layout = ref;
  }
  out->cloud.layout.width = ref.width;
  out->cloud.layout.height = ref.height;
  out->cloud.layout.row_step = ref.row_step;
  const std::size_t slots = static_cast<std::size_t>(lasers) * steps;
  const uint32_t step_bytes = ref.point_step;
  out->cloud.data.assign(slots * step_bytes, 0);
  out->truth.assign(slots, static_cast<uint8_t>(SurfaceClass::kNone));
  const double dt = model.period() / steps;
  GaussianStream noise(seed);
  for (int row = 0; row < lasers; ++row) {
    const int l = lasers - 1 - row;
    for (int k = 0; k < steps; ++k) {
      const std::size_t slot = static_cast<std::size_t>(row) * steps + k;
      uint8_t* dst = out->cloud.data.data() + slot * step_bytes;
      const uint16_t ring = static_cast<uint16_t>(row);
      std::memcpy(dst + 26, &ring, 2);
      const uint32_t t_ns = static_cast<uint32_t>(k * dt * 1e9);
      std::memcpy(dst + 20, &t_ns, 4);
      const std::size_t ray = static_cast<std::size_t>(k) * lasers + l;
      double r;
      if (hit_range[ray] < 0.0 ||
          !noisyRange(hit_range[ray], model.noise_sigma, model.min_range, model.max_range, &noise, ray, &r)) {
        continue;
      }
      const double dx = cos_el[l] * cos_az[k], dy = cos_el[l] * sin_az[k], dz = sin_el[l];
      putFloat(dst + 0, static_cast<float>(dx * r));
      putFloat(dst + 4, static_cast<float>(dy * r));
      putFloat(dst + 8, static_cast<float>(dz * r));
      const float intensity = returnIntensity(static_cast<SurfaceClass>(hit_class[ray]), hit_cos[ray]);
      putFloat(dst + 16, intensity);
      const uint16_t reflectivity = static_cast<uint16_t>(intensity);
      std::memcpy(dst + 24, &reflectivity, 2);
      const uint32_t range_mm = static_cast<uint32_t>(r * 1000.0);
      std::memcpy(dst + 32, &range_mm, 4);
      out->truth[slot] = hit_class[ray];
    }
  }
}

void simulateVelodyne(const World& world, const Eigen::Isometry3d& start,
                      const Eigen::Isometry3d* end, const VelodyneModel& model, uint64_t seed,
                      SimulatedScan* out) {
  if (!model.validate().empty() || !world.finalized()) {
    clearScan(out, velodyneXYZIRTLayout);
    return;
  }
  const int lasers = model.lasers();
  const int steps = model.azimuth_steps;
  // Per-laser trigonometry, kept between calls on this thread (no per-scan allocation once
  // warm).
  thread_local std::vector<double> cos_el, sin_el;
  cos_el.resize(lasers);
  sin_el.resize(lasers);
  for (int l = 0; l < lasers; ++l) {
    const double e = model.elevations_deg[l] * M_PI / 180.0;
    cos_el[l] = std::cos(e);
    sin_el[l] = std::sin(e);
  }
  // Per-step azimuth and (for a moving sensor) pose.
  thread_local std::vector<double> cos_az, sin_az;
  thread_local std::vector<Eigen::Matrix3d> rotations;
  thread_local std::vector<Eigen::Vector3d> origins;
  cos_az.resize(steps);
  sin_az.resize(steps);
  for (int k = 0; k < steps; ++k) {
    const double az = model.start_azimuth - kTwoPi * k / steps;  // clockwise from above
    cos_az[k] = std::cos(az);
    sin_az[k] = std::sin(az);
  }
  if (end) {
    const Eigen::Quaterniond q0(start.linear()), q1(end->linear());
    rotations.resize(steps);
    origins.resize(steps);
    for (int k = 0; k < steps; ++k) {
      const double f = static_cast<double>(k) / steps;
      rotations[k] = q0.slerp(f, q1).toRotationMatrix();
      origins[k] = (1.0 - f) * start.translation() + f * end->translation();
    }
  }
  // Pass 1 casts laser by laser: consecutive rays then land in neighbouring cells, which keeps
  // the height field in cache (firing order jumps between near and far ranges).
  const std::size_t max_points = model.raysPerRevolution();
  thread_local std::vector<double> hit_range;  // < 0: no hit
  thread_local std::vector<float> hit_cos;
  thread_local std::vector<uint8_t> hit_class;
  hit_range.resize(max_points);
  hit_cos.resize(max_points);
  hit_class.resize(max_points);
  const Eigen::Matrix3d R0 = start.linear();
  const Eigen::Vector3d o0 = start.translation();
  const int start_level = startLevelFor(world, o0);
  RayHit hit;
  for (int l = 0; l < lasers; ++l) {
    for (int k = 0; k < steps; ++k) {
      const std::size_t ray = static_cast<std::size_t>(k) * lasers + l;
      const Eigen::Vector3d ds(cos_el[l] * cos_az[k], cos_el[l] * sin_az[k], sin_el[l]);
      const Eigen::Vector3d dw = end ? Eigen::Vector3d(rotations[k] * ds) : Eigen::Vector3d(R0 * ds);
      if (!castRay(world, end ? origins[k] : o0, dw, model.max_range, end ? -1 : start_level, &hit)) {
        hit_range[ray] = -1.0;
        continue;
      }
      hit_range[ray] = hit.range;
      hit_cos[ray] = static_cast<float>(std::abs(hit.normal.cast<double>().dot(dw)));
      hit_class[ray] = static_cast<uint8_t>(hit.surface);
    }
  }
  if (model.organised) {
    writeOrganised(model, lasers, steps, cos_el, sin_el, cos_az, sin_az, hit_range, hit_cos, hit_class,
                   seed, out);
    return;
  }
  // Pass 2 writes the returns in firing order (azimuth step, then ring) with their noise.
  const uint32_t step_bytes = 22;
  out->cloud.data.resize(max_points * step_bytes);
  out->truth.resize(max_points);
  uint8_t* dst = out->cloud.data.data();
  uint8_t* truth = out->truth.data();
  std::size_t count = 0;
  const double dt = model.period() / steps;
  GaussianStream noise(seed);
  for (int k = 0; k < steps; ++k) {
    const float time = static_cast<float>(k * dt);
    for (int l = 0; l < lasers; ++l) {
      const std::size_t ray = static_cast<std::size_t>(k) * lasers + l;
      if (hit_range[ray] < 0.0) continue;
      double r;
      if (!noisyRange(hit_range[ray], model.noise_sigma, model.min_range, model.max_range, &noise, ray, &r)) {
        continue;
      }
      const double dx = cos_el[l] * cos_az[k], dy = cos_el[l] * sin_az[k], dz = sin_el[l];
      putFloat(dst + 0, static_cast<float>(dx * r));
      putFloat(dst + 4, static_cast<float>(dy * r));
      putFloat(dst + 8, static_cast<float>(dz * r));
      putFloat(dst + 12, returnIntensity(static_cast<SurfaceClass>(hit_class[ray]), hit_cos[ray]));
      const uint16_t ring = static_cast<uint16_t>(l);
      std::memcpy(dst + 16, &ring, 2);
      putFloat(dst + 18, time);
      dst += step_bytes;
      truth[count++] = hit_class[ray];
    }
  }
  out->cloud.data.resize(count * step_bytes);
  out->truth.resize(count);
  sizeLayout(&out->cloud.layout, static_cast<uint32_t>(count), velodyneXYZIRTLayout);
}

}  // namespace

float returnIntensity(SurfaceClass c, float cos_incidence) {
  static const float kReflectivity[kNumSurfaceClasses] = {
      0.20f,  // road
      0.35f,  // sidewalk
      0.25f,  // terrain
      0.40f,  // curb
      0.60f,  // car
      0.45f,  // wall
      0.30f,  // pole
      0.35f,  // person
      0.12f,  // pothole (wet, dark)
  };
  const int k = static_cast<int>(c);
  const float refl = k < kNumSurfaceClasses ? kReflectivity[k] : 0.f;
  return 255.f * refl * (0.3f + 0.7f * std::min(1.f, std::max(0.f, cos_incidence)));
}

void simulateVelodyneRevolution(const World& world, const Eigen::Isometry3d& sensor_in_world,
                                const VelodyneModel& model, uint64_t seed, SimulatedScan* out) {
  simulateVelodyne(world, sensor_in_world, nullptr, model, seed, out);
}

void simulateVelodyneRevolution(const World& world, const Eigen::Isometry3d& sensor_at_start,
                                const Eigen::Isometry3d& sensor_at_end, const VelodyneModel& model,
                                uint64_t seed, SimulatedScan* out) {
  simulateVelodyne(world, sensor_at_start, &sensor_at_end, model, seed, out);
}

void simulateSickScan(const World& world, const Eigen::Isometry3d& sensor_in_world,
                      const SickModel& model, uint64_t seed, SimulatedLaserScan* out) {
  const int beams = model.validate().empty() && world.finalized() ? model.beams() : 0;
  out->angle_min = static_cast<float>(model.angle_min);
  out->angle_increment = static_cast<float>(model.angle_increment);
  out->angle_max = static_cast<float>(model.angle_min + (beams > 0 ? beams - 1 : 0) * model.angle_increment);
  out->scan_time = static_cast<float>(1.0 / model.rate_hz);
  // The LMS-291 sweeps a full circle per scan period and measures over its 180 degrees.
  out->time_increment = static_cast<float>(model.angle_increment / kTwoPi / model.rate_hz);
  out->range_min = static_cast<float>(model.min_range);
  out->range_max = static_cast<float>(model.max_range);
  out->ranges.assign(beams, std::numeric_limits<float>::infinity());
  out->intensities.assign(beams, 0.f);
  out->beam_truth.assign(beams, static_cast<uint8_t>(SurfaceClass::kNone));
  SimulatedScan& pts = out->points;
  pts.cloud.data.resize(static_cast<std::size_t>(beams) * 16);
  pts.truth.resize(beams);
  uint8_t* dst = pts.cloud.data.data();
  std::size_t count = 0;
  const Eigen::Matrix3d R = sensor_in_world.linear();
  const Eigen::Vector3d origin = sensor_in_world.translation();
  GaussianStream noise(seed);
  RayHit hit;
  for (int b = 0; b < beams; ++b) {
    const double a = model.angle_min + b * model.angle_increment;
    const Eigen::Vector3d ds(std::cos(a), std::sin(a), 0.0);
    const Eigen::Vector3d dw = R * ds;
    if (!castRay(world, origin, dw, model.max_range, &hit)) continue;
    double r;
    if (!noisyRange(hit.range, model.noise_sigma, model.min_range, model.max_range, &noise, b, &r)) continue;
    const float intensity =
        returnIntensity(hit.surface, static_cast<float>(std::abs(hit.normal.cast<double>().dot(dw))));
    out->ranges[b] = static_cast<float>(r);
    out->intensities[b] = intensity;
    out->beam_truth[b] = static_cast<uint8_t>(hit.surface);
    putFloat(dst + 0, static_cast<float>(ds.x() * r));
    putFloat(dst + 4, static_cast<float>(ds.y() * r));
    putFloat(dst + 8, 0.f);
    putFloat(dst + 12, intensity);
    dst += 16;
    pts.truth[count++] = static_cast<uint8_t>(hit.surface);
  }
  pts.cloud.data.resize(count * 16);
  pts.truth.resize(count);
  sizeLayout(&pts.cloud.layout, static_cast<uint32_t>(count), xyziLayout);
}

void simulateStereoFrame(const World& world, const Eigen::Isometry3d& sensor_in_world,
                         const StereoModel& model, uint64_t seed, SimulatedScan* out) {
  if (!model.validate().empty() || !world.finalized()) {
    clearScan(out, xyzLayout);
    return;
  }
  const std::size_t max_points = static_cast<std::size_t>(model.columns) * model.rows;
  out->cloud.data.resize(max_points * 12);
  out->truth.resize(max_points);
  uint8_t* dst = out->cloud.data.data();
  std::size_t count = 0;
  const Eigen::Matrix3d R = sensor_in_world.linear();
  const Eigen::Vector3d origin = sensor_in_world.translation();
  // Pinhole image plane at x = 1: pixel centres spread over the field of view.
  const double half_w = std::tan(0.5 * model.horizontal_fov), half_h = std::tan(0.5 * model.vertical_fov);
  GaussianStream noise(seed);
  RayHit hit;
  const double fb = model.focalPixels() * model.baseline;  // disparity * depth [px m]
  const double sigma_d = model.disparitySigma();
  const double step = model.disparity_step_px;
  for (int row = 0; row < model.rows; ++row) {
    const double v = half_h * (1.0 - 2.0 * (row + 0.5) / model.rows);  // top row looks up
    for (int col = 0; col < model.columns; ++col) {
      const double u = half_w * (1.0 - 2.0 * (col + 0.5) / model.columns);  // left column: +y
      const Eigen::Vector3d ds = Eigen::Vector3d(1.0, u, v).normalized();
      const Eigen::Vector3d dw = R * ds;
      if (!castRay(world, origin, dw, model.max_range, &hit)) continue;
      // Depth from a noisy, sub-pixel-rounded disparity, moved along the ray (StereoModel).
      double r = hit.range;
      if (sigma_d > 0.0) {
        const double depth = hit.range * ds.x();
        double d = fb / depth + sigma_d * noise.at(static_cast<uint64_t>(row) * model.columns + col);
        if (step > 0.0) d = step * std::round(d / step);
        if (!(d > 0.0)) continue;  // beyond infinity: the matcher gives no depth
        r = hit.range * (fb / d) / depth;
      }
      if (r < model.min_range || r > model.max_range) continue;
      putFloat(dst + 0, static_cast<float>(ds.x() * r));
      putFloat(dst + 4, static_cast<float>(ds.y() * r));
      putFloat(dst + 8, static_cast<float>(ds.z() * r));
      dst += 12;
      out->truth[count++] = static_cast<uint8_t>(hit.surface);
    }
  }
  out->cloud.data.resize(count * 12);
  out->truth.resize(count);
  sizeLayout(&out->cloud.layout, static_cast<uint32_t>(count), xyzLayout);
}

}  // namespace sim
}  // namespace ladar_perception
