// The local ground height stage of the vertical scan method (beyond the thesis: the
// ground-height estimate shared across azimuth that 5.1.2 names as future work). See
// VerticalScanParams::local_ground.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ladar_perception/ground/vertical_scan.h"
#include "label_scan.h"
#include "vertical_scan_internal.h"

namespace ladar_perception {

using vertical_scan::forEachLabelled;

namespace {

// The per-return work of the local ground stage, shared by its scalar and its AVX2 passes.
struct LocalGroundPass {
  std::size_t n;
  const uint32_t* __restrict bins;
  const float* __restrict rr;
  const float* __restrict hh;
  uint8_t* __restrict labels;
  float* __restrict prob;
  // The face test's range image.
  const uint32_t* __restrict cell;
  const uint32_t* __restrict image;
  const float* __restrict row_gap_tan;
  int cell_shift;
  uint32_t rows;
  float face_dr, face_height;
  // The feet of faces: looked for in the cells stamped in mark (all when !marked).
  bool feet, marked;
  const uint8_t* mark;
  uint8_t stamp;
  float above_threshold, thr;
  // The grid: cell = ring * cols + column, three floats each.
  float inv_cell;
  int last_ring, cols, shift;
  float* __restrict grid;
  // Per bin, the band of heights that is ground (below, above).
  const float* __restrict band;
  // A return on a face (onFace()) stays an obstacle.
  float face_min_height, face_slope;

  // The face tests walk at most this many rows from a return.
  static constexpr uint32_t kMaxFaceRows = 8;
  // The return in range-image cell cn (the last one there in input order), n when it is empty.
  std::size_t returnIn(uint32_t cn) const {
    const uint32_t j = image[cn];
    return j < n && cell[j] == cn ? j : n;
  }

