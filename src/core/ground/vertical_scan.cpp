// Vertical scan ground extraction (thesis 3.3): the model, its settings' derived tables, the
// binning of a scan's returns by laser row and azimuth column (3.3 step 1) and classify(), which
// runs the stages: fitColumns() (vertical_scan_column.cpp), labelPoints()
// (vertical_scan_label.cpp), labelFromLaserNeighbours() (vertical_scan_neighbours.cpp) and
// relabelFromLocalGround() (vertical_scan_local_ground.cpp).
#include "ladar_perception/ground/vertical_scan.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "ladar_perception/cloud/laser_elevations.h"
#include "vertical_scan_internal.h"

namespace ladar_perception {

namespace {

// Zeroes n words with vector stores (no memset: its `rep stos` costs one counted instruction
// per byte under callgrind, the yardstick of the speed target).
inline void zeroFill(uint32_t* p, std::size_t n) {
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128i zero = _mm_setzero_si128();
  for (; i + 4 <= n; i += 4) _mm_storeu_si128(reinterpret_cast<__m128i*>(p + i), zero);
#endif
  for (; i < n; ++i) p[i] = 0;
}


}  // namespace

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
  // Three readable bytes past the last cell: the AVX2 binning gathers a 32-bit word per lane
  // and keeps its low byte.
  lut_.resize(static_cast<std::size_t>(cells) + 3, 0);
}

// --------------------------------------------------------------------------------------------
// The model.

VerticalScanGround::VerticalScanGround(const VerticalScanParams& params, std::string name)
    : name_(std::move(name)) {
  setParams(params);
}

