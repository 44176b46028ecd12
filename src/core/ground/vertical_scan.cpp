// Vertical scan ground extraction (thesis 3.3; equations restated in algorithms.md).
#include "ladar_perception/ground/vertical_scan.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {

namespace {

constexpr uint32_t kInvalidBin = std::numeric_limits<uint32_t>::max();
constexpr float kPi = 3.14159265358979f;
constexpr int kMaxRingRows = 128;   // rows of the bin grid when the cloud carries `ring`
constexpr float kMinR = 0.05f;      // horizontal distance floor for Height / r [m]
constexpr int kAtanCells = 2048;    // atan LUT cells on [0, 1]: < 0.015 deg error

// Sorts keys ascending (small arrays: a bin's points).
template <typename K>
inline void insertionSort(K* keys, int n) {
  for (int i = 1; i < n; ++i) {
    const K k = keys[i];
    int j = i - 1;
    while (j >= 0 && keys[j] > k) {
      keys[j + 1] = keys[j];
      --j;
    }
    keys[j + 1] = k;
  }
}

// A point's sort key within its bin: the bits of r > 0 (which order like the floats) above the
// point index, so one integer comparison orders by r and then by input order.
inline uint64_t rangeKey(float r, uint32_t index) {
  uint32_t bits;
  std::memcpy(&bits, &r, 4);
  return (static_cast<uint64_t>(bits) << 32) | index;
}

// Sorts keys ascending and permutes vals alike (small, nearly sorted arrays).
template <typename V>
inline void insertionSort(float* keys, V* vals, int n) {
  for (int i = 1; i < n; ++i) {
    const float k = keys[i];
    const V v = vals[i];
    int j = i - 1;
    while (j >= 0 && keys[j] > k) {
      keys[j + 1] = keys[j];
      vals[j + 1] = vals[j];
      --j;
    }
    keys[j + 1] = k;
    vals[j + 1] = v;
  }
}

}  // namespace

// --------------------------------------------------------------------------------------------
// Settings by name.

VerticalScanParams verticalScanThesisParams() {
  VerticalScanParams p;
  p.column_width_deg = 1.5f;
  p.iterations = 9;
  p.weight_bias = 0.02f;
  p.ground_slope_min = -0.35f;
  p.ground_slope_max = 0.35f;
  p.tolerances = ObstacleToleranceParams();
  p.bend_ground_line = false;
  p.couple_columns = false;
  // Eq 3.15 as the thesis writes it takes |GndError|: returns below the line score too.
  p.negative_obstacles = true;
  p.negative_gnd_error_max = 0.f;
  p.vertical_surfaces = false;
  return p;
}

VerticalScanParams verticalScanDefaultParams() {
  VerticalScanParams p;
  // Tuned on the simulator's urban, hillside and potholes worlds (ground_eval): the bent line
  // tracks the terrain, so GndErrorMax can be small and the SlopeError factor (which shrinks
  // a fixed height with range, eq 3.15) saturates early.
  p.tolerances.gnd_error_max_base = 0.3f;
  p.tolerances.gnd_error_max_per_m = 0.005f;
  p.tolerances.slope_error_max_base = 0.004f;
  p.tolerances.slope_error_max_per_m = 0.f;
  p.tolerances.obstacle_threshold = 0.5f;
  p.negative_gnd_error_max = 0.05f;
  p.track_max_drop = 0.03f;
  p.vertical_slope_max = 0.5f;
  p.track_max_step = 0.2f;
  p.track_tolerance_per_m = 0.05f;
  return p;
}

// --------------------------------------------------------------------------------------------
// Row assignment from elevation.

void ElevationRowTable::build(const std::vector<float>& elevations_deg) {
  std::vector<float> el = elevations_deg;
  std::sort(el.begin(), el.end());
  rows_ = static_cast<int>(std::min<std::size_t>(el.size(), 255));
  el.resize(rows_);
  lut_.clear();
  if (rows_ == 0) {
    lut_.assign(1, 0);
    t_min_ = 0.f;
    inv_cell_ = 1.f;
    max_cell_ = 0.f;
    return;
  }
  const float deg = kPi / 180.f;
  // Cells much finer than the smallest laser spacing, over the table +- half a spacing.
  float min_gap = 2.f;
  for (int i = 1; i < rows_; ++i) min_gap = std::min(min_gap, std::max(el[i] - el[i - 1], 0.01f));
  const float lo = (el.front() - 2.f) * deg;
  const float hi = (el.back() + 2.f) * deg;
  t_min_ = std::tan(lo);
  const float t_max = std::tan(hi);
  // tan() is steepest at the lowest/highest angle; size cells from the smallest gap there.
  const float d_tan_min = min_gap * deg / 4.f;
  const int cells = std::max(1, std::min(65536, static_cast<int>((t_max - t_min_) / d_tan_min) + 1));
  inv_cell_ = static_cast<float>(cells) / (t_max - t_min_);
  max_cell_ = static_cast<float>(cells - 1);
  lut_.resize(cells);
  int row = 0;
  for (int c = 0; c < cells; ++c) {
    const float a = std::atan(t_min_ + (static_cast<float>(c) + 0.5f) / inv_cell_) / deg;
    while (row + 1 < rows_ && a > 0.5f * (el[row] + el[row + 1])) ++row;
    lut_[c] = static_cast<uint8_t>(row);
  }
}

