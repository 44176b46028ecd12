// Vertical scan ground extraction (thesis 3.3; equations restated in algorithms.md).
#include "ladar_perception/ground/vertical_scan.h"

#include "label_scan.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>  // the AVX2 median (target attribute; called only on an AVX2 CPU)
#endif

#include "ladar_perception/cloud/laser_elevations.h"

// The per-point and per-bin functions are compiled twice, for the x86-64 baseline (SSE2) and
// for x86-64-v3 (AVX2), and the loader picks the second on a CPU that has it (GCC function
// multiversioning, an ifunc per function). The source is the same: the SSE2 intrinsics get
// the three-operand VEX encoding (no register copies) and the compiler may vectorise scalar
// loops 8 wide. x86-64-v3 has FMA: CMakeLists.txt compiles this file with -ffp-contract=off,
// so no multiply-add is fused and both clones compute the same floats (the labels and
// P(obstacle) are bit-identical; see DEVELOPERS.md).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(LADAR_NO_CLONES)
#define LADAR_CLONES 1
#define LADAR_HOT_PATH __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define LADAR_HOT_PATH
#endif

namespace ladar_perception {

namespace {

// GCC's attribute on lambdas (clang rejects it after `mutable`, and inlines these lambdas
// without it).
#if defined(__GNUC__) && !defined(__clang__)
#define LADAR_ALWAYS_INLINE __attribute__((always_inline))
#else
#define LADAR_ALWAYS_INLINE
#endif

constexpr float kPi = 3.14159265358979f;
constexpr int kMaxRingRows = 128;   // rows of the bin grid when the cloud carries `ring`
constexpr uint32_t kNoCell = 0xFFFFFFFFu;  // laser_neighbours: the cell of an unknown return
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

// A point's sort key within its bin: the bits of r > 0 (which order like the floats) above the
// point index, so one integer comparison orders by r and then by input order.
inline uint64_t rangeKey(float r, uint32_t index) {
  uint32_t bits;
  std::memcpy(&bits, &r, 4);
  return (static_cast<uint64_t>(bits) << 32) | index;
}

// The position of the lower median of r[0..n) ordered by (r, position), n <= kMaxRankBin: the
// position whose rank (the number of entries before it in that order) is (n - 1) / 2. Reads
// kMaxRankBin floats from r.
constexpr int kMaxRankBin = 32;

inline int lowerMedianPositionByRank(const float* r, int n) {
  const int mid = (n - 1) / 2;
  for (int p = 0; p < n; ++p) {
    int rank = 0;
    for (int q = 0; q < n; ++q) rank += r[q] < r[p] || (r[q] == r[p] && q < p);
    if (rank == mid) return p;
  }
  return mid;  // unreachable: exactly one position has rank mid
}

#if defined(__SSE2__)
// NV = ceil(n / 4) vectors. The number of strictly smaller entries of every position at once;
// the positions where it equals mid hold the median's value, and the earliest position with
// that value has rank mid. When no position has exactly mid smaller entries, a run of equal
// values straddles the median: the exact rank test decides.
template <int NV>
inline LADAR_ALWAYS_INLINE int lowerMedianPositionSse(const float* r, int n) {
  const int mid = (n - 1) / 2;
  __m128 v[NV];
  __m128i less[NV];
  for (int k = 0; k < NV; ++k) {
    v[k] = _mm_loadu_ps(r + 4 * k);
    less[k] = _mm_setzero_si128();
  }
  for (int q = 0; q < n; ++q) {
    const __m128 rq = _mm_set1_ps(r[q]);
    for (int k = 0; k < NV; ++k) less[k] = _mm_sub_epi32(less[k], _mm_castps_si128(_mm_cmplt_ps(rq, v[k])));
  }
  const __m128i v_mid = _mm_set1_epi32(mid);
  unsigned at_mid = 0;
  for (int k = 0; k < NV; ++k) {
    at_mid |= static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(less[k], v_mid))))
              << (4 * k);
  }
  const unsigned in_bin = n >= 32 ? ~0u : (1u << n) - 1u;
  at_mid &= in_bin;
  if (at_mid == 0) return lowerMedianPositionByRank(r, n);
  const __m128 value = _mm_set1_ps(r[__builtin_ctz(at_mid)]);
  unsigned equal = 0;
  for (int k = 0; k < NV; ++k) {
    equal |= static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(v[k], value))) << (4 * k);
  }
  return __builtin_ctz(equal & in_bin);
}
#endif

#if defined(LADAR_CLONES)
// lowerMedianPositionSse with 8 lanes (NV = ceil(n / 8) vectors): the same counts, half the
// comparisons. Called only where the CPU has AVX2 (the AVX2 clone of fitColumns()).
template <int NV>
__attribute__((target("avx2"))) inline int lowerMedianPositionAvx2(const float* r, int n) {
  const int mid = (n - 1) / 2;
  __m256 v[NV];
  __m256i less[NV];
  for (int k = 0; k < NV; ++k) {
    v[k] = _mm256_loadu_ps(r + 8 * k);
    less[k] = _mm256_setzero_si256();
  }
  for (int q = 0; q < n; ++q) {
    const __m256 rq = _mm256_set1_ps(r[q]);
    for (int k = 0; k < NV; ++k) {
      less[k] = _mm256_sub_epi32(less[k], _mm256_castps_si256(_mm256_cmp_ps(rq, v[k], _CMP_LT_OQ)));
    }
  }
  const __m256i v_mid = _mm256_set1_epi32(mid);
  unsigned at_mid = 0;
  for (int k = 0; k < NV; ++k) {
    at_mid |= static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(less[k], v_mid))))
              << (8 * k);
  }
  const unsigned in_bin = n >= 32 ? ~0u : (1u << n) - 1u;
  at_mid &= in_bin;
  if (at_mid == 0) return lowerMedianPositionByRank(r, n);
  const __m256 value = _mm256_set1_ps(r[__builtin_ctz(at_mid)]);
  unsigned equal = 0;
  for (int k = 0; k < NV; ++k) {
    equal |= static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(v[k], value, _CMP_EQ_OQ))) << (8 * k);
  }
  return __builtin_ctz(equal & in_bin);
}

bool cpuHasAvx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
}
const bool kCpuHasAvx2 = cpuHasAvx2();
#endif