void VerticalScanGround::setLidarModel(const LidarModel& lidar) {
  setParams(paramsForLidarModel(params_, lidar));
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
  knots_used_ = knots_;
  knot_stride_ = knots_ + 1;  // the spare knot after each column's stays 0 (= kh[0])
  knot_height_.assign(static_cast<std::size_t>(columns_) * knot_stride_ + 2 * kKnotPad, 0.f);
  knot_support_.assign(knot_height_.size(), 0.f);
  coupled_.assign(knot_height_.size(), 0.f);
  column_slope_.assign(columns_, 0.f);
  column_support_.assign(columns_, 0);
  if (p.neighbour_cells_per_column < 1) p.neighbour_cells_per_column = 1;
  if (p.neighbour_cells_per_column > 64) p.neighbour_cells_per_column = 64;
  if (p.laser_neighbours) {
    // Sized for the largest bin grid (kMaxRingRows rows); filled once, never cleared.
    // Row-major (cell = row << cell_row_shift_ | sub-column): a laser's sweep writes and
    // reads consecutive cells, and so does a firing of all lasers at one azimuth, row by row.
    cell_row_shift_ = 0;
    while ((1 << cell_row_shift_) < columns_ * p.neighbour_cells_per_column) ++cell_row_shift_;
    range_image_.assign(static_cast<std::size_t>(kMaxRingRows) << cell_row_shift_, 0xFFFFFFFFu);
    // A row of padding before and after: the marks of the rows below row 0 and above the top.
    cell_mark_.assign(range_image_.size() + (std::size_t{2} << cell_row_shift_), 0);
    mark_stamp_ = 0;
    // The angle from each row to the next one up, from the laser table (0.4 degrees beyond it).
    std::vector<float> el = p.laser_elevations_deg.empty() ? hdl64eElevationsDeg() : p.laser_elevations_deg;
    std::sort(el.begin(), el.end());
    row_gap_tan_.assign(kMaxRingRows, std::tan(0.4f * kPi / 180.f));
    for (std::size_t k = 0; k + 1 < el.size() && k < row_gap_tan_.size(); ++k) {
      row_gap_tan_[k] = std::tan(std::max(el[k + 1] - el[k], 0.05f) * kPi / 180.f);
    }
  } else {
    range_image_.clear();
    range_image_.shrink_to_fit();
    cell_mark_.clear();
    cell_mark_.shrink_to_fit();
  }
  if (!(p.local_ground_cell >= 0.05f)) p.local_ground_cell = 0.5f;
  p.local_ground_columns = std::max(0, std::min(p.local_ground_columns, 16));
  p.local_ground_rings = std::max(0, std::min(p.local_ground_rings, 16));
  if (p.local_ground_min_returns < 1) p.local_ground_min_returns = 1;
  if (p.local_ground && p.laser_neighbours) {
    local_rings_ = static_cast<int>(p.max_range / p.local_ground_cell) + 1;
    local_grid_.assign(3 * static_cast<std::size_t>(columns_) * local_rings_, 0.f);
    local_around_.assign(local_grid_.size(), 0.f);
    local_bin_cell_.assign(static_cast<std::size_t>(columns_) * kMaxRingRows, 0);
    local_bin_band_.assign(2 * local_bin_cell_.size(), 0.f);
  } else {
    local_rings_ = 0;
    local_grid_.clear();
    local_grid_.shrink_to_fit();
    local_around_.clear();
    local_around_.shrink_to_fit();
    local_bin_cell_.clear();
    local_bin_cell_.shrink_to_fit();
    local_bin_band_.clear();
    local_bin_band_.shrink_to_fit();
  }
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

void VerticalScanGround::readRingOrder(const PointCloudView& view) {
  // One pass over every 7th return (a stride prime to the usual beam counts): the highest ring,
  // and per ring the sum of tan(elevation) = z / r (sensor frame). Then the mean of the lower
  // and the upper half of the ring numbers: over a revolution a tilt averages out, so the half
  // with the higher mean holds the upper beams.
  RingInfo info;
  info.source = view.ringSource();
  const std::size_t n = view.size();
  double ring_sum[kMaxRingRows] = {};
  std::size_t ring_count[kMaxRingRows] = {};
  int max_ring = -1;
  for (std::size_t i = 0; i < n; i += 7) {
    const int ring = view.ring(i);
    max_ring = std::max(max_ring, ring);
    const Eigen::Vector3f p = view.xyz(i);
    const float r = std::sqrt(p.x() * p.x() + p.y() * p.y());
    if (!(r > 0.5f) || !std::isfinite(p.z())) continue;
    const int k = ring < 0 ? 0 : (ring >= kMaxRingRows ? kMaxRingRows - 1 : ring);
    ring_sum[k] += p.z() / r;
    ++ring_count[k];
  }
  if (info.source == PointCloudView::RingSource::kRows) max_ring = static_cast<int>(view.height()) - 1;
  info.max_ring = max_ring;
  info.top_ring = std::max(max_ring, row_table_.rows() - 1);
  const int mid = info.top_ring / 2;
  double sum[2] = {0.0, 0.0};
  std::size_t count[2] = {0, 0};
  for (int k = 0; k < kMaxRingRows; ++k) {
    sum[k > mid] += ring_sum[k];
    count[k > mid] += ring_count[k];
  }
  info.top_down = count[0] >= 16 && count[1] >= 16 &&
                  sum[0] / static_cast<double>(count[0]) > sum[1] / static_cast<double>(count[1]);
  last_rings_ = info;
}

float VerticalScanGround::groundHeight(int col, float r) const { return groundLineHeight(col, r); }

int VerticalScanGround::columnOf(float x, float y) const {
  return static_cast<int>(columnCoordinate(x, y));
}

#if defined(LADAR_CLONES)
namespace {

// What binPoints() hands its 8-lane loop: the cloud's packed x, y, z, the tables and constants
// of the binning, and the arrays it writes.
struct BinPass {
  const uint8_t* xyz;  // x of point 0; y and z follow it
  std::size_t step, n;
  float min_r2, max_r2, tz, max_c, quarter, cells_per_column, last_sub;
  const ElevationRowTable* row_table;
  const float* atan_lut;
  int shift, cell_row_shift, rows, ring_top;
  uint32_t unknown_bin;
  uint32_t *bins, *cell, *image;
  float *rr, *hh, *prob;
  uint8_t* labels;
};

// The first four floats of the point at p and of the one four points on.
__attribute__((target("avx2"))) inline __m256 loadPointPair(const uint8_t* p, std::size_t step) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(reinterpret_cast<const float*>(p))),
                              _mm_loadu_ps(reinterpret_cast<const float*>(p + 4 * step)), 1);
}