// --------------------------------------------------------------------------------------------
// Column equations.

namespace vertical_scan {

float estimateSlope(const float* r, const float* height, int n, const VerticalScanParams& p,
                    float seed, float* weights, int* support) {
  // Eq 3.4 (feasibility) and the mean height of the feasible returns for eq 3.5.
  float sum_h = 0.f;
  int feasible_count = 0;
  for (int i = 0; i < n; ++i) {
    const bool ok = feasible(height[i], r[i], p);
    weights[i] = ok ? 1.f : 0.f;
    if (ok) {
      sum_h += height[i];
      ++feasible_count;
    }
  }
  if (support) *support = 0;
  if (feasible_count == 0) return seed;
  const float mean_h = sum_h / static_cast<float>(feasible_count);
  // Eq 3.5: upper-half rejection; weights[i] keeps 1 for the returns that take part.
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (weights[i] > 0.f && !(height[i] < mean_h)) weights[i] = 0.f;
    kept += weights[i] > 0.f;
  }
  if (kept == 0) {
    // All feasible heights equal the mean (e.g. one return): keep them all.
    for (int i = 0; i < n; ++i) weights[i] = feasible(height[i], r[i], p) ? 1.f : 0.f;
    kept = feasible_count;
  }
  if (support) *support = kept;
  // Compact the participating returns' slopes to the front of a local buffer (in r order).
  constexpr int kMaxLocal = 512;
  float slope_local[kMaxLocal];
  int m = 0;
  for (int i = 0; i < n && m < kMaxLocal; ++i) {
    if (weights[i] > 0.f) slope_local[m++] = height[i] / std::max(r[i], kMinR);
  }
  float estimate = seed;
  for (int it = 0; it < p.iterations; ++it) {
    float prev_w = 1.f;
    float sum_w = 0.f;
    float sum_ws = 0.f;
    for (int j = 0; j < m; ++j) {
      // Eq 3.6: w = 1 - |Slope + WeightBias - SlopeEstimate|, clamped at 0.
      float w = 1.f - std::fabs(slope_local[j] + p.weight_bias - estimate);
      w = w > 0.f ? w : 0.f;
      // Eq 3.7: a farther return never weighs more than a nearer one.
      w = w < prev_w ? w : prev_w;
      prev_w = w;
      sum_w += w;
      sum_ws += w * slope_local[j];
    }
    if (!(sum_w > 0.f)) break;
    // Eqs 3.8-3.9: normalised weights, weighted mean slope.
    estimate = sum_ws / sum_w;
  }
  return estimate;
}