// Inlined into each clone of fitColumns() (compiled for its target).
inline LADAR_ALWAYS_INLINE int lowerMedianPosition(const float* r, int n) {
  if (n <= 2) return n == 2 && r[1] < r[0] ? 1 : 0;
#if defined(LADAR_CLONES)
  if (kCpuHasAvx2) {
    if (n <= 8) return lowerMedianPositionAvx2<1>(r, n);
    if (n <= 16) return lowerMedianPositionAvx2<2>(r, n);
    if (n <= 24) return lowerMedianPositionAvx2<3>(r, n);
    return lowerMedianPositionAvx2<4>(r, n);
  }
#endif
#if defined(__SSE2__)
  if (n <= 4) return lowerMedianPositionSse<1>(r, n);
  if (n <= 8) return lowerMedianPositionSse<2>(r, n);
  if (n <= 12) return lowerMedianPositionSse<3>(r, n);
  if (n <= 16) return lowerMedianPositionSse<4>(r, n);
  if (n <= 24) return lowerMedianPositionSse<6>(r, n);
  return lowerMedianPositionSse<8>(r, n);
#else
  return lowerMedianPositionByRank(r, n);
#endif
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

LADAR_HOT_PATH float estimateSlope(const float* r, const float* height, int n, const VerticalScanParams& p,
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
    const float next = sum_ws / sum_w;
    // At the fixed point every further iteration returns the same value: stop early.
    if (next == estimate) break;
    estimate = next;
  }
  return estimate;
}