// binPoints()'s SSE2 loop with 8 lanes and the two table lookups as gathers (AVX2). Every lane
// repeats the scalar loop's arithmetic operation for operation, so the bins, cells, r and
// heights are bit-identical to it. Returns the first point it left to the caller.
template <bool kRing, bool kSubColumns>
__attribute__((target("avx2"))) std::size_t binPointsAvx2(const BinPass& b, const PointCloudView& view) {
  const __m256 v_min_r2 = _mm256_set1_ps(b.min_r2), v_max_r2 = _mm256_set1_ps(b.max_r2);
  const __m256 v_tz = _mm256_set1_ps(b.tz);
  const __m256 v_min_r = _mm256_set1_ps(kMinR);
  const __m256 v_t_min = _mm256_set1_ps(b.row_table->tMin());
  const __m256 v_inv_cell = _mm256_set1_ps(b.row_table->invCell());
  const __m256 v_max_cell = _mm256_set1_ps(b.row_table->maxCell());
  const __m256 v_zero = _mm256_setzero_ps();
  const __m256 v_cells = _mm256_set1_ps(static_cast<float>(kAtanCells));
  const __m256 v_half = _mm256_set1_ps(0.5f);
  const __m256 v_max_c = _mm256_set1_ps(b.max_c);
  const __m256 v_abs = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m128i v_shift = _mm_cvtsi32_si128(b.shift);
  const __m256i v_unknown_bin = _mm256_set1_epi32(static_cast<int>(b.unknown_bin));
  const __m256i v_byte = _mm256_set1_epi32(0xFF);
  const int* row_lut = reinterpret_cast<const int*>(b.row_table->lut());
  const __m256 v_quarter = _mm256_set1_ps(b.quarter), v_half_turn = _mm256_set1_ps(2.f * b.quarter);
  const __m256 v_sign_bit = _mm256_castsi256_ps(_mm256_set1_epi32(static_cast<int>(0x80000000u)));
  const __m256 v_cells_per_column = _mm256_set1_ps(b.cells_per_column), v_last_sub = _mm256_set1_ps(b.last_sub);
  const __m256i v_no_cell = _mm256_set1_epi32(-1);
  const __m128i v_cell_row_shift = _mm_cvtsi32_si128(b.cell_row_shift);
  const std::size_t step = b.step;
  uint32_t* __restrict image = b.image;
  std::size_t i = 0;
  for (; i + 8 <= b.n; i += 8) {
    const uint8_t* pt = b.xyz + i * step;
    // Point k in the low half, point k + 4 in the high half.
    const __m256 P0 = loadPointPair(pt, step), P1 = loadPointPair(pt + step, step);
    const __m256 P2 = loadPointPair(pt + 2 * step, step), P3 = loadPointPair(pt + 3 * step, step);
    // Transpose within each half: X, Y, Z become the eight points' x, y and z.
    const __m256 t0 = _mm256_unpacklo_ps(P0, P1), t1 = _mm256_unpackhi_ps(P0, P1);
    const __m256 t2 = _mm256_unpacklo_ps(P2, P3), t3 = _mm256_unpackhi_ps(P2, P3);
    const __m256 X = _mm256_shuffle_ps(t0, t2, 0x44);
    const __m256 Y = _mm256_shuffle_ps(t0, t2, 0xEE);
    const __m256 Z = _mm256_shuffle_ps(t1, t3, 0x44);
    const __m256 rs2 = _mm256_add_ps(_mm256_mul_ps(X, X), _mm256_mul_ps(Y, Y));
    const __m256 d2 = _mm256_add_ps(rs2, _mm256_mul_ps(Z, Z));
    const __m256 valid = _mm256_and_ps(_mm256_cmp_ps(d2, v_min_r2, _CMP_GE_OQ), _mm256_cmp_ps(d2, v_max_r2, _CMP_LE_OQ));
    const int valid_bits = _mm256_movemask_ps(valid);
    if (valid_bits == 0) {
      for (int l = 0; l < 8; ++l) {
        if (kSubColumns) b.cell[i + l] = kNoCell;
        b.bins[i + l] = b.unknown_bin;
        b.rr[i + l] = 0.f;
        b.hh[i + l] = 0.f;
        b.labels[i + l] = kLabelUnknown;
        b.prob[i + l] = 0.f;
      }
      continue;
    }
    const __m256i valid_i = _mm256_castps_si256(valid);
    const __m256 rc = _mm256_max_ps(_mm256_sqrt_ps(rs2), v_min_r);
    __m256 f = _mm256_mul_ps(_mm256_sub_ps(_mm256_div_ps(Z, rc), v_t_min), v_inv_cell);
    f = _mm256_min_ps(_mm256_max_ps(f, v_zero), v_max_cell);
    const __m256 ax = _mm256_and_ps(X, v_abs), ay = _mm256_and_ps(Y, v_abs);
    const __m256 steep = _mm256_cmp_ps(ay, ax, _CMP_GT_OQ);
    const __m256 mx = _mm256_blendv_ps(ax, ay, steep);
    const __m256 mn = _mm256_blendv_ps(ay, ax, steep);
    const __m256 tt = _mm256_and_ps(_mm256_div_ps(mn, mx), _mm256_cmp_ps(mx, v_zero, _CMP_GT_OQ));
    const __m256 neg_x = _mm256_cmp_ps(X, v_zero, _CMP_LT_OQ), neg_y = _mm256_cmp_ps(Y, v_zero, _CMP_LT_OQ);
    __m256 off = _mm256_and_ps(steep, v_quarter);
    off = _mm256_blendv_ps(off, _mm256_sub_ps(v_half_turn, off), neg_x);
    off = _mm256_blendv_ps(off, _mm256_sub_ps(v_zero, off), neg_y);
    off = _mm256_add_ps(off, v_half_turn);
    const __m256 flip = _mm256_and_ps(_mm256_xor_ps(_mm256_xor_ps(steep, neg_x), neg_y), v_sign_bit);
    const __m256i lut_i =
        _mm256_and_si256(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(tt, v_cells), v_half)), valid_i);
    const __m256 lut = _mm256_i32gather_ps(b.atan_lut, lut_i, 4);
    const __m256 a = _mm256_min_ps(_mm256_add_ps(off, _mm256_xor_ps(lut, flip)), v_max_c);
    __m256i row;
    if (kRing) {
      alignas(32) int ring[8];
      for (int l = 0; l < 8; ++l) {
        int rg = view.ring(i + l);
        if (b.ring_top >= 0) rg = b.ring_top - rg;
        ring[l] = rg < 0 ? 0 : (rg >= b.rows ? b.rows - 1 : rg);
      }
      row = _mm256_load_si256(reinterpret_cast<const __m256i*>(ring));
    } else {
      const __m256i row_i = _mm256_and_si256(_mm256_cvttps_epi32(f), valid_i);
      row = _mm256_and_si256(_mm256_i32gather_epi32(row_lut, row_i, 1), v_byte);
    }
    __m256i bin = _mm256_add_epi32(_mm256_sll_epi32(_mm256_cvttps_epi32(a), v_shift), row);
    if (kSubColumns) {
      const __m256i sub = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_mul_ps(a, v_cells_per_column), v_last_sub));
      const __m256i c = _mm256_or_si256(_mm256_sll_epi32(row, v_cell_row_shift), sub);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(b.cell + i),
                          _mm256_blendv_epi8(v_no_cell, c, valid_i));
      // The image entry of a cell is the last return in it, in input order.
      alignas(32) uint32_t lane_cell[8];
      _mm256_store_si256(reinterpret_cast<__m256i*>(lane_cell), c);
      const uint32_t i0 = static_cast<uint32_t>(i);
      if (valid_bits == 0xFF) {
        for (uint32_t l = 0; l < 8; ++l) image[lane_cell[l]] = i0 + l;
      } else {
        for (uint32_t l = 0; l < 8; ++l) {
          if (valid_bits >> l & 1) image[lane_cell[l]] = i0 + l;
        }
      }
    }
    _mm256_storeu_ps(b.rr + i, _mm256_and_ps(rc, valid));
    _mm256_storeu_ps(b.hh + i, _mm256_and_ps(_mm256_add_ps(Z, v_tz), valid));
    if (valid_bits != 0xFF) {
      bin = _mm256_blendv_epi8(v_unknown_bin, bin, valid_i);
      for (int l = 0; l < 8; ++l) {
        if (!(valid_bits >> l & 1)) {
          b.labels[i + l] = kLabelUnknown;
          b.prob[i + l] = 0.f;
        }
      }
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(b.bins + i), bin);
  }
  return i;
}

}  // namespace
#endif