int trackGroundLine(const float* r, const float* height, int n, const VerticalScanParams& p,
                    float slope0, int knots, float* knot_height, float* knot_support,
                    float* scratch) {
  float* gr = scratch;           // accepted ground returns, starting with the sensor's
  float* gh = scratch + n + 1;   // ground point (0, 0)
  int m = 0;
  gr[m] = 0.f;
  gh[m] = 0.f;
  ++m;
  float slope = slope0;
  int anchor = 0;
  bool last_steep = false;  // the newest ground return was a step (steeper than ground_slope_max)
  // Returns below the extrapolation that agree with each other: where the ground reappears
  // lower (behind an obstacle the line went over, or down a ditch wider than a pothole).
  int below_first = -1, below_last = -1;
  for (int i = 0; i < n; ++i) {
    const float dr = r[i] - gr[m - 1];
    const float dh = height[i] - gh[m - 1];
    const float grow = p.track_tolerance_per_m * (dr > 0.f ? dr : 0.f);
    const float res = dh - slope * dr;
    if (res < -(p.track_max_drop + grow)) {
      // Below the line: remember a run of mutually consistent returns.
      if (below_last >= 0 &&
          std::fabs(height[i] - height[below_last]) <
              p.track_max_drop + p.track_tolerance_per_m * (r[i] - r[below_last]) + 0.05f) {
        below_last = i;
      } else {
        below_first = below_last = i;
      }
      if (r[below_last] - r[below_first] < p.track_recover_distance) continue;
      // The run is long enough to be ground: restart the line at its first return.
      gr[m] = r[below_first];
      gh[m] = height[below_first];
      ++m;
      if (below_last != below_first) {
        gr[m] = r[below_last];
        gh[m] = height[below_last];
        ++m;
      }
      anchor = m - 2 > 0 ? m - 2 : 0;
      below_first = below_last = -1;
      last_steep = false;
      continue;
    }
    if (res > p.track_max_step + grow || dh > p.track_max_step + p.ground_slope_max * dr) continue;
    const float local = dh / (std::fabs(dr) + 0.02f);
    if (local > p.track_max_local_slope || local < p.track_min_local_slope) continue;
    if (dr <= 0.f) continue;  // same distance as the last ground return: keep the first
    below_first = below_last = -1;
    const bool steep = local > p.ground_slope_max;
    if (steep && last_steep) {
      // Two steps in a row climb a wall or a car, not a curb: the previous step was not
      // ground either.
      --m;
      if (anchor > m - 1) anchor = m - 1 > 0 ? m - 1 : 0;
      last_steep = false;
      continue;
    }
    last_steep = steep;
    gr[m] = r[i];
    gh[m] = height[i];
    ++m;
    // The extrapolation slope: from the newest ground return back over at least
    // track_anchor_distance (noise on closely spaced returns does not tilt it).
    while (anchor + 1 < m - 1 && r[i] - gr[anchor + 1] >= p.track_anchor_distance) ++anchor;
    const float span = r[i] - gr[anchor];
    if (span >= p.track_anchor_distance || anchor == 0) {
      float s = (height[i] - gh[anchor]) / std::max(span, 1e-3f);
      s = std::min(std::max(s, p.ground_slope_min), p.ground_slope_max);
      s = std::min(std::max(s, slope0 - p.track_max_bend), slope0 + p.track_max_bend);
      slope = s;
    }
  }
  // Sample the polyline at the knots.
  const float L = p.segment_length;
  int j = 0;
  for (int k = 0; k < knots; ++k) {
    const float rk = static_cast<float>(k) * L;
    while (j + 1 < m && gr[j + 1] < rk) ++j;
    float h;
    float dist;
    if (j + 1 < m) {
      const float t = (rk - gr[j]) / std::max(gr[j + 1] - gr[j], 1e-3f);
      h = gh[j] + (gh[j + 1] - gh[j]) * std::min(std::max(t, 0.f), 1.f);
      dist = std::min(rk - gr[j], gr[j + 1] - rk);
    } else {
      h = gh[m - 1] + slope * (rk - gr[m - 1]);
      dist = rk - gr[m - 1];
    }
    knot_height[k] = h;
    knot_support[k] = 1.f / (1.f + std::max(dist, 0.f));
  }
  return m - 1;
}

}  // namespace vertical_scan

// --------------------------------------------------------------------------------------------
// The model.

VerticalScanGround::VerticalScanGround(const VerticalScanParams& params, std::string name)
    : name_(std::move(name)) {
  setParams(params);
}