LADAR_HOT_PATH int trackGroundLine(const float* r, const float* height, int n, const VerticalScanParams& p,
                    float slope0, int knots, float* knot_height, float* knot_support,
                    float* scratch) {
  float* gr = scratch;           // accepted ground returns, starting with the sensor's
  float* gh = scratch + n + 1;   // ground point (0, 0)
  int m = 0;
  gr[m] = 0.f;
  gh[m] = 0.f;
  ++m;
  // Until the first ground return: the straight estimate, rising at most track_first_slope_max.
  float slope = slope0;
  if (p.track_first_slope_max > 0.f) slope = std::min(slope, p.track_first_slope_max);
  int anchor = 0;
  bool last_steep = false;  // the newest ground return was a step (steeper than ground_slope_max)
  // Returns below the extrapolation that agree with each other: where the ground reappears
  // lower (behind an obstacle the line went over, or down a ditch wider than a pothole).
  int below_first = -1, below_last = -1;
  bool hole = false;
  const float hole_depth =
      p.negative_gnd_error_max > 0.f ? p.negative_gnd_error_max : p.tolerances.gnd_error_max_base;
  for (int i = 0; i < n; ++i) {
    const float dr = r[i] - gr[m - 1];
    const float dh = height[i] - gh[m - 1];
    const float gap = dr > 0.f ? dr : 0.f;
    const float grow = p.track_tolerance_per_m * gap;
    const float grow_drop = p.track_drop_per_m * gap;
    const float res = dh - slope * dr;
    // Before the first ground return the extrapolation is the straight estimate from the
    // sensor's ground point, which the lower half of a near vertical surface (a parked car's
    // side, below eq 3.5's mean height) tilts upward: the road in front of it may then lie
    // well below the line. Until a return is accepted, the line is trusted no more below than
    // above (track_max_step); after that the drop tolerance applies.
    const float drop = m == 1 ? std::max(p.track_max_drop, p.track_max_step) : p.track_max_drop;
    // The drop tolerance grows with the gap since the last ground return, for the sparser
    // returns at range (by track_drop_per_m, slower than a step's). A gap that a hole opened
    // (returns seen well below the line since the last ground return: a pothole's floor) was
    // not unobserved terrain, so there it does not grow; otherwise the line follows the
    // pothole's far wall down and its floor becomes ground.
    if (res < -(drop + (hole ? 0.f : grow_drop))) {
      if (res < -(drop + grow_drop + hole_depth)) hole = true;
      // Below the line: remember a run of mutually consistent returns, each continuing the
      // previous level or at the line's slope (ground that falls away behind an obstacle,
      // e.g. an embankment into a ditch), or anything in between.
      const float run_dr = below_last >= 0 ? r[i] - r[below_last] : 0.f;
      const float run_dh = below_last >= 0 ? height[i] - height[below_last] : 0.f;
      const float run_tol = p.track_max_drop + p.track_tolerance_per_m * run_dr + 0.05f;
      const float along = slope * run_dr;
      if (below_last >= 0 && run_dh < std::max(along, 0.f) + run_tol &&
          run_dh > std::min(along, 0.f) - run_tol) {
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
      hole = false;
      last_steep = false;
      continue;
    }
    if (res > p.track_max_step + grow || dh > p.track_max_step + p.ground_slope_max * dr) continue;
    const float local = dh / (std::fabs(dr) + 0.02f);
    if (local > p.track_max_local_slope || local < p.track_min_local_slope) continue;
    if (dr <= 0.f) continue;  // same distance as the last ground return: keep the first
    below_first = below_last = -1;
    hole = false;
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
  int k = 0;
  for (; k < knots; ++k) {
    const float rk = static_cast<float>(k) * L;
    while (j + 1 < m && gr[j + 1] < rk) ++j;
    if (j + 1 >= m) break;  // beyond the last ground return: the extrapolated tail below
    const float t = (rk - gr[j]) / std::max(gr[j + 1] - gr[j], 1e-3f);
    const float h = gh[j] + (gh[j + 1] - gh[j]) * std::min(std::max(t, 0.f), 1.f);
    const float dist = std::min(rk - gr[j], gr[j + 1] - rk);
    knot_height[k] = h;
    knot_support[k] = 1.f / (1.f + std::max(dist, 0.f));
  }
  // The tail: the line extrapolated from the last ground return with the current slope.
  const float last_r = gr[m - 1], last_h = gh[m - 1];
#if defined(__SSE2__)
  {
    const __m128 v_L = _mm_set1_ps(L), v_last_r = _mm_set1_ps(last_r);
    const __m128 v_last_h = _mm_set1_ps(last_h), v_slope = _mm_set1_ps(slope);
    const __m128 v_zero = _mm_setzero_ps(), v_one = _mm_set1_ps(1.f);
    for (; k + 4 <= knots; k += 4) {
      const __m128 rk = _mm_mul_ps(_mm_cvtepi32_ps(_mm_setr_epi32(k, k + 1, k + 2, k + 3)), v_L);
      const __m128 dist = _mm_sub_ps(rk, v_last_r);
      _mm_storeu_ps(knot_height + k, _mm_add_ps(v_last_h, _mm_mul_ps(v_slope, dist)));
      // std::max(dist, 0.f) is dist < 0 ? 0 : dist, i.e. maxps(0, dist).
      _mm_storeu_ps(knot_support + k,
                    _mm_div_ps(v_one, _mm_add_ps(v_one, _mm_max_ps(v_zero, dist))));
    }
  }
#endif
  for (; k < knots; ++k) {
    const float rk = static_cast<float>(k) * L;
    const float dist = rk - last_r;
    knot_height[k] = last_h + slope * dist;
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
    local_grid_.assign(2 * static_cast<std::size_t>(columns_) * local_rings_, 0.f);
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

int VerticalScanGround::columnOf(float x, float y) const {
  return static_cast<int>(columnCoordinate(x, y));
}

float VerticalScanGround::groundHeight(int col, float r) const {
  vertical_scan::GroundLine line{&knot_height_[kKnotPad + static_cast<std::size_t>(col) * knot_stride_], knots_used_,
                                 inv_segment_};
  return line.heightAt(r);
}

template <bool kRing, bool kTilted, bool kFastXYZ, bool kSubColumns>
LADAR_HOT_PATH void VerticalScanGround::binPoints(const PointCloudView& view, const SensorPose& pose,
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
          const int rg = view.ring(i + l);
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

LADAR_HOT_PATH void VerticalScanGround::fitColumns() {
  const VerticalScanParams& p = params_;
  const int rows = rows_;
  col_r_.resize(static_cast<std::size_t>(columns_) * rows);
  col_h_.resize(col_r_.size());
  col_w_.resize(4 * (static_cast<std::size_t>(rows) + 1));
  // (r, height) pairs per bin after a sentinel pair for bin -1, and one for bin `bins` after
  // them; r = -1 marks an empty bin.
  rep_.assign(2 * (static_cast<std::size_t>(columns_) * rows + 2), -1.f);
  float* rep_rh = rep_.data() + 2;
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
      // The lower median by (r, input order) of the bin's points (their position in the bin
      // orders like their input index).
      uint32_t rep;
      if (cnt <= kMaxRankBin) {
        rep = begin + lowerMedianPosition(&order_r_[begin], cnt);
      } else {
        // Large bins (slow spin, duplicated points): partial selection on (r, position) keys.
        big_bin_.resize(cnt);
        for (int q = 0; q < cnt; ++q) {
          big_bin_[q] = rangeKey(order_r_[begin + q], static_cast<uint32_t>(q));
        }
        const int mid = (cnt - 1) / 2;
        std::nth_element(big_bin_.begin(), big_bin_.begin() + mid, big_bin_.end());
        rep = begin + static_cast<uint32_t>(big_bin_[mid]);
      }
      const float rep_r = order_r_[rep], rep_h = order_h_[rep];
      cr[m] = rep_r;
      ch[m] = rep_h;
      rep_rh[2 * b] = rep_r;
      rep_rh[2 * b + 1] = rep_h;
      ++m;
    }
    insertionSort(cr, ch, m);
    col_count[c] = m;
    int support = 0;
    if (p.bend_ground_line) {
      // The seed of the bent line: the straight estimate over the returns off vertical
      // surfaces. The lower half of a parked car's side or a person a few metres away lies
      // below eq 3.5's mean height and would tilt the estimate upward, so that the road in
      // front of it falls below the extrapolated line and the obstacle's lower part is
      // tracked as ground. A representative is on a vertical surface when the height step to
      // its neighbour in r on either side exceeds track_max_step + ground_slope_max * dr.
      float* vr = col_w_.data() + 2 * (rows + 1);
      float* vh = vr + (rows + 1);
      int mv = 0;
      bool steep_before = false;  // the step from q - 1 to q (each step is tested once)
      for (int q = 0; q < m; ++q) {
        const bool steep_after =
            q + 1 < m && std::fabs(ch[q + 1] - ch[q]) > p.track_max_step + p.ground_slope_max * (cr[q + 1] - cr[q]);
        if (!steep_before && !steep_after) {
          vr[mv] = cr[q];
          vh[mv] = ch[q];
          ++mv;
        }
        steep_before = steep_after;
      }
      column_slope_[c] = vertical_scan::estimateSlope(vr, vh, mv, p, 0.f, col_w_.data(), &support);
    } else {
      column_slope_[c] = vertical_scan::estimateSlope(cr, ch, m, p, 0.f, col_w_.data(), &support);
    }
    col_n[c] = support;
  }

  // Column coupling of the straight estimate (beyond the thesis): a column with too few
  // feasible returns (occluded by a nearby obstacle) takes its neighbours' support-weighted
  // estimate.
  if (p.couple_columns && p.coupling_radius > 0) {
    slope_coupled_.resize(columns_);
    for (int c = 0; c < columns_; ++c) {
      if (col_n[c] >= p.min_ground_returns) {
        slope_coupled_[c] = column_slope_[c];
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
      slope_coupled_[c] = sw > 0.f ? sws / sw : column_slope_[c];
    }
    for (int c = 0; c < columns_; ++c) column_slope_[c] = slope_coupled_[c];
  }

  // The ground line of each column, out to the scan's farthest return (knots_used_; the knots
  // beyond are not read).
  const int K = knot_stride_;  // the stride of a column's knots
  const int KU = knots_used_;
  for (int c = 0; c < columns_; ++c) {
    float* kh = &knot_height_[kKnotPad + static_cast<std::size_t>(c) * K];
    float* ks = &knot_support_[static_cast<std::size_t>(c) * K];
    if (p.bend_ground_line) {
      vertical_scan::trackGroundLine(&col_r_[static_cast<std::size_t>(c) * rows],
                                     &col_h_[static_cast<std::size_t>(c) * rows], col_count[c], p,
                                     column_slope_[c], KU, kh, ks, col_w_.data());
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
        nb_height[j + RR] = &knot_height_[kKnotPad + static_cast<std::size_t>(cc) * K];
        nb_support[j + RR] = &knot_support_[static_cast<std::size_t>(cc) * K];
      }
      float* dst = &coupled_[kKnotPad + static_cast<std::size_t>(c) * K];
      dst[0] = 0.f;
      int k = 1;
#if defined(__SSE2__)
      // Four knots at a time; every lane sums over j in the same order as the loop below.
      {
        const float* own_h = &knot_height_[kKnotPad + static_cast<std::size_t>(c) * K];
        const float* own_s = &knot_support_[static_cast<std::size_t>(c) * K];
        const __m128 v_keep = _mm_set1_ps(0.66f), v_eps = _mm_set1_ps(1e-3f);
        for (; k + 4 <= KU; k += 4) {
          __m128 sw = _mm_setzero_ps(), swh = _mm_setzero_ps();
          for (int j = 0; j <= 2 * RR; ++j) {
            const __m128 w = _mm_mul_ps(_mm_add_ps(_mm_loadu_ps(nb_support[j] + k), v_eps),
                                        _mm_set1_ps(kernel[j]));
            sw = _mm_add_ps(sw, w);
            swh = _mm_add_ps(swh, _mm_mul_ps(w, _mm_loadu_ps(nb_height[j] + k)));
          }
          const __m128 keep = _mm_cmpge_ps(_mm_loadu_ps(own_s + k), v_keep);
          const __m128 h = _mm_or_ps(_mm_and_ps(keep, _mm_loadu_ps(own_h + k)),
                                     _mm_andnot_ps(keep, _mm_div_ps(swh, sw)));
          _mm_storeu_ps(dst + k, h);
        }
      }
#endif
      for (; k < KU; ++k) {
        // A knot within half a metre of the column's own ground return keeps its height.
        const std::size_t own = static_cast<std::size_t>(c) * K + k;
        if (knot_support_[own] >= 0.66f) {
          dst[k] = knot_height_[kKnotPad + own];
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

LADAR_HOT_PATH void VerticalScanGround::labelPoints(GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const ObstacleToleranceParams& tol = p.tolerances;
  const std::size_t n = bin_.size();
  const uint32_t rows = static_cast<uint32_t>(rows_);
  const int shift = row_shift_;
  const int K = knot_stride_;  // the stride of a column's knots
  const int last_k = knots_ - 2;
  const float inv_seg = inv_segment_;
  const float thr = tol.obstacle_threshold;
  const bool negative = p.negative_obstacles;
  const bool vertical = p.vertical_surfaces;
  const float inv_v_gnd = 1.f / std::max(p.vertical_gnd_error_max, 1e-4f);
  const float inv_v_slope = 1.f / std::max(p.vertical_slope_max, 1e-4f);
  const bool foot = vertical && p.vertical_foot_slope > 0.f;
  const float inv_foot = foot ? 1.f / p.vertical_foot_slope : 0.f;
  // Negative obstacles only where the line is supported (negative_support_distance).
  const bool support_gate = negative && p.negative_support_distance > 0.f;
  const float min_support = support_gate ? 1.f / (1.f + p.negative_support_distance) : 0.f;
  const float* __restrict support = knot_support_.data();
  // Eq 3.15's range-growing tolerances; GndErrorMax may differ below the line.
  const float g_above = tol.gnd_error_max_base;
  // g_below as g_above + (g_below - g_above), the sum the 4-wide loop forms per lane.
  const float g_below_delta = (p.negative_gnd_error_max > 0.f ? p.negative_gnd_error_max : g_above) - g_above;
  const float g_below = g_above + g_below_delta;
  const float g_per_m = tol.gnd_error_max_per_m;
  const float s_base = tol.slope_error_max_base;
  const float s_per_m = tol.slope_error_max_per_m;
  const float* __restrict rep = rep_.data() + 2;  // rep[2b], rep[2b + 1]: bin b's r, height
  const float* __restrict knots = knot_height_.data() + kKnotPad;
  const uint32_t* __restrict bins = bin_.data();
  const float* __restrict rr = r_.data();
  const float* __restrict hh = height_.data();
  uint8_t* __restrict labels = out->labels.data();
  float* __restrict prob = out->p_obstacle.data();
  // P_vertical of one return (see below), given its GndError factor g, its height-above-the-
  // foot factor g_foot and eq 3.15's P.
  auto vertical_probability = [=](uint32_t b, float r, float h, float g, float g_foot, float prob_i) {
    const uint32_t row = b & (rows - 1);
    float local = -1.f;
    const float* lo = rep + 2 * (b - 1);  // the row below
    const float* hi = rep + 2 * (b + 1);  // the row above
    if (row > 0 && lo[0] >= 0.f) {
      local = std::fabs(h - lo[1]) / (std::fabs(r - lo[0]) + 0.02f);
    }
    if (row + 1 < rows && hi[0] >= 0.f) {
      const float sl = std::fabs(h - hi[1]) / (std::fabs(r - hi[0]) + 0.02f);
      local = local < 0.f ? sl : (sl < local ? sl : local);
    }
    float v = local > 0.f ? local * inv_v_slope : 0.f;  // no row below or above: 0
    v = v < 1.f ? v : 1.f;
    const float pv = g * v;
    float best = pv > prob_i ? pv : prob_i;
    if (foot && row + 1 < rows && hi[0] >= 0.f) {
      // The foot of a face: the row above rises from this return at least as steeply as
      // vertical_foot_slope; scored by the height above the foot.
      float u = (hi[1] - h) / (std::fabs(r - hi[0]) + 0.02f) * inv_foot;
      u = u < 1.f ? u : 1.f;
      const float pf = g_foot * u;
      best = pf > best ? pf : best;
    }
    return best;
  };
  // P of a return below the line that eq 3.15 calls a negative obstacle (P > threshold): kept
  // where the column's ground returns support the line's knot k or k + 1
  // (negative_support_distance), else P_vertical alone, with the depth below the line as the
  // GndError factor (no foot term).
  auto below_line_probability = [=](uint32_t b, float r, float h, float prob_i) {
    const std::size_t col = b >> shift;
    int k = static_cast<int>(r * inv_seg);  // the line's segment at r, as in GroundLine::heightAt
    k = k < last_k ? k : last_k;
    const float* ks = support + col * K + k;
    if (ks[0] >= min_support || ks[1] >= min_support) return prob_i;
    if (!vertical) return 0.f;
    const float ground = vertical_scan::GroundLine{knots + col * K, last_k + 2, inv_seg}.heightAt(r);
    float g = (ground - h) * inv_v_gnd;
    g = g < 1.f ? g : 1.f;
    return vertical_probability(b, r, h, g, 0.f, 0.f);
  };
  std::size_t i = 0;
  below_line_listed_ = false;
  deep_listed_ = false;
#if defined(__SSE2__)
  // Four returns at a time, each lane repeating the scalar loop's arithmetic below (minps(a, b)
  // is a < b ? a : b); the knot index col * K + k is formed in float, exact below 2^24.
  if (static_cast<double>(columns_) * K < 16777216.0) {
    const __m128 v_inv_seg = _mm_set1_ps(inv_seg);
    const __m128 v_last_k = _mm_set1_ps(static_cast<float>(last_k));
    const __m128 v_K = _mm_set1_ps(static_cast<float>(K));
    const __m128 v_zero = _mm_setzero_ps(), v_one = _mm_set1_ps(1.f);
    const __m128 v_abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 v_sign = _mm_castsi128_ps(_mm_set1_epi32(static_cast<int>(0x80000000u)));
    const __m128 v_g_above = _mm_set1_ps(g_above), v_g_below_delta = _mm_set1_ps(g_below_delta);
    const __m128 v_g_per_m = _mm_set1_ps(g_per_m);
    const __m128 v_s_base = _mm_set1_ps(s_base), v_s_per_m = _mm_set1_ps(s_per_m);
    const __m128 v_thr = _mm_set1_ps(thr), v_inv_v_gnd = _mm_set1_ps(inv_v_gnd);
    const __m128i v_invalid = _mm_set1_epi32(static_cast<int>(unknown_bin_));
    const __m128i v_shift = _mm_cvtsi32_si128(shift);
    // Label bytes of four lanes from their obstacle bits and their unknown bits.
    static_assert(kLabelGround == 0, "label bytes assume ground = 0");
    uint32_t obstacle_bytes[16], unknown_bytes[16];
    for (int m = 0; m < 16; ++m) {
      obstacle_bytes[m] = unknown_bytes[m] = 0;
      for (int l = 0; l < 4; ++l) {
        if (m >> l & 1) {
          obstacle_bytes[m] |= static_cast<uint32_t>(kLabelObstacle) << (8 * l);
          unknown_bytes[m] |= static_cast<uint32_t>(kLabelUnknown) << (8 * l);
        }
      }
    }
    alignas(16) int32_t knot_i[4];
    const __m128i v_row_mask = _mm_set1_epi32(static_cast<int>(rows - 1));
    const __m128i v_invalid_all = _mm_set1_epi32(-1);
    const __m128 v_pad = _mm_set1_ps(0.02f);
    const __m128 v_inv_v_slope = _mm_set1_ps(inv_v_slope);
    const __m128 v_inv_foot = _mm_set1_ps(inv_foot);
    // Groups of four with a negative obstacle: (group << 4) | lane bits, revisited after the
    // loop by below_line_probability() (negative_support_distance).
    below_line_groups_.resize(support_gate ? n / 4 + 1 : 0);
    uint32_t* const below_groups = below_line_groups_.data();
    std::size_t below_count = 0;
    // laser_neighbours: groups of four with a return more than about g_below under the line
    // (the floor or wall of a hole: labelFromLaserNeighbours() looks above them).
    const bool list_deep = p.laser_neighbours;
    deep_groups_.resize(list_deep ? n / 4 + 1 : 0);
    uint32_t* const deep_groups = deep_groups_.data();
    std::size_t deep_count = 0;
    const __m128 v_deep = _mm_set1_ps(g_below - 1e-3f);
    // The loop, specialised for the default settings (every term on, SlopeErrorMax constant)
    // so that their tests leave it; any other combination runs the same code with run-time
    // tests. It captures by value: the label stores (bytes) may alias anything it read
    // through a reference, which would be reloaded after every store.
    auto sse_loop = [=, &below_count, &deep_count](auto negative_c, auto vertical_c, auto foot_c, auto support_gate_c,
                                      auto growing_slope_tolerance_c, auto deep_c) mutable LADAR_ALWAYS_INLINE {
      for (; i + 4 <= n; i += 4) {
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bins + i));
        const __m128i invalid = _mm_cmpeq_epi32(b, v_invalid);
        const int invalid_bits = _mm_movemask_ps(_mm_castsi128_ps(invalid));
        if (invalid_bits == 0xF) continue;  // binPoints labelled them unknown
        const __m128 r = _mm_loadu_ps(rr + i);
        const __m128 h = _mm_loadu_ps(hh + i);
        // The column's ground line at r.
        const __m128 col = _mm_cvtepi32_ps(_mm_srl_epi32(b, v_shift));
        const __m128 f = _mm_mul_ps(r, v_inv_seg);
        const __m128 kf = _mm_min_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(f)), v_last_k);
        _mm_store_si128(reinterpret_cast<__m128i*>(knot_i),
                        _mm_andnot_si128(invalid, _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(col, v_K), kf))));
        // Each lane's kh[k - 1], kh[k], kh[k + 1] (and kh[k + 2]) in one 16-byte load, then
        // transposed (the knot array is padded before and after: in bounds for every lane).
        const __m128 q0 = _mm_loadu_ps(knots + knot_i[0] - 1), q1 = _mm_loadu_ps(knots + knot_i[1] - 1);
        const __m128 q2 = _mm_loadu_ps(knots + knot_i[2] - 1), q3 = _mm_loadu_ps(knots + knot_i[3] - 1);
        const __m128 t0 = _mm_unpacklo_ps(q0, q1), t1 = _mm_unpacklo_ps(q2, q3);
        const __m128 k0 = _mm_movehl_ps(t1, t0);  // kh[k] of lanes 0..3
        const __m128 k1 = _mm_movelh_ps(_mm_unpackhi_ps(q0, q1), _mm_unpackhi_ps(q2, q3));  // kh[k + 1]
        const __m128 ground = _mm_add_ps(k0, _mm_mul_ps(_mm_sub_ps(k1, k0), _mm_sub_ps(f, kf)));
        // Eqs 3.10, 3.11, 3.15 as below.
        __m128 gnd_error = _mm_sub_ps(ground, h);
        if (!negative_c) gnd_error = _mm_andnot_ps(_mm_cmpgt_ps(gnd_error, v_zero), gnd_error);
        const __m128 abs_error = _mm_and_ps(gnd_error, v_abs);
        const __m128 above = _mm_cmpgt_ps(gnd_error, v_zero);
        const int below_line_bits = support_gate_c ? _mm_movemask_ps(above) : 0;  // GndError > 0
        if (deep_c) {
          const int deep_bits = _mm_movemask_ps(_mm_cmpgt_ps(gnd_error, v_deep)) & ~invalid_bits;
          if (deep_bits) deep_groups[deep_count++] = static_cast<uint32_t>(i >> 2) << 4 | deep_bits;
        }
        const __m128 g_max =
            _mm_add_ps(_mm_add_ps(v_g_above, _mm_and_ps(above, v_g_below_delta)), _mm_mul_ps(v_g_per_m, r));
        // SlopeErrorMax = s_base + s_per_m * r, exactly s_base when it does not grow.
        const __m128 s_max = growing_slope_tolerance_c ? _mm_add_ps(v_s_base, _mm_mul_ps(v_s_per_m, r)) : v_s_base;
        const __m128 gt = _mm_min_ps(_mm_div_ps(abs_error, g_max), v_one);
        const __m128 st = _mm_min_ps(_mm_div_ps(abs_error, _mm_mul_ps(r, s_max)), v_one);
        __m128 p4v = _mm_mul_ps(gt, st);
        if (vertical_c) {
          // g_foot (the height-above-the-foot factor; g itself without the foot term) gates both
          // terms; the GndError factor g is needed only where they run.
          __m128 above_foot;
          if (foot_c) {
            // The foot: the lowest of the line at r and the knots k and k - 1, as below.
            // kh[k - 1] is the spare knot 0 before the column (kh[0] = 0) for k = 0.
            const __m128 kp = _mm_movelh_ps(t0, t1);
            above_foot = _mm_sub_ps(h, _mm_min_ps(_mm_min_ps(kp, k0), ground));
          } else {
            above_foot = _mm_xor_ps(gnd_error, v_sign);
          }
          const __m128 g_foot = _mm_min_ps(_mm_mul_ps(above_foot, v_inv_v_gnd), v_one);
          // g_foot > thr && g_foot > P as one comparison.
          const __m128 need = _mm_cmpgt_ps(g_foot, _mm_max_ps(v_thr, p4v));
          const int need_bits = _mm_movemask_ps(need) & ~invalid_bits;
          if (need_bits) {
            const __m128 g =
                foot_c ? _mm_min_ps(_mm_mul_ps(_mm_xor_ps(gnd_error, v_sign), v_inv_v_gnd), v_one) : g_foot;
            // vertical_probability() on four lanes; the sentinel pairs keep the reads of rows
            // below and above in bounds (unknown lanes read bin 0's).
            const __m128i bv = _mm_andnot_si128(invalid, b);
            alignas(16) uint32_t b4[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(b4), bv);
            const __m128 hi01 = _mm_unpacklo_ps(
                _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[0] + 2)),
                _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[1] + 2)));
            const __m128 hi23 = _mm_unpacklo_ps(
                _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[2] + 2)),
                _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[3] + 2)));
            const __m128 r_hi = _mm_movelh_ps(hi01, hi23), h_hi = _mm_movehl_ps(hi23, hi01);
            const __m128i row = _mm_and_si128(bv, v_row_mask);
            const __m128 has_hi = _mm_and_ps(_mm_castsi128_ps(_mm_cmplt_epi32(row, v_row_mask)),
                                             _mm_cmpge_ps(r_hi, v_zero));
            // |h - h_hi| / d is |(h_hi - h) / d| exactly (d > 0; IEEE division is symmetric in
            // sign): the rise to the row above serves both terms.
            const __m128 rise = _mm_div_ps(_mm_sub_ps(h_hi, h),
                                           _mm_add_ps(_mm_and_ps(_mm_sub_ps(r, r_hi), v_abs), v_pad));
            // pv > prob ? pv : prob is maxps(pv, prob).
            __m128 best = p4v;
            if (foot_c) {
              // The foot of a face (vertical_probability()), where the row above exists.
              const __m128 u = _mm_min_ps(_mm_mul_ps(rise, v_inv_foot), v_one);
              best = _mm_or_ps(_mm_and_ps(has_hi, _mm_max_ps(_mm_mul_ps(g_foot, u), p4v)), _mm_andnot_ps(has_hi, p4v));
            }
            // P_vertical = g * v <= g (v in [0, 1]) raises P only where g exceeds it so far; the
            // row below is read only there.
            if (_mm_movemask_ps(_mm_cmpgt_ps(g, best)) & need_bits) {
              const __m128 lo01 = _mm_unpacklo_ps(
                  _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[0] - 2)),
                  _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[1] - 2)));
              const __m128 lo23 = _mm_unpacklo_ps(
                  _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[2] - 2)),
                  _mm_loadl_pi(v_zero, reinterpret_cast<const __m64*>(rep + 2 * b4[3] - 2)));
              const __m128 r_lo = _mm_movelh_ps(lo01, lo23), h_lo = _mm_movehl_ps(lo23, lo01);
              const __m128 has_lo = _mm_and_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(row, _mm_setzero_si128())),
                                               _mm_cmpge_ps(r_lo, v_zero));
              const __m128 sl_lo = _mm_div_ps(_mm_and_ps(_mm_sub_ps(h, h_lo), v_abs),
                                              _mm_add_ps(_mm_and_ps(_mm_sub_ps(r, r_lo), v_abs), v_pad));
              const __m128 sl_hi = _mm_and_ps(rise, v_abs);
              // Both: the smaller (minps(sl_hi, sl_lo) = sl_hi < sl_lo ? sl_hi : sl_lo); one of
              // them: that one; neither: 0.
              const __m128 one_side = _mm_or_ps(_mm_and_ps(has_lo, sl_lo), _mm_andnot_ps(has_lo, _mm_and_ps(has_hi, sl_hi)));
              const __m128 both = _mm_and_ps(has_lo, has_hi);
              const __m128 local = _mm_or_ps(_mm_and_ps(both, _mm_min_ps(sl_hi, sl_lo)),
                                             _mm_andnot_ps(both, one_side));
              const __m128 v = _mm_min_ps(_mm_mul_ps(local, v_inv_v_slope), v_one);
              best = _mm_max_ps(_mm_mul_ps(g, v), best);
            }
            const __m128 take = _mm_and_ps(need, _mm_castsi128_ps(_mm_andnot_si128(invalid, v_invalid_all)));
            p4v = _mm_or_ps(_mm_and_ps(take, best), _mm_andnot_ps(take, p4v));
          }
        }
        p4v = _mm_andnot_ps(_mm_castsi128_ps(invalid), p4v);  // unknown: 0 as binPoints wrote
        int obstacle_bits = _mm_movemask_ps(_mm_cmpgt_ps(p4v, v_thr)) & ~invalid_bits;
        if (support_gate_c) {
          // Negative obstacles are rare: their groups are listed.
          const int below_bits = obstacle_bits & below_line_bits;
          if (below_bits) below_groups[below_count++] = static_cast<uint32_t>(i >> 2) << 4 | below_bits;
        }
        _mm_storeu_ps(prob + i, p4v);
        const uint32_t label4 = obstacle_bytes[obstacle_bits] | unknown_bytes[invalid_bits];
        std::memcpy(labels + i, &label4, 4);
      }
      return i;
    };
    if (negative && vertical && foot && support_gate && s_per_m == 0.f) {
      if (list_deep) {
        i = sse_loop(std::true_type{}, std::true_type{}, std::true_type{}, std::true_type{}, std::false_type{},
                     std::true_type{});
        deep_count_ = deep_count;
        deep_listed_ = true;
      } else {
        i = sse_loop(std::true_type{}, std::true_type{}, std::true_type{}, std::true_type{}, std::false_type{},
                     std::false_type{});
      }
    } else {
      i = sse_loop(negative, vertical, foot, support_gate, true, std::false_type{});
    }
    for (std::size_t c = 0; c < below_count; ++c) {
      const std::size_t group = static_cast<std::size_t>(below_groups[c] >> 4) * 4;
      for (unsigned bits = below_groups[c] & 15u; bits; bits &= bits - 1) {
        const std::size_t q = group + static_cast<std::size_t>(__builtin_ctz(bits));
        prob[q] = below_line_probability(bins[q], rr[q], hh[q], prob[q]);
        labels[q] = prob[q] > thr ? kLabelObstacle : kLabelGround;
      }
    }
    below_line_count_ = below_count;
    below_line_listed_ = support_gate;
  }