  // A face rises from return i: walking up its sub-column of the range image, the returns
  // stay within face_dr of it in r, the first rises no more than two row spacings at its
  // range, and one reaches face_height above it. An empty cell is passed over.
  bool faceRises(std::size_t i) const {
    const uint32_t c = cell[i];
    const uint32_t row = c >> cell_shift;
    const uint32_t row_step = 1u << cell_shift;
    const float r = rr[i], h = hh[i];
    const float first_rise = std::max(face_height, 2.f * r * row_gap_tan[row]);
    bool first = true;
    for (uint32_t k = 1; k <= kMaxFaceRows && row + k < rows; ++k) {
      const std::size_t j = returnIn(c + k * row_step);
      if (j == n) continue;
      if (std::fabs(rr[j] - r) > face_dr) return false;
      const float rise = hh[j] - h;
      if (first && rise > first_rise) return false;
      first = false;
      if (rise >= face_height) return true;
    }
    return false;
  }
  // A face through return i: walking up and down its sub-column from it (an empty cell passed
  // over), each next return lies within face_dr in r of the one before and rises or falls at
  // least as steeply as face_slope; the returns so reached span face_min_height or more in
  // height (a curb's face, a step; not a bump of rough ground near the sensor, where the rows
  // lie a few cm apart in r).
  bool onFace(std::size_t i) const {
    const uint32_t c = cell[i];
    const uint32_t row = c >> cell_shift;
    const uint32_t row_step = 1u << cell_shift;
    float lo = hh[i], hi = hh[i];
    for (int side = 0; side < 2; ++side) {
      float r = rr[i], h = hh[i];
      for (uint32_t k = 1; k <= kMaxFaceRows; ++k) {
        if (side == 0 ? row + k >= rows : k > row) break;
        const std::size_t j = returnIn(side == 0 ? c + k * row_step : c - k * row_step);
        if (j == n) continue;
        const float dr = std::fabs(rr[j] - r), dh = std::fabs(hh[j] - h);
        if (dr > face_dr || dh < face_slope * dr) break;
        r = rr[j];
        h = hh[j];
        lo = std::min(lo, h);
        hi = std::max(hi, h);
      }
    }
    return hi - lo >= face_min_height;
  }
  bool footCandidate(std::size_t i) const { return feet && (!marked || mark[cell[i]] == stamp); }
  // Ground return i's cell of the grid (its own r).
  int gridCell(std::size_t i) const {
    int ring = static_cast<int>(rr[i] * inv_cell);  // a ground return is a known one
    ring = ring < last_ring ? ring : last_ring;
    return ring * cols + static_cast<int>(bins[i] >> shift);
  }
  // A ground return at the foot of a face becomes an obstacle (true).
  bool footOfFace(std::size_t i) {
    if (!faceRises(i)) return false;
    labels[i] = kLabelObstacle;
    prob[i] = std::max(prob[i], above_threshold);
    return true;
  }
  // The other ground returns are summed in their cell of the grid (height, squared height,
  // count).
  void accumulate(std::size_t i, int g_cell) {
    float* g = grid + 3 * static_cast<std::size_t>(g_cell);
    const float h = hh[i];
    g[0] += h;
    g[1] += h * h;
    g[2] += 1.f;
  }
  bool inBand(std::size_t i) const {
    const float* lh = band + 2 * static_cast<std::size_t>(bins[i]);
    const float h = hh[i];
    return h >= lh[0] && h <= lh[1];
  }
  // Obstacle return i, level with the ground around it: ground unless a face rises from it or
  // it lies on one.
  void levelReturn(std::size_t i) {
    if (faceRises(i) || onFace(i)) return;
    labels[i] = kLabelGround;
    prob[i] = std::min(prob[i], thr);
  }
};

#if defined(LADAR_CLONES)
// The two passes over the returns eight at a time (AVX2): the labels, the marks and the bands
// tested by lanes, the returns that pass handed to LocalGroundPass in increasing order, as the
// scalar passes do. Each returns the first return it left to the caller.
__attribute__((target("avx2"))) std::size_t groundPassAvx2(LocalGroundPass& L) {
  const __m256i v_ground = _mm256_set1_epi32(kLabelGround);
  const __m256i v_stamp = _mm256_set1_epi32(L.stamp), v_byte = _mm256_set1_epi32(0xFF);
  const __m256 v_inv_cell = _mm256_set1_ps(L.inv_cell);
  const __m256i v_last_ring = _mm256_set1_epi32(L.last_ring), v_cols = _mm256_set1_epi32(L.cols);
  const __m128i v_shift = _mm_cvtsi32_si128(L.shift);
  const bool all_candidates = L.feet && !L.marked;
  const int* mark = reinterpret_cast<const int*>(L.mark);
  alignas(32) int g_cell[8];
  std::size_t i = 0;
  for (; i + 8 <= L.n; i += 8) {
    const __m256i lab = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(L.labels + i)));
    const __m256i ground = _mm256_cmpeq_epi32(lab, v_ground);
    unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(ground)));
    if (!bits) continue;
    unsigned candidates = all_candidates ? bits : 0u;
    if (L.feet && L.marked) {
      // Unknown returns have no cell: their lanes read cell 0's mark.
      const __m256i c = _mm256_and_si256(ground, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(L.cell + i)));
      const __m256i m = _mm256_and_si256(_mm256_i32gather_epi32(mark, c, 1), v_byte);
      candidates = bits & static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(m, v_stamp))));
    }
    // gridCell() by lanes.
    const __m256i ring = _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_loadu_ps(L.rr + i), v_inv_cell)),
                                          v_last_ring);
    const __m256i column = _mm256_srl_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(L.bins + i)), v_shift);
    _mm256_store_si256(reinterpret_cast<__m256i*>(g_cell), _mm256_add_epi32(_mm256_mullo_epi32(ring, v_cols), column));
    for (; candidates; candidates &= candidates - 1) {
      const unsigned l = static_cast<unsigned>(__builtin_ctz(candidates));
      if (L.footOfFace(i + l)) bits &= ~(1u << l);
    }
    for (; bits; bits &= bits - 1) {
      const unsigned l = static_cast<unsigned>(__builtin_ctz(bits));
      L.accumulate(i + l, g_cell[l]);
    }
  }
  return i;
}