void VerticalScanGround::setParams(const VerticalScanParams& params) {
  params_ = params;
  VerticalScanParams& p = params_;
  // Sanitise instead of failing: a bad number from a parameter server must not crash.
  if (!(p.column_width_deg >= 0.1f && p.column_width_deg <= 90.f)) p.column_width_deg = 1.5f;
  if (!(p.min_range >= 0.f)) p.min_range = 0.f;
  if (!(p.max_range > p.min_range)) p.max_range = p.min_range + 120.f;
  if (p.iterations < 0) p.iterations = 0;
  if (p.iterations > 100) p.iterations = 100;
  if (!(p.segment_length >= 0.1f)) p.segment_length = 1.f;
  if (p.coupling_radius < 0) p.coupling_radius = 0;
  if (!(p.tolerances.gnd_error_max_base > 1e-4f)) p.tolerances.gnd_error_max_base = 1e-4f;
  if (!(p.tolerances.slope_error_max_base > 1e-5f)) p.tolerances.slope_error_max_base = 1e-5f;
  if (p.laser_elevations_deg.empty()) row_table_.build(hdl64eElevationsDeg());
  else row_table_.build(p.laser_elevations_deg);
  columns_ = std::max(1, static_cast<int>(std::lround(360.0 / p.column_width_deg)));
  inv_column_width_ = static_cast<float>(columns_) / (2.f * kPi);
  inv_segment_ = 1.f / p.segment_length;
  atan_lut_.resize(kAtanCells + 2);
  for (int i = 0; i <= kAtanCells + 1; ++i) {
    atan_lut_[i] = std::atan(static_cast<float>(i) / kAtanCells) * inv_column_width_;
  }
  // atan2(y, x) + pi = offset + sign * atan(min/max) per octant (steep: |y| > |x|; then the
  // signs of x and y), in column units.
  const float quarter = 0.25f * static_cast<float>(columns_);
  for (int o = 0; o < 8; ++o) {
    const bool o_steep = o & 1, o_neg_x = o & 2, o_neg_y = o & 4;
    float offset = o_steep ? quarter : 0.f, sign = o_steep ? -1.f : 1.f;
    if (o_neg_x) { offset = 2.f * quarter - offset; sign = -sign; }
    if (o_neg_y) { offset = -offset; sign = -sign; }
    octant_offset_[o] = offset + 2.f * quarter;
    octant_sign_[o] = sign;
  }
  if (p.bend_ground_line) {
    knots_ = static_cast<int>(std::ceil(p.max_range / p.segment_length)) + 2;
  } else {
    knots_ = 2;  // a straight line: knot 1 at r = segment_length, extrapolated beyond
  }
  knot_height_.assign(static_cast<std::size_t>(columns_) * knots_, 0.f);
  knot_support_.assign(knot_height_.size(), 0.f);
  coupled_.assign(knot_height_.size(), 0.f);
  column_slope_.assign(columns_, 0.f);
  column_support_.assign(columns_, 0);
}

inline float VerticalScanGround::columnCoordinate(float x, float y) const {
  // atan2(y, x) + pi in column units: octant reduction, then the LUT on min/max in [0, 1].
  const float ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const float mx = steep ? ay : ax;
  const float mn = steep ? ax : ay;
  const float t = mx > 0.f ? mn / mx : 0.f;
  const int octant = (y < 0.f) << 2 | (x < 0.f) << 1 | steep;
  const float a = octant_offset_[octant] +
                  octant_sign_[octant] * atan_lut_[static_cast<int>(t * kAtanCells + 0.5f)];
  const float max_c = static_cast<float>(columns_) - 0.5f;
  return a < max_c ? a : max_c;
}

int VerticalScanGround::columnOf(float x, float y) const {
  return static_cast<int>(columnCoordinate(x, y));
}

float VerticalScanGround::groundHeight(int col, float r) const {
  vertical_scan::GroundLine line{&knot_height_[static_cast<std::size_t>(col) * knots_], knots_,
                                 inv_segment_};
  return line.heightAt(r);
}