#endif
  below_line_from_ = i;
  for (; i < n; ++i) {
    const uint32_t b = bins[i];
    if (b == unknown_bin_) continue;
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
    if (vertical) {
      // P_vertical = max(GndError factor * local slope factor, height above the foot factor *
      // rise to the row above factor), evaluated only where it can reach the threshold (the
      // foot's height factor, never below the GndError one, exceeds it). The foot is the lowest
      // of the line and its two knots before r: where the piecewise line smears a step over a
      // segment (a curb face, the bottom of a car's side), the height above the ground in
      // front of the step, also when a knot falls between the last ground return and the face.
      float g = -gnd_error * inv_v_gnd;
      g = g < 1.f ? g : 1.f;
      const float fk = k > 0 && kh[k - 1] < kh[k] ? kh[k - 1] : kh[k];
      const float foot_h = fk < ground ? fk : ground;
      float g_foot = foot ? (h - foot_h) * inv_v_gnd : g;
      g_foot = g_foot < 1.f ? g_foot : 1.f;
      if (g_foot > thr && g_foot > prob_i) prob_i = vertical_probability(b, r, h, g, g_foot, prob_i);
    }
    if (support_gate && prob_i > thr && gnd_error > 0.f) prob_i = below_line_probability(b, r, h, prob_i);
    prob[i] = prob_i;
    labels[i] = prob_i > thr ? kLabelObstacle : kLabelGround;
  }
}

