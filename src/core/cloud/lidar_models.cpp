#include "ladar_perception/cloud/lidar_models.h"

#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {

namespace {

// n beams evenly spaced from lo to hi [deg] (Ouster's uniform beam spacing; the HDL-32E).
std::vector<float> evenly(int n, float lo, float hi) {
  std::vector<float> deg(n);
  for (int k = 0; k < n; ++k) deg[k] = lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n - 1);
  return deg;
}

LidarModel velodyne(const char* name, const char* description, const char* source,
                    std::vector<float> elevations, int azimuth_steps, double min_range,
                    double max_range, double noise_sigma, double mount_height) {
  LidarModel m;
  m.name = name;
  m.description = description;
  m.source = source;
  m.elevations_deg = std::move(elevations);
  std::sort(m.elevations_deg.begin(), m.elevations_deg.end());
  m.azimuth_steps = azimuth_steps;
  m.min_range = min_range;
  m.max_range = max_range;
  m.noise_sigma = noise_sigma;
  m.mount_height = mount_height;
  m.ring_order = RingOrder::kBottomUp;
  m.organised = false;
  return m;
}

LidarModel ouster(const char* name, const char* description, const char* source, int beams,
                  float half_fov_deg, double min_range, double max_range) {
  LidarModel m = velodyne(name, description, source, evenly(beams, -half_fov_deg, half_fov_deg),
                          1024, min_range, max_range, 0.03, 1.8);
  m.ring_order = RingOrder::kTopDown;
  m.organised = true;
  return m;
}

std::vector<LidarModel> makeTable() {
  std::vector<LidarModel> t;
  // Nominal geometry; a real unit's beams deviate by tenths of a degree (its calibration
  // file has the exact angles: give them as laser_elevations_deg).
  t.push_back(velodyne("hdl64e", "Velodyne HDL-64E",
                       "HDL-64E S2 data sheet and user's manual: +2.0 to -24.8 deg, two blocks of 32 "
                       "beams (1/3 deg, then about 1/2 deg); 0.09 deg at 10 Hz (1800 firings used); "
                       "120 m; accuracy < 2 cm",
                       hdl64eElevationsDeg(), 1800, 0.9, 120.0, 0.02, 1.73));
  t.push_back(velodyne("hdl32e", "Velodyne HDL-32E",
                       "HDL-32E data sheet and user's manual (laser vertical angle table): +10.67 to "
                       "-30.67 deg in 1.33 deg steps; 0.16 deg at 10 Hz; 1-100 m; accuracy +-2 cm",
                       evenly(32, -30.67f, 10.67f), 2170, 1.0, 100.0, 0.02, 1.8));
  t.push_back(velodyne("vlp16", "Velodyne VLP-16 (Puck)",
                       "VLP-16 data sheet and user's manual: +-15 deg in 2 deg steps; 0.2 deg at "
                       "10 Hz; up to 100 m; accuracy +-3 cm",
                       evenly(16, -15.f, 15.f), 1800, 0.5, 100.0, 0.03, 1.0));
  t.push_back(velodyne("vlp32c", "Velodyne VLP-32C (Ultra Puck)",
                       "VLP-32C user's manual (laser vertical angle table): -25 to +15 deg, "
                       "densest (1/3 deg) around the horizon; 0.2 deg at 10 Hz; 200 m; "
                       "accuracy +-3 cm",
                       {-25.f, -15.639f, -11.31f, -8.843f, -7.254f, -6.148f, -5.333f, -4.667f,
                        -4.f, -3.667f, -3.333f, -3.f, -2.667f, -2.333f, -2.f, -1.667f,
                        -1.333f, -1.f, -0.667f, -0.333f, 0.f, 0.333f, 0.667f, 1.f,
                        1.333f, 1.667f, 2.333f, 3.333f, 4.667f, 7.f, 10.333f, 15.f},
                       1800, 0.5, 200.0, 0.03, 1.8));
  const char* os1 = "Ouster OS1 data sheet (rev 6 and later hardware): 45 deg vertical field of view "
                    "(+-22.5 deg), uniform beam spacing; 1024 columns at 10 Hz; 0.5-120 m; "
                    "precision 1-3 cm";
  t.push_back(ouster("os1_32", "Ouster OS1-32", os1, 32, 22.5f, 0.5, 120.0));
  t.push_back(ouster("os1_64", "Ouster OS1-64", os1, 64, 22.5f, 0.5, 120.0));
  t.push_back(ouster("os1_128", "Ouster OS1-128", os1, 128, 22.5f, 0.5, 120.0));
  t.push_back(ouster("os2_128", "Ouster OS2-128",
                     "Ouster OS2 data sheet (rev 6 and later hardware): 22.5 deg vertical field of "
                     "view (+-11.25 deg), uniform beam spacing; 1024 columns at 10 Hz; 1-240 m; "
                     "precision 2-5 cm",
                     128, 11.25f, 1.0, 240.0));
  return t;
}

}  // namespace