template <bool kRing, bool kTilted, bool kFastXYZ, bool kSubColumns>
LADAR_HOT_PATH void VerticalScanGround::binPoints(const PointCloudView& view, const SensorPose& pose,
                                   GroundClassification* out) {
  const std::size_t n = view.size();
  const float min_r2 = params_.min_range * params_.min_range;
  const float max_r2 = params_.max_range * params_.max_range;
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const int rows = rows_;
  // Top-down rings (Ouster): row = ring_top - ring, so that row 0 is the lowest beam.
  const int ring_top = kRing && last_rings_.top_down ? last_rings_.top_ring : -1;
  const ElevationRowTable& row_table = row_table_;
  const float* __restrict atan_lut = atan_lut_.data();
  const float max_c = static_cast<float>(columns_) - 0.5f;
  float octant_offset[8], octant_sign[8];  // local copies: the stores below cannot alias them
  std::memcpy(octant_offset, octant_offset_, sizeof(octant_offset));
  std::memcpy(octant_sign, octant_sign_, sizeof(octant_sign));
  const int shift = row_shift_;
  const uint32_t unknown_bin = unknown_bin_;
  uint32_t* __restrict bins = bin_.data();
  float* __restrict rr = r_.data();
  float* __restrict hh = height_.data();
  // laser_neighbours: each return's range-image cell (row << cell_row_shift_ | sub-column, or
  // kNoCell), and the image entry of that cell (the last return in it, in input order).
  uint32_t* __restrict cell = kSubColumns ? cell_.data() : nullptr;
  uint32_t* __restrict image = kSubColumns ? range_image_.data() : nullptr;
  const float cells_per_column = static_cast<float>(params_.neighbour_cells_per_column);
  const float last_sub = static_cast<float>(columns_ * params_.neighbour_cells_per_column - 1);
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
  std::size_t i = 0;
#if defined(__SSE2__)
  // Four points at a time (SSE2, the x86-64 baseline) when x, y, z are consecutive floats and a
  // 16-byte read from x stays inside the point. Every lane repeats the scalar loop's arithmetic
  // below operation for operation, so the bins, r and heights are bit-identical to it.
  if (kFastXYZ && !kTilted && y_off == x_off + 4 && z_off == x_off + 8 && x_off + 16 <= step) {
    const __m128 v_min_r2 = _mm_set1_ps(min_r2), v_max_r2 = _mm_set1_ps(max_r2);
    const __m128 v_tz = _mm_set1_ps(t.z());
    const __m128 v_min_r = _mm_set1_ps(kMinR);
    const __m128 v_t_min = _mm_set1_ps(row_table.tMin());
    const __m128 v_inv_cell = _mm_set1_ps(row_table.invCell());
    const __m128 v_max_cell = _mm_set1_ps(row_table.maxCell());
    const __m128 v_zero = _mm_setzero_ps();
    const __m128 v_cells = _mm_set1_ps(static_cast<float>(kAtanCells));
    const __m128 v_half = _mm_set1_ps(0.5f);
    const __m128 v_max_c = _mm_set1_ps(max_c);
    const __m128 v_abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128i v_shift = _mm_cvtsi32_si128(shift);
    const __m128i v_unknown_bin = _mm_set1_epi32(static_cast<int>(unknown_bin));
    const uint8_t* __restrict row_lut = row_table.lut();
    const uint8_t* src = base + x_off;
    alignas(16) int32_t row_i[4], lut_i[4];
    const float quarter = 0.25f * static_cast<float>(columns_);
    const __m128 v_quarter = _mm_set1_ps(quarter), v_half_turn = _mm_set1_ps(2.f * quarter);
    const __m128 v_sign_bit = _mm_castsi128_ps(_mm_set1_epi32(static_cast<int>(0x80000000u)));
    const __m128 v_cells_per_column = _mm_set1_ps(cells_per_column), v_last_sub = _mm_set1_ps(last_sub);
    const __m128i v_no_cell = _mm_set1_epi32(-1);
    const __m128i v_cell_row_shift = _mm_cvtsi32_si128(cell_row_shift_);
#if defined(LADAR_CLONES)
    if (cpuHasAvx2()) {
      const BinPass pass{src, step, n, min_r2, max_r2, t.z(), max_c, quarter, cells_per_column, last_sub,
                         &row_table, atan_lut, shift, cell_row_shift_, rows, ring_top, unknown_bin,
                         bins, cell, image, rr, hh, prob, labels};
      i = binPointsAvx2<kRing, kSubColumns>(pass, view);
    }
#endif
    for (; i + 4 <= n; i += 4) {
      const uint8_t* pt = src + i * step;
      __m128 X = _mm_loadu_ps(reinterpret_cast<const float*>(pt));
      __m128 Y = _mm_loadu_ps(reinterpret_cast<const float*>(pt + step));
      __m128 Z = _mm_loadu_ps(reinterpret_cast<const float*>(pt + 2 * step));
      const __m128 W = _mm_loadu_ps(reinterpret_cast<const float*>(pt + 3 * step));
      {
        // Transpose: X, Y, Z become the four points' x, y and z.
        const __m128 t0 = _mm_unpacklo_ps(X, Y), t1 = _mm_unpackhi_ps(X, Y);
        const __m128 t2 = _mm_unpacklo_ps(Z, W), t3 = _mm_unpackhi_ps(Z, W);
        X = _mm_movelh_ps(t0, t2);
        Y = _mm_movehl_ps(t2, t0);
        Z = _mm_movelh_ps(t1, t3);
      }
      const __m128 rs2 = _mm_add_ps(_mm_mul_ps(X, X), _mm_mul_ps(Y, Y));
      const __m128 d2 = _mm_add_ps(rs2, _mm_mul_ps(Z, Z));
      const __m128 valid = _mm_and_ps(_mm_cmpge_ps(d2, v_min_r2), _mm_cmple_ps(d2, v_max_r2));
      const int valid_bits = _mm_movemask_ps(valid);
      if (valid_bits == 0) {
        for (int l = 0; l < 4; ++l) {
          if (kSubColumns) cell[i + l] = kNoCell;
          bins[i + l] = unknown_bin;
          rr[i + l] = 0.f;
          hh[i + l] = 0.f;
          labels[i + l] = kLabelUnknown;
          prob[i + l] = 0.f;
        }
        continue;
      }
      const __m128i valid_i = _mm_castps_si128(valid);
      // r (clamped at kMinR as below: maxps(a, b) = a > b ? a : b) and the row from z / r.
      const __m128 rc = _mm_max_ps(_mm_sqrt_ps(rs2), v_min_r);
      __m128 f = _mm_mul_ps(_mm_sub_ps(_mm_div_ps(Z, rc), v_t_min), v_inv_cell);
      f = _mm_min_ps(_mm_max_ps(f, v_zero), v_max_cell);
      // Column: octant reduction and the atan LUT index (0 for invalid lanes).
      const __m128 ax = _mm_and_ps(X, v_abs), ay = _mm_and_ps(Y, v_abs);
      const __m128 steep = _mm_cmpgt_ps(ay, ax);
      const __m128 mx = _mm_or_ps(_mm_and_ps(steep, ay), _mm_andnot_ps(steep, ax));
      const __m128 mn = _mm_or_ps(_mm_and_ps(steep, ax), _mm_andnot_ps(steep, ay));
      const __m128 tt = _mm_and_ps(_mm_div_ps(mn, mx), _mm_cmpgt_ps(mx, v_zero));
      // The octant's offset and sign as setParams() builds octant_offset_/octant_sign_:
      // offset = steep ? q : 0, then 2q - offset for x < 0, -offset for y < 0, + 2q; the sign
      // (+-1, so sign * lut only flips lut's sign bit) flips with each of the three.
      const __m128 neg_x = _mm_cmplt_ps(X, v_zero), neg_y = _mm_cmplt_ps(Y, v_zero);
      __m128 off = _mm_and_ps(steep, v_quarter);
      off = _mm_or_ps(_mm_and_ps(neg_x, _mm_sub_ps(v_half_turn, off)), _mm_andnot_ps(neg_x, off));
      off = _mm_or_ps(_mm_and_ps(neg_y, _mm_sub_ps(v_zero, off)), _mm_andnot_ps(neg_y, off));
      off = _mm_add_ps(off, v_half_turn);
      const __m128 flip = _mm_and_ps(_mm_xor_ps(_mm_xor_ps(steep, neg_x), neg_y), v_sign_bit);
      _mm_store_si128(reinterpret_cast<__m128i*>(row_i), _mm_and_si128(_mm_cvttps_epi32(f), valid_i));
      _mm_store_si128(
          reinterpret_cast<__m128i*>(lut_i),
          _mm_and_si128(_mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(tt, v_cells), v_half)), valid_i));
      const __m128 lut = _mm_setr_ps(atan_lut[lut_i[0]], atan_lut[lut_i[1]], atan_lut[lut_i[2]],
                                     atan_lut[lut_i[3]]);
      // a < max_c ? a : max_c is minps(a, max_c).
      const __m128 a = _mm_min_ps(_mm_add_ps(off, _mm_xor_ps(lut, flip)), v_max_c);
      __m128i row;
      if (kRing) {
        int ring[4];
        for (int l = 0; l < 4; ++l) {
          int rg = view.ring(i + l);
          if (ring_top >= 0) rg = ring_top - rg;
          ring[l] = rg < 0 ? 0 : (rg >= rows ? rows - 1 : rg);
        }
        row = _mm_setr_epi32(ring[0], ring[1], ring[2], ring[3]);
      } else {
        row = _mm_setr_epi32(row_lut[row_i[0]], row_lut[row_i[1]], row_lut[row_i[2]],
                             row_lut[row_i[3]]);
      }
      __m128i bin = _mm_add_epi32(_mm_sll_epi32(_mm_cvttps_epi32(a), v_shift), row);
      if (kSubColumns) {
        // The sub-column as the scalar loop computes it: trunc(min(x, L)) = min(trunc(x), L)
        // for an integer L.
        const __m128i sub = _mm_cvttps_epi32(_mm_min_ps(_mm_mul_ps(a, v_cells_per_column), v_last_sub));
        const __m128i c = _mm_or_si128(_mm_sll_epi32(row, v_cell_row_shift), sub);
        const uint32_t i0 = static_cast<uint32_t>(i);
        if (valid_bits == 0xF) {
          _mm_storeu_si128(reinterpret_cast<__m128i*>(cell + i), c);
          // The lanes from registers (a store and four loads of it would wait on forwarding).
          image[static_cast<uint32_t>(_mm_cvtsi128_si32(c))] = i0;
          image[static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(c, 0x55)))] = i0 + 1;
          image[static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(c, 0xAA)))] = i0 + 2;
          image[static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(c, 0xFF)))] = i0 + 3;
        } else {
          _mm_storeu_si128(reinterpret_cast<__m128i*>(cell + i),
                           _mm_or_si128(_mm_and_si128(valid_i, c), _mm_andnot_si128(valid_i, v_no_cell)));
          for (int l = 0; l < 4; ++l) {
            if (valid_bits >> l & 1) image[cell[i + l]] = i0 + static_cast<uint32_t>(l);
          }
        }
      }
      _mm_storeu_ps(rr + i, _mm_and_ps(rc, valid));
      _mm_storeu_ps(hh + i, _mm_and_ps(_mm_add_ps(Z, v_tz), valid));
      if (valid_bits != 0xF) {
        bin = _mm_or_si128(_mm_and_si128(valid_i, bin), _mm_andnot_si128(valid_i, v_unknown_bin));
        for (int l = 0; l < 4; ++l) {
          if (!(valid_bits >> l & 1)) {
            labels[i + l] = kLabelUnknown;
            prob[i + l] = 0.f;
          }
        }
      }
      _mm_storeu_si128(reinterpret_cast<__m128i*>(bins + i), bin);
    }
  }