LADAR_HOT_PATH void VerticalScanGround::labelFromLaserNeighbours(float sensor_height, GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const ObstacleToleranceParams& tol = p.tolerances;
  const std::size_t n = bin_.size();
  const uint32_t rows = static_cast<uint32_t>(rows_);
  const int shift = row_shift_;
  const uint32_t* __restrict bins = bin_.data();
  const float* __restrict rr = r_.data();
  const float* __restrict hh = height_.data();
  uint8_t* __restrict labels = out->labels.data();
  float* __restrict prob = out->p_obstacle.data();
  const uint32_t* __restrict cell = cell_.data();     // written by binPoints()
  const uint32_t* __restrict image = range_image_.data();
  const float thr = tol.obstacle_threshold;
  const float g_below = p.negative_gnd_error_max > 0.f ? p.negative_gnd_error_max : tol.gnd_error_max_base;
  const int K = knot_stride_, last_k = knots_ - 2;
  const float* knots = knot_height_.data() + kKnotPad;
  const float inv_seg = inv_segment_;
  // Eq 3.15 for a return `depth` below the line (with GndErrorMax below the line).
  ObstacleToleranceParams below_tol = tol;
  below_tol.gnd_error_max_base = g_below;
  auto eq315 = [&](float depth, float r) { return obstacleProbability(depth, depth / r, r, below_tol); };
  // Negative obstacles measured from the foot of a step. Where the line's segment climbs a
  // step within it (a curb), the road in front of the step lies below the segment but level
  // with the ground before it: a return that eq 3.15 called a negative obstacle is scored
  // again with its depth below the lower of the line and its previous segment extended. The
  // step's own lowest returns, which the smeared segment also put below the line, are found
  // below as the feet of faces.
  auto step_foot_depth = [&](std::size_t i) {
    if (labels[i] != kLabelObstacle) return;
    const uint32_t b = bins[i];
    const float r = rr[i], h = hh[i];
    const float f = r * inv_seg;
    int k = static_cast<int>(f);
    k = k < last_k ? k : last_k;
    const float* kh = knots + static_cast<std::size_t>(b >> shift) * K;
    const float t = f - static_cast<float>(k);
    const float below = kh[k] + (kh[k + 1] - kh[k]) * t - h;
    if (!(below > 0.f)) return;
    const float km1 = k > 0 ? kh[k - 1] : 0.f;
    const float depth = kh[k] + (kh[k] - km1) * t - h;
    if (!(depth < below)) return;
    if (prob[i] > eq315(below, r) + 1e-6f) return;  // a vertical-surface term made it an obstacle
    const float p_step = eq315(depth > 0.f ? depth : 0.f, r);
    if (p_step > thr) return;
    prob[i] = p_step;
    labels[i] = kLabelGround;
  };
  if (p.negative_obstacles) {
    if (below_line_listed_) {
      // labelPoints() listed its 4-wide loop's obstacles below the line; the rest of the scan
      // went through its scalar loop.
      const uint32_t* groups = below_line_groups_.data();
      for (std::size_t c = 0; c < below_line_count_; ++c) {
        const std::size_t group = static_cast<std::size_t>(groups[c] >> 4) * 4;
        for (unsigned lanes = groups[c] & 15u; lanes; lanes &= lanes - 1) {
          step_foot_depth(group + static_cast<std::size_t>(__builtin_ctz(lanes)));
        }
      }
      for (std::size_t i = below_line_from_; i < n; ++i) {
        if (bins[i] != unknown_bin_) step_foot_depth(i);
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        if (bins[i] != unknown_bin_) step_foot_depth(i);
      }
    }
  }
  // Per row: neighbour_spacing_fraction of the spacing between it and the next row up on flat
  // ground, per r^2 (spacing = r^2 tan(gap) / sensor height).
  const float hs = sensor_height > 0.1f ? sensor_height : 0.1f;
  float gap_per_r2[kMaxRingRows];
  for (uint32_t row = 0; row < rows && row < static_cast<uint32_t>(kMaxRingRows); ++row) {
    gap_per_r2[row] = p.neighbour_spacing_fraction * row_gap_tan_[row] / hs;
  }
  const float max_dr = p.neighbour_max_dr;
  const float step = p.neighbour_min_step;
  const float above_threshold = std::nextafter(thr, 2.f);
  // A relabelled return's P(obstacle) is its neighbour's, raised above the threshold: with a
  // threshold of 1 or more no P can be above it, and no return is an obstacle.
  if (above_threshold > 1.f) return;
  // The neighbour in the row below (d = -row_step) or above (d = row_step): its index, or n.
  // An image entry is the cell's when that return's own cell is the cell (the image is never
  // cleared).
  const int cell_shift = cell_row_shift_;
  const uint32_t row_step = 1u << cell_shift;
  auto neighbour = [&](uint32_t c, uint32_t d) -> std::size_t {
    const uint32_t cn = c + d;
    const uint32_t j = image[cn];
    return j < n && cell[j] == cn ? j : n;
  };
  neighbour_obstacles_.clear();
  auto face_or_wall = [&](std::size_t i) LADAR_ALWAYS_INLINE {
    const uint32_t c = cell[i];
    const uint32_t row = c >> cell_shift;
    const float r = rr[i], h = hh[i];
    float p_face = -1.f;
    if (row > 0) {
      const std::size_t j = neighbour(c, 0u - row_step);
      if (j < n) {
        const float dr = std::fabs(r - rr[j]);
        if (labels[j] == kLabelObstacle && h >= hh[j] + step &&
            dr < std::min(max_dr, gap_per_r2[row - 1] * r * r)) {
          p_face = prob[j];  // the top of a face
        } else if (dr < 2.f * max_dr && h > hh[j] &&
                   groundHeight(static_cast<int>(bins[j] >> shift), rr[j]) - hh[j] > g_below) {
          p_face = prob[j];  // the top of a hole's far wall
        }
      }
    }
    if (row + 1 < rows) {
      const std::size_t j = neighbour(c, row_step);
      if (j < n && labels[j] == kLabelObstacle && hh[j] >= h + step &&
          std::fabs(r - rr[j]) < std::min(max_dr, gap_per_r2[row] * r * r) && prob[j] > p_face) {
        p_face = prob[j];  // the foot of a face
      }
    }
    if (p_face >= 0.f) {
      neighbour_obstacles_.emplace_back(static_cast<uint32_t>(i), std::max(p_face, above_threshold));
    }
  };
  // The ground returns to test: where labelPoints() listed the deep returns, only those in a
  // cell next to an obstacle (top and foot of a face) or above a deep return (a hole's far
  // wall), a superset of the cells whose neighbour can relabel them; else all. 16 labels at
  // a time (ground is label 0).
  static_assert(kLabelGround == 0, "the ground scan assumes ground = 0");
  const bool marked = deep_listed_;
  uint8_t stamp = 0;
  // A row of padding each side: mark_below[c] and mark_above[c] are the marks of the cells in
  // the rows below and above cell c.
  uint8_t* const mark_below = cell_mark_.data();
  uint8_t* const mark = mark_below + row_step;
  uint8_t* const mark_above = mark + row_step;
  if (marked) {
    if (++mark_stamp_ == 0) {  // a wrap: forget the stamps of 255 scans ago
      std::fill(cell_mark_.begin(), cell_mark_.end(), 0);
      mark_stamp_ = 1;
    }
    stamp = mark_stamp_;
    auto mark_around = [&](std::size_t j) {
      const uint32_t c = cell[j];
      mark_below[c] = stamp;
      mark_above[c] = stamp;
    };
    vertical_scan::forEachLabelled(labels, n, kLabelObstacle, mark_around);
    const uint32_t* groups = deep_groups_.data();
    for (std::size_t g = 0; g < deep_count_; ++g) {
      const std::size_t group = static_cast<std::size_t>(groups[g] >> 4) * 4;
      for (unsigned lanes = groups[g] & 15u; lanes; lanes &= lanes - 1) {
        mark_above[cell[group + static_cast<std::size_t>(__builtin_ctz(lanes))]] = stamp;
      }
    }
    for (std::size_t q = below_line_from_; q < n; ++q) {  // past the listing loop
      if (bins[q] != unknown_bin_) mark_above[cell[q]] = stamp;
    }
  }
  // Curb faces become ground before the pass, so that neither the curb's top nor the road at
  // its foot is made an obstacle by them.
  if (p.curb_policy == kCurbGround) relabelCurbFaces(g_below, marked ? mark : nullptr, stamp, out);
  std::size_t i = 0;
  if (marked) {
#if defined(__SSE2__)
    for (; i + 16 <= n; i += 16) {
      const __m128i l16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(labels + i));
      unsigned ground = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(l16, _mm_setzero_si128())));
      while (ground) {
        const std::size_t q = i + static_cast<std::size_t>(__builtin_ctz(ground));
        ground &= ground - 1;
        if (mark[cell[q]] == stamp) face_or_wall(q);
      }
    }