float LidarModel::minSpacingDeg() const {
  float gap = 0.f;
  for (std::size_t k = 1; k < elevations_deg.size(); ++k) {
    const float d = elevations_deg[k] - elevations_deg[k - 1];
    if (k == 1 || d < gap) gap = d;
  }
  return gap;
}

const std::vector<LidarModel>& lidarModels() {
  static const std::vector<LidarModel> table = makeTable();
  return table;
}

const LidarModel* findLidarModel(const std::string& name) {
  for (const LidarModel& m : lidarModels()) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

std::string lidarModelNames() {
  std::string s;
  for (const LidarModel& m : lidarModels()) s += (s.empty() ? "" : ", ") + m.name;
  return s;
}

bool lidarModelFromElevations(const std::vector<float>& elevations_deg, LidarModel* model,
                              std::string* error) {
  std::ostringstream why;
  std::vector<float> el = elevations_deg;
  std::sort(el.begin(), el.end());
  if (el.empty()) why << "laser_elevations_deg is empty";
  else if (el.size() > 128) why << "laser_elevations_deg has " << el.size() << " beams, at most 128";
  for (std::size_t k = 0; why.str().empty() && k < el.size(); ++k) {
    if (!std::isfinite(el[k]) || std::fabs(el[k]) >= 90.f) {
      why << "laser_elevations_deg has " << el[k] << ", outside (-90, 90) deg";
    } else if (k > 0 && el[k] - el[k - 1] < 0.005f) {
      why << "laser_elevations_deg has two beams closer than 0.005 deg (" << el[k - 1] << ", "
          << el[k] << ")";
    }
  }
  if (!why.str().empty()) {
    if (error) *error = why.str();
    return false;
  }
  LidarModel m;
  m.name = "custom";
  m.description = "laser_elevations_deg (" + std::to_string(el.size()) + " beams)";
  m.source = "user table";
  m.elevations_deg = std::move(el);
  *model = std::move(m);
  return true;
}

bool measureRingElevations(const PointCloudView& view, std::vector<float>* elevations_deg,
                           std::string* error) {
  if (!view.hasRing()) {
    if (error) *error = "the cloud has no ring or channel field and is not organised";
    return false;
  }
  std::vector<std::vector<float>> per_ring;
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    const float r = std::sqrt(p.x() * p.x() + p.y() * p.y());
    const int ring = view.ring(i);
    if (!p.allFinite() || !(r > 0.5f) || ring < 0) continue;
    if (ring >= 128) {
      if (error) *error = "ring " + std::to_string(ring) + " is beyond the 128 beams a table can hold";
      return false;
    }
    if (ring >= static_cast<int>(per_ring.size())) per_ring.resize(ring + 1);
    per_ring[ring].push_back(std::atan2(p.z(), r) * 57.29578f);
  }
  const int rings = static_cast<int>(per_ring.size());
  std::vector<float> el(rings, 0.f);
  std::vector<bool> known(rings, false);
  int known_count = 0;
  for (int k = 0; k < rings; ++k) {
    std::vector<float>& v = per_ring[k];
    if (v.size() < 10) continue;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    el[k] = v[v.size() / 2];
    known[k] = true;
    ++known_count;
  }
  if (rings < 2 || 2 * known_count < rings) {
    if (error) *error = std::to_string(known_count) + " of " + std::to_string(rings) + " rings have 10 returns or more";
    return false;
  }
  // Rings without returns (sky beams) between or beyond the measured ones: linear in the ring.
  for (int k = 0; k < rings; ++k) {
    if (known[k]) continue;
    int lo = k - 1, hi = k + 1;
    while (lo >= 0 && !known[lo]) --lo;
    while (hi < rings && !known[hi]) ++hi;
    if (lo >= 0 && hi < rings) {
      el[k] = el[lo] + (el[hi] - el[lo]) * static_cast<float>(k - lo) / static_cast<float>(hi - lo);
    } else {
      // Beyond the last measured ring: continue the spacing of the two nearest measured ones.
      const int a = lo >= 0 ? lo : hi;
      int b = a + (lo >= 0 ? -1 : 1);
      while (b >= 0 && b < rings && !known[b]) b += lo >= 0 ? -1 : 1;
      const float step = (b >= 0 && b < rings) ? (el[a] - el[b]) / static_cast<float>(a - b) : 0.5f;
      el[k] = el[a] + step * static_cast<float>(k - a);
    }
    known[k] = true;
  }
  // Ascending in ring order (reversed for a driver that numbers from the top), each beam at
  // least 0.01 deg above the one below (the median of a beam whose returns a tilt spreads can
  // come out level with its neighbour's).
  if (el.front() > el.back()) std::reverse(el.begin(), el.end());
  for (int k = 1; k < rings; ++k) el[k] = std::max(el[k], el[k - 1] + 0.01f);
  *elevations_deg = el;
  return true;
}