__attribute__((target("avx2"))) std::size_t levelPassAvx2(LocalGroundPass& L) {
  const __m256i v_obstacle = _mm256_set1_epi32(kLabelObstacle);
  std::size_t i = 0;
  for (; i + 8 <= L.n; i += 8) {
    const __m256i lab = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(L.labels + i)));
    const __m256i obstacle = _mm256_cmpeq_epi32(lab, v_obstacle);
    if (_mm256_testz_si256(obstacle, obstacle)) continue;
    // inBand() by lanes (an obstacle return's bin is a known one; other lanes read bin 0's).
    const __m256i b = _mm256_and_si256(obstacle, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(L.bins + i)));
    const __m256i b2 = _mm256_add_epi32(b, b);
    const __m256 h = _mm256_loadu_ps(L.hh + i);
    const __m256 lo = _mm256_i32gather_ps(L.band, b2, 4), hi = _mm256_i32gather_ps(L.band + 1, b2, 4);
    const __m256 in = _mm256_and_ps(_mm256_cmp_ps(h, lo, _CMP_GE_OQ), _mm256_cmp_ps(h, hi, _CMP_LE_OQ));
    unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(_mm256_and_ps(in, _mm256_castsi256_ps(obstacle))));
    for (; bits; bits &= bits - 1) L.levelReturn(i + static_cast<unsigned>(__builtin_ctz(bits)));
  }
  return i;
}
#endif

}  // namespace