template <bool kRing, bool kTilted, bool kFastXYZ>
void VerticalScanGround::binPoints(const PointCloudView& view, const SensorPose& pose,
                                   GroundClassification* out) {
  const std::size_t n = view.size();
  const float min_r2 = params_.min_range * params_.min_range;
  const float max_r2 = params_.max_range * params_.max_range;
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const int rows = rows_;
  const ElevationRowTable& row_table = row_table_;
  const float* __restrict atan_lut = atan_lut_.data();
  const float max_c = static_cast<float>(columns_) - 0.5f;
  float octant_offset[8], octant_sign[8];  // local copies: the stores below cannot alias them
  std::memcpy(octant_offset, octant_offset_, sizeof(octant_offset));
  std::memcpy(octant_sign, octant_sign_, sizeof(octant_sign));
  const int shift = row_shift_;
  uint32_t* __restrict count = bin_start_.data() + 1;
  uint32_t* __restrict bins = bin_.data();
  float* __restrict rr = r_.data();
  float* __restrict hh = height_.data();
  uint8_t* __restrict labels = out->labels.data();
  float* __restrict prob = out->p_obstacle.data();
  uint32_t x_off = 0, y_off = 0, z_off = 0;
  if (kFastXYZ) {
    const CloudLayout& L = view.layout();
    x_off = findField(L, "x")->offset;
    y_off = findField(L, "y")->offset;
    z_off = findField(L, "z")->offset;
  }
  const uint8_t* base = kFastXYZ ? view.pointData(0) : nullptr;
  const std::size_t step = view.layout().point_step;
  for (std::size_t i = 0; i < n; ++i) {
    float xs, ys, zs;
    if (kFastXYZ) {
      const uint8_t* pt = base + i * step;
      std::memcpy(&xs, pt + x_off, 4);
      std::memcpy(&ys, pt + y_off, 4);
      std::memcpy(&zs, pt + z_off, 4);
    } else {
      const Eigen::Vector3f ps = view.xyz(i);
      xs = ps.x(); ys = ps.y(); zs = ps.z();
    }
    const float rs2 = xs * xs + ys * ys;
    const float d2 = rs2 + zs * zs;
    // NaN compares false: NaN/Inf and out-of-range returns are unknown.
    if (!(d2 >= min_r2 && d2 <= max_r2)) {
      bins[i] = kInvalidBin;
      labels[i] = kLabelUnknown;
      prob[i] = 0.f;
      continue;
    }
    float gx, gy, gz, r;
    const float rs = std::sqrt(rs2);
    if (kTilted) {
      const Eigen::Vector3f g = R * Eigen::Vector3f(xs, ys, zs) + t;
      gx = g.x(); gy = g.y(); gz = g.z();
      r = std::sqrt(gx * gx + gy * gy);
    } else {
      // Untilted and straight above the ground origin (classify() routes any other pose to
      // the tilted path): the horizontal distance is the sensor's.
      gx = xs; gy = ys; gz = zs + t.z();
      r = rs;
    }
    int row;
    if (kRing) {
      row = view.ring(i);
      row = row < 0 ? 0 : (row >= rows ? rows - 1 : row);
    } else {
      row = row_table.row(zs, rs > kMinR ? rs : kMinR);
    }
    // Column: atan2(gy, gx) + pi in column units (octant reduction and the atan LUT).
    const float ax = std::fabs(gx), ay = std::fabs(gy);
    const bool steep = ay > ax;
    const float mx = steep ? ay : ax;
    const float mn = steep ? ax : ay;
    // mx is 0 for a point straight above or below the sensor (x = y = 0): column 0.
    const float lut = atan_lut[static_cast<int>((mx > 0.f ? mn / mx : 0.f) * kAtanCells + 0.5f)];
    const int octant = (gy < 0.f) << 2 | (gx < 0.f) << 1 | steep;
    float a = octant_offset[octant] + octant_sign[octant] * lut;
    a = a < max_c ? a : max_c;
    const uint32_t bin = (static_cast<uint32_t>(a) << shift) + row;
    bins[i] = bin;
    rr[i] = r > kMinR ? r : kMinR;
    hh[i] = gz;
    ++count[bin];
  }
}

void VerticalScanGround::classify(const PointCloudView& view, const SensorPose& pose,
                                  GroundClassification* out) {
  const std::size_t n = view.size();
  out->resize(n);
  const bool ring = view.hasRing();
  const int wanted_rows = ring ? kMaxRingRows : std::max(1, row_table_.rows());
  row_shift_ = 0;
  while ((1 << row_shift_) < wanted_rows) ++row_shift_;
  rows_ = 1 << row_shift_;
  const std::size_t bins = static_cast<std::size_t>(columns_) * rows_;
  r_.resize(n);
  height_.resize(n);
  bin_.resize(n);
  bin_start_.assign(bins + 1, 0);
  if (n == 0) {
    // fitColumns() writes every knot; an empty scan leaves flat ground lines.
    std::fill(knot_height_.begin(), knot_height_.end(), 0.f);
    std::fill(knot_support_.begin(), knot_support_.end(), 0.f);
    return;
  }

  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const bool tilted = !R.isIdentity(1e-6f) || t.x() != 0.f || t.y() != 0.f;
  const bool fast = view.packedFloatXYZ() &&
                    (view.height() <= 1 || view.layout().row_step == view.width() * view.layout().point_step);
  if (ring && fast) {
    if (tilted) binPoints<true, true, true>(view, pose, out);
    else binPoints<true, false, true>(view, pose, out);
  } else if (ring) {
    if (tilted) binPoints<true, true, false>(view, pose, out);
    else binPoints<true, false, false>(view, pose, out);
  } else if (fast) {
    if (tilted) binPoints<false, true, true>(view, pose, out);
    else binPoints<false, false, true>(view, pose, out);
  } else {
    if (tilted) binPoints<false, true, false>(view, pose, out);
    else binPoints<false, false, false>(view, pose, out);
  }

  // Counting sort of the valid points by bin (3.3 step 1).
  uint32_t acc = 0;
  for (std::size_t b = 0; b < bins; ++b) {
    const uint32_t c = bin_start_[b + 1];
    bin_start_[b] = acc;
    acc += c;
  }
  bin_start_[bins] = acc;
  order_.resize(acc);
  {
    // Scatter; bin_start_[b] advances to the end of bin b, i.e. the start of bin b + 1.
    for (std::size_t i = 0; i < n; ++i) {
      const uint32_t b = bin_[i];
      if (b == kInvalidBin) continue;
      order_[bin_start_[b]++] = rangeKey(r_[i], static_cast<uint32_t>(i));
    }
    // Shift back: bin b spans [bin_start_[b-1], bin_start_[b]) now; restore starts.
    for (std::size_t b = bins; b > 0; --b) bin_start_[b] = bin_start_[b - 1];
    bin_start_[0] = 0;
  }
  fitColumns();
  labelPoints(out);
}