std::string checkCloudAgainstLidarModel(const PointCloudView& view, const LidarModel& lidar) {
  const std::size_t n = view.size();
  const int beams = lidar.beams();
  if (beams == 0) return "";
  char buf[256];
  if (view.hasRing()) {
    std::bitset<1024> seen;
    int max_ring = -1;
    std::size_t valid = 0;
    for (std::size_t i = 0; i < n; i += 7) {
      if (!view.xyz(i).allFinite()) continue;
      const int ring = view.ring(i);
      if (ring < 0) continue;
      ++valid;
      max_ring = std::max(max_ring, ring);
      if (ring < 1024) seen.set(static_cast<std::size_t>(ring));
    }
    if (valid < 200) return "";
    const int distinct = static_cast<int>(seen.count());
    const char* source = ringSourceName(view.ringSource());
    if (distinct > beams || max_ring >= 2 * beams || 2 * distinct < beams) {
      std::snprintf(buf, sizeof(buf),
                    "cloud has %d distinct rings (%s, highest %d), sensor_model %s has %d beams", distinct,
                    source, max_ring, lidar.name.c_str(), beams);
      return buf;
    }
    return "";
  }
  // Elevation histogram in 0.5 degree cells over (-90, 90), every 31st return (an atan2 each).
  std::array<uint32_t, 360> hist{};
  std::size_t valid = 0;
  for (std::size_t i = 0; i < n; i += 31) {
    const Eigen::Vector3f p = view.xyz(i);
    const float r = std::sqrt(p.x() * p.x() + p.y() * p.y());
    if (!p.allFinite() || !(r > 0.5f)) continue;
    const float deg = std::atan2(p.z(), r) * 57.29578f;
    const int cell = std::min(359, std::max(0, static_cast<int>((deg + 90.f) * 2.f)));
    ++hist[cell];
    ++valid;
  }
  if (valid < 200) return "";
  const std::size_t lo_count = valid / 50, hi_count = valid - valid / 50;
  std::size_t acc = 0;
  int lo = -1, hi = -1;
  for (int c = 0; c < 360; ++c) {
    acc += hist[c];
    if (lo < 0 && acc > lo_count) lo = c;
    if (hi < 0 && acc >= hi_count) hi = c;
  }
  const float lo_deg = lo * 0.5f - 90.f, hi_deg = (hi + 1) * 0.5f - 90.f;
  const float bottom = lidar.elevations_deg.front(), top = lidar.elevations_deg.back();
  if (hi_deg > top + 3.f || lo_deg < bottom - 3.f) {
    std::snprintf(buf, sizeof(buf),
                  "cloud's returns span %+.1f..%+.1f deg of elevation (2nd-98th percentile), sensor_model %s's "
                  "%d beams span %+.1f..%+.1f deg",
                  lo_deg, hi_deg, lidar.name.c_str(), beams, bottom, top);
    return buf;
  }
  return "";
}

}  // namespace ladar_perception