#endif
  for (; i < n; ++i) {
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
      if (kSubColumns) cell[i] = kNoCell;
      bins[i] = unknown_bin;
      rr[i] = 0.f;
      hh[i] = 0.f;
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
      if (ring_top >= 0) row = ring_top - row;
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
    if (kSubColumns) {
      float sub = a * cells_per_column;
      sub = sub < last_sub ? sub : last_sub;
      const uint32_t c = static_cast<uint32_t>(row) << cell_row_shift_ | static_cast<uint32_t>(static_cast<int>(sub));
      cell[i] = c;
      image[c] = static_cast<uint32_t>(i);
    }
    rr[i] = r > kMinR ? r : kMinR;
    hh[i] = gz;
  }
}

void VerticalScanGround::classify(const PointCloudView& view, const SensorPose& pose,
                                  GroundClassification* out) {
  const std::size_t n = view.size();
  out->resize(n);
  const bool ring = view.hasRing();
  if (ring) readRingOrder(view);
  else last_rings_ = RingInfo();
  const int wanted_rows = ring ? kMaxRingRows : std::max(1, row_table_.rows());
  row_shift_ = 0;
  while ((1 << row_shift_) < wanted_rows) ++row_shift_;
  rows_ = 1 << row_shift_;
  const std::size_t bins = static_cast<std::size_t>(columns_) * rows_;
  r_.resize(n);
  height_.resize(n);
  bin_.resize(n);
  run_start_.resize(n + 1);
  // Bin `bins` (one past the grid) marks the unknown returns: never sorted, never fitted.
  unknown_bin_ = static_cast<uint32_t>(bins);
  bin_start_.resize(bins + 2);
  zeroFill(bin_start_.data(), bins + 2);
  if (n == 0) {
    // fitColumns() writes the knots; an empty scan leaves flat ground lines.
    knots_used_ = knots_;
    std::fill(knot_height_.begin(), knot_height_.end(), 0.f);
    std::fill(knot_support_.begin(), knot_support_.end(), 0.f);
    return;
  }

  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const bool tilted = !R.isIdentity(1e-6f) || t.x() != 0.f || t.y() != 0.f;
  const bool fast = view.packedFloatXYZ() &&
                    (view.height() <= 1 || view.layout().row_step == view.width() * view.layout().point_step);
  const bool sub = params_.laser_neighbours;
  if (sub) cell_.resize(n);
  // binPoints<ring, tilted, fast, sub> for the run-time flags.
  auto bin_with = [&](auto ring_c, auto tilted_c, auto fast_c) {
    if (sub) {
      binPoints<decltype(ring_c)::value, decltype(tilted_c)::value, decltype(fast_c)::value, true>(view, pose, out);
    } else {
      binPoints<decltype(ring_c)::value, decltype(tilted_c)::value, decltype(fast_c)::value, false>(view, pose, out);
    }
  };
  auto bin_tilted = [&](auto ring_c, auto fast_c) {
    if (tilted) bin_with(ring_c, std::true_type{}, fast_c);
    else bin_with(ring_c, std::false_type{}, fast_c);
  };
  if (ring && fast) bin_tilted(std::true_type{}, std::true_type{});
  else if (ring) bin_tilted(std::true_type{}, std::false_type{});
  else if (fast) bin_tilted(std::false_type{}, std::true_type{});
  else bin_tilted(std::false_type{}, std::false_type{});

  // Counting sort of the valid points by bin (3.3 step 1), by runs: consecutive points mostly
  // share a bin (a laser's sweep crosses a column in several returns), so the points are
  // counted and moved a run at a time. Unknown returns are neither counted nor moved.
  const uint32_t* __restrict bins_in = bin_.data();
  uint32_t* __restrict run_start = run_start_.data();
  uint32_t* __restrict count = bin_start_.data() + 1;
  std::size_t runs = 0;
  {
    // Run boundaries: the positions i > 0 whose bin differs from the bin of i - 1.
    run_start[runs++] = 0;
    std::size_t i = 1;
#if defined(__SSE2__)
    for (; i + 4 <= n; i += 4) {
      const __m128i here = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bins_in + i));
      const __m128i before = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bins_in + i - 1));
      unsigned changed = ~static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(here, before)))) & 0xFu;
      while (changed) {
        run_start[runs++] = static_cast<uint32_t>(i + __builtin_ctz(changed));
        changed &= changed - 1;
      }
    }