void VerticalScanGround::fitColumns() {
  const VerticalScanParams& p = params_;
  const int rows = rows_;
  col_r_.resize(static_cast<std::size_t>(columns_) * rows);
  col_h_.resize(col_r_.size());
  col_w_.resize(2 * (static_cast<std::size_t>(rows) + 1));
  rep_r_.assign(static_cast<std::size_t>(columns_) * rows, -1.f);
  rep_h_.resize(rep_r_.size());
  std::vector<int>& col_n = column_support_;
  std::vector<int>& col_count = column_count_;
  col_count.assign(columns_, 0);

  // Median-filtered range per bin: the bin's representative return (3.3 step 1), then the
  // column's representatives sorted by r (step 2) and the straight slope estimate (3.4-3.9).
  for (int c = 0; c < columns_; ++c) {
    float* cr = &col_r_[static_cast<std::size_t>(c) * rows];
    float* ch = &col_h_[static_cast<std::size_t>(c) * rows];
    int m = 0;
    for (int row = 0; row < rows; ++row) {
      const std::size_t b = static_cast<std::size_t>(c) * rows + row;
      const uint32_t begin = bin_start_[b];
      const uint32_t end = bin_start_[b + 1];
      if (begin == end) continue;
      const int cnt = static_cast<int>(end - begin);
      // The lower median by (r, input order) of the bin's keys.
      uint64_t* keys = &order_[begin];
      const int mid = (cnt - 1) / 2;
      if (cnt <= 48) {
        insertionSort(keys, cnt);
      } else {
        // Large bins (slow spin, duplicated points): partial selection.
        std::nth_element(keys, keys + mid, keys + cnt);
      }
      const uint32_t rep = static_cast<uint32_t>(keys[mid]);
      cr[m] = r_[rep];
      ch[m] = height_[rep];
      rep_r_[b] = r_[rep];
      rep_h_[b] = height_[rep];
      ++m;
    }
    insertionSort(cr, ch, m);
    col_count[c] = m;
    int support = 0;
    column_slope_[c] =
        vertical_scan::estimateSlope(cr, ch, m, p, 0.f, col_w_.data(), &support);
    col_n[c] = support;
  }

  // Column coupling of the straight estimate (beyond the thesis): a column with too few
  // feasible returns (occluded by a nearby obstacle) takes its neighbours' support-weighted
  // estimate.
  if (p.couple_columns && p.coupling_radius > 0) {
    coupled_.resize(std::max<std::size_t>(coupled_.size(), columns_));
    for (int c = 0; c < columns_; ++c) {
      if (col_n[c] >= p.min_ground_returns) {
        coupled_[c] = column_slope_[c];
        continue;
      }
      float sw = 0.f, sws = 0.f;
      for (int radius = 1; radius <= columns_ / 2 && sw == 0.f; radius *= 2) {
        for (int j = -radius * p.coupling_radius; j <= radius * p.coupling_radius; ++j) {
          const int cc = (c + j + columns_) % columns_;
          const float w = static_cast<float>(col_n[cc]);
          sw += w;
          sws += w * column_slope_[cc];
        }
      }
      coupled_[c] = sw > 0.f ? sws / sw : column_slope_[c];
    }
    for (int c = 0; c < columns_; ++c) column_slope_[c] = coupled_[c];
  }

  // The ground line of each column.
  const int K = knots_;
  for (int c = 0; c < columns_; ++c) {
    float* kh = &knot_height_[static_cast<std::size_t>(c) * K];
    float* ks = &knot_support_[static_cast<std::size_t>(c) * K];
    if (p.bend_ground_line) {
      vertical_scan::trackGroundLine(&col_r_[static_cast<std::size_t>(c) * rows],
                                     &col_h_[static_cast<std::size_t>(c) * rows], col_count[c], p,
                                     column_slope_[c], K, kh, ks, col_w_.data());
    } else {
      kh[0] = 0.f;
      kh[1] = column_slope_[c] * p.segment_length;
    }
  }

  // Coupling of the bent lines: each knot becomes the support-weighted mean of the same knot in
  // the neighbouring columns (kernel 1 / (1 + |j|)); a column without support borrows fully.
  if (p.couple_columns && p.bend_ground_line && p.coupling_radius > 0) {
    coupled_.resize(knot_height_.size());
    const int R = p.coupling_radius;
    // The kernel 1 / (1 + |j|) and the neighbour columns' knot rows (wrapping around).
    float kernel[2 * 64 + 1];
    const float* nb_height[2 * 64 + 1];
    const float* nb_support[2 * 64 + 1];
    const int RR = std::min(R, 64);
    for (int j = -RR; j <= RR; ++j) kernel[j + RR] = 1.f / (1.f + static_cast<float>(std::abs(j)));
    for (int c = 0; c < columns_; ++c) {
      for (int j = -RR; j <= RR; ++j) {
        const int cc = ((c + j) % columns_ + columns_) % columns_;
        nb_height[j + RR] = &knot_height_[static_cast<std::size_t>(cc) * K];
        nb_support[j + RR] = &knot_support_[static_cast<std::size_t>(cc) * K];
      }
      float* dst = &coupled_[static_cast<std::size_t>(c) * K];
      dst[0] = 0.f;
      for (int k = 1; k < K; ++k) {
        // A knot within half a metre of the column's own ground return keeps its height.
        const std::size_t own = static_cast<std::size_t>(c) * K + k;
        if (knot_support_[own] >= 0.66f) {
          dst[k] = knot_height_[own];
          continue;
        }
        float sw = 0.f, swh = 0.f;
        for (int j = 0; j <= 2 * RR; ++j) {
          const float w = (nb_support[j][k] + 1e-3f) * kernel[j];
          sw += w;
          swh += w * nb_height[j][k];
        }
        dst[k] = swh / sw;
      }
    }
    knot_height_.swap(coupled_);
  }
}