#endif
    for (; i < n; ++i) {
      if (labels[i] == kLabelGround && mark[cell[i]] == stamp) face_or_wall(i);
    }
  } else {
    for (; i < n; ++i) {
      if (labels[i] == kLabelGround) face_or_wall(i);
    }
  }
  // Applied after the pass: a relabelled return does not make its own neighbours obstacles.
  for (const auto& o : neighbour_obstacles_) {
    labels[o.first] = kLabelObstacle;
    prob[o.first] = o.second;
  }
}

// curb_policy kCurbGround, before the pass of labelFromLaserNeighbours(). A ground return (at
// r, h, in row `row` of cell c) tops a curb when the returns below it in its sub-column, from
// the obstacle j lower by at least neighbour_min_step down, are obstacles that fall
// monotonically, within curb_max_depth of it in r and curb_max_height of it in height, to a
// ground return: the road in front of the curb, which goes on level towards the sensor, not
// the floor of a hole (whose far wall is a face between ground returns too), which lies below
// the hole's near rim. Tested are the ground returns in marked cells (next to an obstacle),
// all when mark is null; the faces' returns become ground after all are tested.
LADAR_HOT_PATH void VerticalScanGround::relabelCurbFaces(float g_below, const uint8_t* mark, uint8_t stamp,
                                                         GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const std::size_t n = bin_.size();
  const float* rr = r_.data();
  const float* hh = height_.data();
  uint8_t* labels = out->labels.data();
  const uint32_t* cell = cell_.data();
  const uint32_t* image = range_image_.data();
  const int cell_shift = cell_row_shift_;
  const uint32_t row_step = 1u << cell_shift;
  const float step = p.neighbour_min_step;
  const float curb_height = p.curb_max_height, curb_depth = p.curb_max_depth;
  const float hole_depth = 0.5f * g_below;
  constexpr int kMaxFaceRows = 6;  // a face's returns below its top, at most
  auto below = [&](uint32_t c) -> std::size_t {  // the neighbour in the row below, or n
    const uint32_t cn = c - row_step;
    const uint32_t j = image[cn];
    return j < n && cell[j] == cn ? j : n;
  };
  auto tops_curb = [&](uint32_t c, uint32_t row, float r, float h, std::size_t j) {
    std::size_t face[kMaxFaceRows];
    int m = 0;
    float lowest = h;
    for (;;) {
      if (labels[j] == kLabelGround) {
        if (m == 0 || !(h - hh[j] >= step && h - hh[j] <= curb_height && hh[j] <= lowest)) return;
        const std::size_t k = row > 1 ? below(c - row_step) : n;
        if (k < n && labels[k] == kLabelGround && hh[k] - hh[j] > hole_depth) return;
        for (int q = 0; q < m; ++q) curb_ground_.push_back(static_cast<uint32_t>(face[q]));
        return;
      }
      if (labels[j] != kLabelObstacle || m == kMaxFaceRows || hh[j] > lowest + step ||
          h - hh[j] > curb_height || std::fabs(r - rr[j]) > curb_depth) {
        return;
      }
      lowest = hh[j] < lowest ? hh[j] : lowest;
      face[m++] = j;
      c -= row_step;  // the next row down
      if (--row == 0) return;
      j = below(c);
      if (j == n) return;
    }
  };
  auto test = [&](std::size_t q) {
    const uint32_t c = cell[q];
    if (mark && mark[c] != stamp) return;
    const uint32_t row = c >> cell_shift;
    if (row == 0) return;
    const std::size_t j = below(c);
    if (j < n && labels[j] == kLabelObstacle && hh[q] >= hh[j] + step) tops_curb(c, row, rr[q], hh[q], j);
  };
  curb_ground_.clear();
  vertical_scan::forEachLabelled(labels, n, kLabelGround, test);
  for (const uint32_t j : curb_ground_) {
    labels[j] = kLabelGround;
    out->p_obstacle[j] = p.tolerances.obstacle_threshold;
  }
}

std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params) {
  return std::make_unique<VerticalScanGround>(params, "vertical_scan");
}

}  // namespace ladar_perception