#endif
    for (; i < n; ++i) {
      if (bins_in[i] != bins_in[i - 1]) run_start[runs++] = static_cast<uint32_t>(i);
    }
    run_start[runs] = static_cast<uint32_t>(n);
  }
  for (std::size_t k = 0; k < runs; ++k) {
    count[bins_in[run_start[k]]] += run_start[k + 1] - run_start[k];
  }
  count[unknown_bin_] = 0;
  uint32_t acc = 0;
  for (std::size_t b = 0; b <= bins; ++b) {
    const uint32_t c = bin_start_[b + 1];
    bin_start_[b] = acc;
    acc += c;
  }
  bin_start_[bins + 1] = acc;
  order_h_.resize(acc);
  order_r_.resize(acc + kMaxRankBin);  // readable floats past the last bin
  {
    // Move r and height (not the point index: fitColumns() then reads a bin's representative
    // from the bin's own entries instead of gathering it from r_ and height_ all over the
    // scan); bin_start_[b] advances to the end of bin b, i.e. the start of bin b + 1. Within a
    // bin the points stay in input order.
    float* __restrict order_h = order_h_.data();
    float* __restrict order_r = order_r_.data();
    uint32_t* __restrict start = bin_start_.data();
    const float* __restrict r_in = r_.data();
    const float* __restrict h_in = height_.data();
    // The farthest valid return on the way: the ground lines are only needed out to it.
    float r_max = 0.f;
#if defined(__SSE2__)
    __m128 v_r_max = _mm_setzero_ps();
#endif
    for (std::size_t k = 0; k < runs; ++k) {
      const uint32_t from = run_start[k];
      const uint32_t len = run_start[k + 1] - from;
      const uint32_t b = bins_in[from];
      if (b == unknown_bin_) continue;
      const uint32_t at = start[b];
      start[b] = at + len;
      float* dr = order_r + at;
      float* dh = order_h + at;
      const float* sr = r_in + from;
      const float* sh = h_in + from;
#if defined(__SSE2__)
      if (len >= 4) {
        // Four at a time; the last four overlap the previous ones (same values).
        for (uint32_t q = 0; q + 4 < len; q += 4) {
          const __m128 rq = _mm_loadu_ps(sr + q);
          v_r_max = _mm_max_ps(v_r_max, rq);
          _mm_storeu_ps(dr + q, rq);
          _mm_storeu_ps(dh + q, _mm_loadu_ps(sh + q));
        }
        const __m128 r_last = _mm_loadu_ps(sr + len - 4);
        v_r_max = _mm_max_ps(v_r_max, r_last);
        _mm_storeu_ps(dr + len - 4, r_last);
        _mm_storeu_ps(dh + len - 4, _mm_loadu_ps(sh + len - 4));
        continue;
      }
#endif
      for (uint32_t q = 0; q < len; ++q) {
        dr[q] = sr[q];
        dh[q] = sh[q];
        r_max = sr[q] > r_max ? sr[q] : r_max;
      }
    }
#if defined(__SSE2__)
    {
      alignas(16) float m4[4];
      _mm_store_ps(m4, v_r_max);
      for (float m : m4) r_max = m > r_max ? m : r_max;
    }
#endif
    // Knot k + 1 is the farthest labelPoints() reads for r <= r_max (k = floor(r / L)).
    knots_used_ = knots_;
    const float reach = r_max * inv_segment_;
    if (reach < static_cast<float>(knots_)) {
      knots_used_ = std::min(knots_, std::max(2, static_cast<int>(reach) + 2));
    }
    for (int k = 0; k < kMaxRankBin; ++k) order_r[acc + k] = 0.f;
    // Shift back: bin b spans [bin_start_[b-1], bin_start_[b]) now; restore starts.
    for (std::size_t b = bins + 1; b > 0; --b) bin_start_[b] = bin_start_[b - 1];
    bin_start_[0] = 0;
  }
  fitColumns();
  labelPoints(out);
  if (sub) labelFromLaserNeighbours(pose.sensor_to_ground.translation().z(), out);
  if (sub && params_.local_ground) relabelFromLocalGround(out);
}

std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params) {
  return std::make_unique<VerticalScanGround>(params, "vertical_scan");
}

}  // namespace ladar_perception

