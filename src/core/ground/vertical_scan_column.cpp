// Vertical scan ground extraction (thesis 3.3), the column stage: each column's representative
// returns (the lower median range per bin), the slope estimate (eqs 3.4-3.9), the bent ground
// line tracked outward (5.1.2) and the coupling of neighbouring columns.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ladar_perception/ground/vertical_scan.h"
#include "vertical_scan_internal.h"

namespace ladar_perception {

namespace {

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

// The position of the lower median of r[0..n) ordered by (r, position), n <= kMaxRankBin: the
// position whose rank (the number of entries before it in that order) is (n - 1) / 2. Reads
// kMaxRankBin floats from r.

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

// Return i of a column (its representatives in r order) is the foot of a face: another lies
// within face_dr of it in r and face_height or more above it. The lowest return of a wall seen
// over a parked car, a fence's or a car's lowest: the line must not continue through them.
inline bool footOfFace(const float* r, const float* height, int n, int i, float face_dr,
                       float face_height) {
  const float top = height[i] + face_height;
  for (int j = i - 1; j >= 0 && r[i] - r[j] <= face_dr; --j) {
    if (height[j] >= top) return true;
  }
  for (int j = i + 1; j < n && r[j] - r[i] <= face_dr; ++j) {
    if (height[j] >= top) return true;
  }
  return false;
}

// The chord from the ground point (r0, h0) to return `to` of a column rises by face_height or
// more and passes face_height or more above a return between them (returns to - 1, to - 2, ...
// beyond r0). The ground is never that far above a return: the line would climb across a face
// it refused (a bush's or a car's, the foot of a wall) to the top of an object or a wall beyond.
inline bool chordClimbsOverReturns(const float* r, const float* height, int to, float r0, float h0,
                                   float face_height) {
  const float rise = height[to] - h0;
  if (rise < face_height) return false;
  const float per_m = rise / std::max(r[to] - r0, 1e-3f);
  for (int j = to - 1; j >= 0 && r[j] > r0; --j) {
    if (h0 + per_m * (r[j] - r0) - height[j] >= face_height) return true;
  }
  return false;
}

}  // namespace

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
  const float face_dr = p.track_face_dr;
  const float face_height = p.track_face_height;
  const bool faces = face_dr > 0.f;
  // The farthest return refused as the foot of a face since the last ground return.
  float face_r = 0.f;
  for (int i = 0; i < n; ++i) {
    const float dr = r[i] - gr[m - 1];
    const float dh = height[i] - gh[m - 1];
    const float gap = dr > 0.f ? dr : 0.f;
    // The step tolerance grows over the terrain not seen since the last ground return; at the
    // foot of a face the line refused, the ground was no higher than that foot, so the growth
    // starts again there (a car's top behind its rear face is not reached as a step).
    const float unseen = r[i] - std::max(gr[m - 1], face_r);
    const float grow = p.track_tolerance_per_m * (unseen > 0.f ? unseen : 0.f);
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
      // The run is long enough to be ground: restart the line at its first return. The last
      // ground returns before it, when the line reached them across a gap (longer than such a
      // run) and each stands above the restart more steeply than any ground slope, were the
      // top of an object (a car's bonnet seen over a bush), not ground: they leave the line.
      int keep = m;
      for (int k = m - 1; k > 1 && gh[k] - height[below_first] >
                                       p.track_max_step + p.ground_slope_max * (r[below_first] - gr[k]);
           --k) {
        if (gr[k] - gr[k - 1] >= p.track_recover_distance) {
          keep = k;
          break;
        }
      }
      // A run below an upward extrapolation may still be a wall far above the ground: not when
      // the line would climb to it over returns it refused.
      if (faces && chordClimbsOverReturns(r, height, below_first, gr[keep - 1], gh[keep - 1], face_height)) {
        continue;
      }
      m = keep;
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
    if (faces) {
      if (footOfFace(r, height, n, i, face_dr, face_height)) {
        face_r = r[i];
        continue;
      }
      if (chordClimbsOverReturns(r, height, i, gr[m - 1], gh[m - 1], face_height)) continue;
    }
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
  // The tail: the line extrapolated from the last ground return. The terrain beyond it is
  // unobserved in this column, so the tail rises no faster than the column's straight estimate
  // (eqs 3.4-3.9; flat where that falls): a line that bent upward over the last metres of
  // ground (a verge, a ramp, a building's plinth) otherwise climbs on through the wall behind
  // them, and the wall's returns below it become ground.
  slope = std::min(slope, std::max(slope0, 0.f));
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

}  // namespace ladar_perception
