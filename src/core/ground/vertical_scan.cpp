// Vertical scan ground extraction (thesis 3.3; equations restated in algorithms.md).
#include "ladar_perception/ground/vertical_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {

namespace {

constexpr uint32_t kInvalidBin = std::numeric_limits<uint32_t>::max();
constexpr float kPi = 3.14159265358979f;
constexpr int kMaxRingRows = 128;   // rows of the bin grid when the cloud carries `ring`
constexpr float kMinR = 0.05f;      // horizontal distance floor for Height / r [m]

// atan2 with a 6-term odd minimax polynomial on [0, 1] (|error| < 2e-5 rad, far below a
// 1.5 deg column); a handful of instructions instead of a libm call per point.
inline float fastAtan2(float y, float x) {
  const float ax = std::fabs(x);
  const float ay = std::fabs(y);
  const float mx = ax > ay ? ax : ay;
  const float mn = ax > ay ? ay : ax;
  const float t = mx > 0.f ? mn / mx : 0.f;
  const float s = t * t;
  float a = t * (0.99997726f +
                 s * (-0.33262347f +
                      s * (0.19354346f + s * (-0.11643287f + s * (0.05265332f - s * 0.01172120f)))));
  if (ay > ax) a = 0.5f * kPi - a;
  if (x < 0.f) a = kPi - a;
  return y < 0.f ? -a : a;
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
  return p;
}

VerticalScanParams verticalScanDefaultParams() {
  VerticalScanParams p;
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

void fitBentLine(const float* r, const float* height, int n, const VerticalScanParams& p,
                 float slope0, int knots, float* knot_height, float* segment_support,
                 float* weights) {
  const float L = p.segment_length;
  const float gate = std::max(p.segment_gate, 1e-3f);
  const float inv_gate = 1.f / gate;
  // Downward bias of the residual, the height-unit twin of WeightBias (eq 3.6).
  const float bias = p.weight_bias * 2.f;
  knot_height[0] = 0.f;
  float slope_prev = slope0;
  int i = 0;
  for (int k = 0; k + 1 < knots; ++k) {
    const float r0 = static_cast<float>(k) * L;
    const float r1 = r0 + L;
    const float g0 = knot_height[k];
    const int a = i;
    while (i < n && r[i] < r1) ++i;
    const int b = (k + 2 == knots) ? n : i;  // the last segment takes everything beyond
    if (k + 2 == knots) i = n;
    float slope = slope_prev;
    float support = 0.f;
    if (b > a) {
      const float lo = std::max(p.ground_slope_min, slope_prev - p.max_bend);
      const float hi = std::min(p.ground_slope_max, slope_prev + p.max_bend);
      for (int it = 0; it < p.iterations; ++it) {
        float prev_w = 1.f;
        float sww = 0.f, swd = 0.f, sw = 0.f;
        for (int j = a; j < b; ++j) {
          const float dr = r[j] - r0;
          const float res = height[j] - (g0 + slope * dr);
          float w = 1.f - std::fabs(res + bias) * inv_gate;
          w = w > 0.f ? w : 0.f;
          w = w < prev_w ? w : prev_w;  // as eq 3.7
          prev_w = w;
          weights[j] = w;
          sw += w;
          sww += w * dr * dr;
          swd += w * dr * (height[j] - g0);
        }
        support = sw;
        if (!(sww > 1e-3f)) break;
        float s = swd / sww;
        s = std::min(std::max(s, lo), hi);
        if (std::fabs(s - slope) < 1e-5f) {
          slope = s;
          break;
        }
        slope = s;
      }
    }
    segment_support[k] = support;
    knot_height[k + 1] = g0 + slope * L;
    slope_prev = slope;
  }
  segment_support[knots - 1] = 0.f;
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
  if (!(p.segment_length >= 0.5f)) p.segment_length = 10.f;
  if (p.coupling_radius < 0) p.coupling_radius = 0;
  if (!(p.tolerances.gnd_error_max_base > 1e-4f)) p.tolerances.gnd_error_max_base = 1e-4f;
  if (!(p.tolerances.slope_error_max_base > 1e-5f)) p.tolerances.slope_error_max_base = 1e-5f;
  if (p.laser_elevations_deg.empty()) row_table_.build(hdl64eElevationsDeg());
  else row_table_.build(p.laser_elevations_deg);
  columns_ = std::max(1, static_cast<int>(std::lround(360.0 / p.column_width_deg)));
  inv_column_width_ = static_cast<float>(columns_) / (2.f * kPi);
  inv_segment_ = 1.f / p.segment_length;
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

int VerticalScanGround::columnOf(float x, float y) const {
  int c = static_cast<int>((fastAtan2(y, x) + kPi) * inv_column_width_);
  return c >= columns_ ? columns_ - 1 : (c < 0 ? 0 : c);
}

float VerticalScanGround::groundHeight(int col, float r) const {
  vertical_scan::GroundLine line{&knot_height_[static_cast<std::size_t>(col) * knots_], knots_,
                                 inv_segment_};
  return line.heightAt(r);
}

template <bool kRing, bool kTilted>
void VerticalScanGround::binPoints(const PointCloudView& view, const SensorPose& pose,
                                   GroundClassification* out) {
  const std::size_t n = view.size();
  const float min_r2 = params_.min_range * params_.min_range;
  const float max_r2 = params_.max_range * params_.max_range;
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const int rows = rows_;
  const float cols_f = static_cast<float>(columns_);
  uint32_t* count = bin_start_.data() + 1;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f ps = view.xyz(i);
    const float xs = ps.x(), ys = ps.y(), zs = ps.z();
    const float rs2 = xs * xs + ys * ys;
    const float d2 = rs2 + zs * zs;
    // NaN compares false: NaN/Inf and out-of-range returns are unknown.
    if (!(d2 >= min_r2 && d2 <= max_r2)) {
      bin_[i] = kInvalidBin;
      out->labels[i] = kLabelUnknown;
      out->p_obstacle[i] = 0.f;
      continue;
    }
    float gx, gy, gz, r;
    const float rs = std::sqrt(rs2);
    if (kTilted) {
      const Eigen::Vector3f g = R * ps + t;
      gx = g.x(); gy = g.y(); gz = g.z();
      r = std::sqrt(gx * gx + gy * gy);
    } else {
      gx = xs + t.x(); gy = ys + t.y(); gz = zs + t.z();
      r = (t.x() == 0.f && t.y() == 0.f) ? rs : std::sqrt(gx * gx + gy * gy);
    }
    int row;
    if (kRing) {
      row = view.ring(i);
      row = row < 0 ? 0 : (row >= rows ? rows - 1 : row);
    } else {
      row = row_table_.row(zs, rs > kMinR ? rs : kMinR);
    }
    float cf = (fastAtan2(gy, gx) + kPi) * inv_column_width_;
    cf = cf < cols_f ? cf : cols_f - 1.f;
    const uint32_t bin = static_cast<uint32_t>(cf) * rows + row;
    bin_[i] = bin;
    r_[i] = r > kMinR ? r : kMinR;
    height_[i] = gz;
    ++count[bin];
  }
}

void VerticalScanGround::classify(const PointCloudView& view, const SensorPose& pose,
                                  GroundClassification* out) {
  const std::size_t n = view.size();
  out->resize(n);
  const bool ring = view.hasRing();
  rows_ = ring ? kMaxRingRows : std::max(1, row_table_.rows());
  const std::size_t bins = static_cast<std::size_t>(columns_) * rows_;
  r_.resize(n);
  height_.resize(n);
  bin_.resize(n);
  bin_start_.assign(bins + 1, 0);
  std::fill(knot_height_.begin(), knot_height_.end(), 0.f);
  std::fill(knot_support_.begin(), knot_support_.end(), 0.f);
  if (n == 0) return;

  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const bool tilted = !R.isIdentity(1e-6f);
  if (ring) {
    if (tilted) binPoints<true, true>(view, pose, out);
    else binPoints<true, false>(view, pose, out);
  } else {
    if (tilted) binPoints<false, true>(view, pose, out);
    else binPoints<false, false>(view, pose, out);
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
  order_r_.resize(acc);
  {
    // Scatter; bin_start_[b] advances to the end of bin b, i.e. the start of bin b + 1.
    for (std::size_t i = 0; i < n; ++i) {
      const uint32_t b = bin_[i];
      if (b == kInvalidBin) continue;
      const uint32_t pos = bin_start_[b]++;
      order_[pos] = static_cast<uint32_t>(i);
      order_r_[pos] = r_[i];
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
  col_w_.resize(std::max<std::size_t>(rows, 1));
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
      uint32_t rep;
      if (cnt <= 2) {
        rep = order_[begin];  // lower median of 1 or 2
        if (cnt == 2 && order_r_[begin + 1] < order_r_[begin]) rep = order_[begin + 1];
      } else if (cnt <= 48) {
        insertionSort(&order_r_[begin], &order_[begin], cnt);
        rep = order_[begin + (cnt - 1) / 2];
      } else {
        // Large bins (slow spin, duplicated points): partial selection.
        std::vector<std::pair<float, uint32_t>>& tmp = median_scratch_;
        tmp.resize(cnt);
        for (int j = 0; j < cnt; ++j) tmp[j] = {order_r_[begin + j], order_[begin + j]};
        std::nth_element(tmp.begin(), tmp.begin() + (cnt - 1) / 2, tmp.end());
        rep = tmp[(cnt - 1) / 2].second;
      }
      cr[m] = r_[rep];
      ch[m] = height_[rep];
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
      vertical_scan::fitBentLine(&col_r_[static_cast<std::size_t>(c) * rows],
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
    for (int c = 0; c < columns_; ++c) {
      float* dst = &coupled_[static_cast<std::size_t>(c) * K];
      dst[0] = 0.f;
      for (int k = 1; k < K; ++k) {
        float sw = 0.f, swh = 0.f;
        for (int j = -R; j <= R; ++j) {
          const int cc = (c + j + columns_) % columns_;
          const float w = (knot_support_[static_cast<std::size_t>(cc) * K + k - 1] + 1e-3f) /
                          (1.f + static_cast<float>(std::abs(j)));
          sw += w;
          swh += w * knot_height_[static_cast<std::size_t>(cc) * K + k];
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
  const int K = knots_;
  const float inv_seg = inv_segment_;
  const float thr = tol.obstacle_threshold;
  const bool negative = p.negative_obstacles;
  uint8_t* labels = out->labels.data();
  float* prob = out->p_obstacle.data();
  for (std::size_t i = 0; i < n; ++i) {
    const uint32_t b = bin_[i];
    if (b == kInvalidBin) continue;
    const float* kh = &knot_height_[static_cast<std::size_t>(b / rows) * K];
    const float r = r_[i];
    const vertical_scan::GroundLine line{kh, K, inv_seg};
    // Eq 3.10 (GndError = ground line height - Height; SlopeEstimate * r for the thesis line)
    // and eq 3.11 (SlopeError = SlopeEstimate - Slope_i = GndError / r).
    float gnd_error = line.heightAt(r) - height_[i];
    if (!negative && gnd_error > 0.f) gnd_error = 0.f;  // below the line counts as ground
    const float slope_error = gnd_error / r;
    const float prob_i = obstacleProbability(gnd_error, slope_error, r, tol);  // eq 3.15
    prob[i] = prob_i;
    labels[i] = prob_i > thr ? kLabelObstacle : kLabelGround;
  }
}

std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params) {
  return std::make_unique<VerticalScanGround>(params, "vertical_scan");
}

}  // namespace ladar_perception