void VerticalScanGround::labelPoints(GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const ObstacleToleranceParams& tol = p.tolerances;
  const std::size_t n = bin_.size();
  const uint32_t rows = static_cast<uint32_t>(rows_);
  const int shift = row_shift_;
  const int K = knots_;
  const int last_k = K - 2;
  const float inv_seg = inv_segment_;
  const float thr = tol.obstacle_threshold;
  const bool negative = p.negative_obstacles;
  const bool vertical = p.vertical_surfaces;
  const float inv_v_gnd = 1.f / std::max(p.vertical_gnd_error_max, 1e-4f);
  const float inv_v_slope = 1.f / std::max(p.vertical_slope_max, 1e-4f);
  // Eq 3.15's range-growing tolerances; GndErrorMax may differ below the line.
  const float g_above = tol.gnd_error_max_base;
  const float g_below = p.negative_gnd_error_max > 0.f ? p.negative_gnd_error_max : g_above;
  const float g_per_m = tol.gnd_error_max_per_m;
  const float s_base = tol.slope_error_max_base;
  const float s_per_m = tol.slope_error_max_per_m;
  const float* __restrict rep_r = rep_r_.data();
  const float* __restrict rep_h = rep_h_.data();
  const float* __restrict knots = knot_height_.data();
  const uint32_t* __restrict bins = bin_.data();
  const float* __restrict rr = r_.data();
  const float* __restrict hh = height_.data();
  uint8_t* __restrict labels = out->labels.data();
  float* __restrict prob = out->p_obstacle.data();
  for (std::size_t i = 0; i < n; ++i) {
    const uint32_t b = bins[i];
    if (b == kInvalidBin) continue;
    const uint32_t col = b >> shift;
    const float* kh = knots + static_cast<std::size_t>(col) * K;
    const float r = rr[i];
    const float h = hh[i];
    // The column's ground line at r (vertical_scan::GroundLine::heightAt, inlined).
    const float f = r * inv_seg;
    int k = static_cast<int>(f);
    k = k < last_k ? k : last_k;
    const float ground = kh[k] + (kh[k + 1] - kh[k]) * (f - static_cast<float>(k));
    // Eq 3.10: GndError = ground line height - Height (SlopeEstimate * r - Height for the
    // thesis line); eq 3.11: SlopeError = SlopeEstimate - Height / r = GndError / r.
    float gnd_error = ground - h;
    if (!negative && gnd_error > 0.f) gnd_error = 0.f;  // below the line counts as ground
    const float abs_error = std::fabs(gnd_error);
    // Eq 3.15: P = min(|GndError|, GndErrorMax)/GndErrorMax * min(|SlopeError|, SlopeErrorMax)/SlopeErrorMax.
    const float g_max = (gnd_error > 0.f ? g_below : g_above) + g_per_m * r;
    const float s_max = s_base + s_per_m * r;
    float gt = abs_error / g_max;
    gt = gt < 1.f ? gt : 1.f;
    float st = abs_error / (r * s_max);
    st = st < 1.f ? st : 1.f;
    float prob_i = gt * st;
    if (vertical && gnd_error < 0.f) {
      // P_vertical = GndError factor * local slope factor; only evaluated where it can reach
      // the threshold (its GndError factor exceeds it), 0 elsewhere.
      float g = -gnd_error * inv_v_gnd;
      g = g < 1.f ? g : 1.f;
      if (g > thr && g > prob_i) {
        const uint32_t row = b & (rows - 1);
        float local = -1.f;
        if (row > 0 && rep_r[b - 1] >= 0.f) {
          local = std::fabs(h - rep_h[b - 1]) / (std::fabs(r - rep_r[b - 1]) + 0.02f);
        }
        if (row + 1 < rows && rep_r[b + 1] >= 0.f) {
          const float sl = std::fabs(h - rep_h[b + 1]) / (std::fabs(r - rep_r[b + 1]) + 0.02f);
          local = local < 0.f ? sl : (sl < local ? sl : local);
        }
        float v = local * inv_v_slope;
        v = v < 1.f ? v : 1.f;
        const float pv = g * v;
        prob_i = pv > prob_i ? pv : prob_i;
      }
    }
    prob[i] = prob_i;
    labels[i] = prob_i > thr ? kLabelObstacle : kLabelGround;
  }
}