// Runs after labelFromLaserNeighbours(): its face test reads the range image binPoints() wrote,
// and the feet of faces are looked for in the cells that pass marked (next to an obstacle).
LADAR_HOT_PATH void VerticalScanGround::relabelFromLocalGround(GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const std::size_t n = bin_.size();
  const int shift = row_shift_;
  const int cols = columns_;
  const float inv_cell = 1.f / p.local_ground_cell;
  // The rings out to the farthest knot the scan used (its farthest return lies before it).
  const int rings = std::max(1, std::min(local_rings_,
      static_cast<int>(static_cast<float>(knots_used_) * p.segment_length * inv_cell) + 2));
  const int last_ring = rings - 1;
  const std::size_t cells = static_cast<std::size_t>(rings) * cols;
  const float thr = p.tolerances.obstacle_threshold;
  const float above_threshold = std::nextafter(thr, 2.f);
  float* __restrict grid = local_grid_.data();
  std::fill(grid, grid + 3 * cells, 0.f);
  LocalGroundPass pass{n, bin_.data(), r_.data(), height_.data(), out->labels.data(), out->p_obstacle.data(),
                       cell_.data(), range_image_.data(), row_gap_tan_.data(), cell_row_shift_,
                       static_cast<uint32_t>(rows_), p.local_ground_face_dr, p.local_ground_face_height,
                       above_threshold <= 1.f,  // else no return can be an obstacle
                       deep_listed_, cell_mark_.data() + (std::size_t{1} << cell_row_shift_), mark_stamp_,
                       above_threshold, thr, inv_cell, last_ring, cols, shift, grid, local_bin_band_.data(),
                       p.local_ground_face_min_height, p.vertical_foot_slope};
  const uint8_t* labels = out->labels.data();

  // One pass over the ground returns. First the feet of faces: a ground return from which a
  // face rises (the lowest returns of a wall, a fence or a car's side, which the per-column
  // terms take for ground) is an obstacle. Looked for in the cells that
  // labelFromLaserNeighbours() marked (next to an obstacle: a face's foot lies below one), in
  // all when it marked none. The other ground returns are summed per cell of the grid, ring-major
  // (cell = ring * cols + column): sum of heights, sum of squared heights, count.
  std::size_t from = 0;
#if defined(LADAR_CLONES)
  if (cpuHasAvx2()) from = groundPassAvx2(pass);
#endif
  forEachLabelled(labels + from, n - from, kLabelGround, [&](std::size_t k) LADAR_ALWAYS_INLINE {
    const std::size_t i = from + k;
    if (!(pass.footCandidate(i) && pass.footOfFace(i))) pass.accumulate(i, pass.gridCell(i));
  });
  // Each bin's cell for the obstacle returns below: that of its representative (3.3 step 1;
  // the returns of a bin, one laser across one column, mostly lie within a cell of it in r).
  const std::size_t bin_count = static_cast<std::size_t>(cols) << shift;
  uint32_t* __restrict bin_cell = local_bin_cell_.data();
  const float* rep_rh = rep_.data() + 2;
  for (std::size_t b = 0; b < bin_count; ++b) {
    const float r = rep_rh[2 * b];
    int ring = static_cast<int>(std::max(r, 0.f) * inv_cell);
    ring = ring < last_ring ? ring : last_ring;
    bin_cell[b] = static_cast<uint32_t>(ring * cols + static_cast<int>(b >> shift));
  }

  // The neighbourhood of each cell: local_ground_rings cells along r, then
  // local_ground_columns columns each side (around the circle), summed.
  const int wr = p.local_ground_rings;
  const int wc = std::min(p.local_ground_columns, (cols - 1) / 2);
  float* __restrict around = local_around_.data();
  if (wr > 0) {
    for (int k = 0; k < rings; ++k) {
      float* dst = around + 3 * static_cast<std::size_t>(k) * cols;
      std::fill(dst, dst + 3 * cols, 0.f);
      for (int q = std::max(0, k - wr); q <= std::min(last_ring, k + wr); ++q) {
        const float* src = grid + 3 * static_cast<std::size_t>(q) * cols;
        for (int c = 0; c < 3 * cols; ++c) dst[c] += src[c];
      }
    }
    std::copy(around, around + 3 * cells, grid);
  }
  // Across columns: the interior of a ring 3 * cols floats at a time, its wc first and last
  // columns around the circle.
  for (int k = 0; k < rings; ++k) {
    const float* __restrict src = grid + 3 * static_cast<std::size_t>(k) * cols;
    float* __restrict dst = around + 3 * static_cast<std::size_t>(k) * cols;
    std::copy(src, src + 3 * cols, dst);
    for (int d = 1; d <= wc; ++d) {
      for (int q = 3 * wc; q < 3 * (cols - wc); ++q) dst[q] += src[q - 3 * d] + src[q + 3 * d];
    }
    auto edge = [&](int c) {
      float s0 = 0.f, s1 = 0.f, s2 = 0.f;
      for (int d = -wc; d <= wc; ++d) {
        const int cc = (c + d + cols) % cols;
        s0 += src[3 * cc];
        s1 += src[3 * cc + 1];
        s2 += src[3 * cc + 2];
      }
      dst[3 * c] = s0;
      dst[3 * c + 1] = s1;
      dst[3 * c + 2] = s2;
    };
    for (int c = 0; c < wc; ++c) edge(c);
    for (int c = cols - wc; c < cols; ++c) edge(c);
  }

  // Obstacle returns level with the ground around them become ground: per bin, the band of
  // heights around the mean ground height of its cell's neighbourhood (empty where it has fewer
  // than local_ground_min_returns ground returns), widened on rough ground to
  // local_ground_roughness standard deviations of those heights (at most
  // local_ground_roughness_max).
  const float min_returns = static_cast<float>(p.local_ground_min_returns);
  const float below = p.local_ground_below, above = p.local_ground_above;
  const float rough = p.local_ground_roughness, rough_max = p.local_ground_roughness_max;
  float* __restrict band = local_bin_band_.data();
  for (std::size_t b = 0; b < bin_count; ++b) {
    const float* a = around + 3 * static_cast<std::size_t>(bin_cell[b]);
    const bool enough = a[2] >= min_returns;
    const float count = enough ? a[2] : 1.f;
    const float mean = a[0] / count;
    const float var = std::max(a[1] / count - mean * mean, 0.f);
    const float spread = rough > 0.f ? std::min(rough * std::sqrt(var), rough_max) : 0.f;
    band[2 * b] = enough ? mean - std::max(below, spread) : 1e30f;
    band[2 * b + 1] = enough ? mean + std::max(above, spread) : -1e30f;
  }
  from = 0;
#if defined(LADAR_CLONES)
  if (cpuHasAvx2()) from = levelPassAvx2(pass);
#endif
  forEachLabelled(labels + from, n - from, kLabelObstacle, [&](std::size_t k) {
    const std::size_t i = from + k;
    if (pass.inBand(i)) pass.levelReturn(i);
  });
}

}  // namespace ladar_perception