bool setVerticalScanParam(VerticalScanParams* p, const std::string& key, double value,
                          std::string* error) {
  const float f = static_cast<float>(value);
  ObstacleToleranceParams& t = p->tolerances;
  struct FloatField { const char* name; float* field; };
  const FloatField floats[] = {
      {"column_width_deg", &p->column_width_deg},
      {"min_range", &p->min_range},
      {"max_range", &p->max_range},
      {"ground_slope_min", &p->ground_slope_min},
      {"ground_slope_max", &p->ground_slope_max},
      {"weight_bias", &p->weight_bias},
      {"tolerances.gnd_error_max_base", &t.gnd_error_max_base},
      {"tolerances.gnd_error_max_per_m", &t.gnd_error_max_per_m},
      {"tolerances.slope_error_max_base", &t.slope_error_max_base},
      {"tolerances.slope_error_max_per_m", &t.slope_error_max_per_m},
      {"tolerances.obstacle_threshold", &t.obstacle_threshold},
      {"segment_length", &p->segment_length},
      {"track_max_step", &p->track_max_step},
      {"track_max_drop", &p->track_max_drop},
      {"track_tolerance_per_m", &p->track_tolerance_per_m},
      {"track_max_local_slope", &p->track_max_local_slope},
      {"track_min_local_slope", &p->track_min_local_slope},
      {"track_anchor_distance", &p->track_anchor_distance},
      {"track_max_bend", &p->track_max_bend},
      {"track_recover_distance", &p->track_recover_distance},
      {"negative_gnd_error_max", &p->negative_gnd_error_max},
      {"vertical_gnd_error_max", &p->vertical_gnd_error_max},
      {"vertical_slope_max", &p->vertical_slope_max},
  };
  for (const FloatField& ff : floats) {
    if (key == ff.name) { *ff.field = f; return true; }
  }
  if (key == "iterations") { p->iterations = static_cast<int>(value); return true; }
  if (key == "coupling_radius") { p->coupling_radius = static_cast<int>(value); return true; }
  if (key == "min_ground_returns") { p->min_ground_returns = static_cast<int>(value); return true; }
  if (key == "bend_ground_line") { p->bend_ground_line = value != 0.0; return true; }
  if (key == "couple_columns") { p->couple_columns = value != 0.0; return true; }
  if (key == "negative_obstacles") { p->negative_obstacles = value != 0.0; return true; }
  if (key == "vertical_surfaces") { p->vertical_surfaces = value != 0.0; return true; }
  if (error) *error = "unknown vertical scan parameter '" + key + "'";
  return false;
}

std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params) {
  return std::make_unique<VerticalScanGround>(params, "vertical_scan");
}

}  // namespace ladar_perception
