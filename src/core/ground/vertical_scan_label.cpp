// Vertical scan ground extraction (thesis 3.3), the labelling stage: every return's
// P(obstacle) against its column's ground line (eqs 3.13-3.15) with the vertical-surface, foot
// and negative-obstacle terms beyond the thesis.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ladar_perception/ground/vertical_scan.h"
#include "vertical_scan_internal.h"

namespace ladar_perception {

namespace {

// The label bytes of four lanes from their obstacle bits and their unknown bits (one table
// lookup each; ground is 0).
struct LabelBytes {
  uint32_t obstacle[16], unknown[16];
  LabelBytes() {
    static_assert(kLabelGround == 0, "label bytes assume ground = 0");
    for (int m = 0; m < 16; ++m) {
      obstacle[m] = unknown[m] = 0;
      for (int l = 0; l < 4; ++l) {
        if (m >> l & 1) {
          obstacle[m] |= static_cast<uint32_t>(kLabelObstacle) << (8 * l);
          unknown[m] |= static_cast<uint32_t>(kLabelUnknown) << (8 * l);
        }
      }
    }
  }
  uint32_t of(int obstacle_bits, int unknown_bits) const { return obstacle[obstacle_bits] | unknown[unknown_bits]; }
};

}  // namespace

#if defined(LADAR_CLONES)
namespace {

// What labelPoints() hands its 8-lane loop (the default settings: every term on, SlopeErrorMax
// constant): the arrays, the tolerances, and the lists it appends to.
struct LabelPass {
  std::size_t n;
  const uint32_t* bins;
  const float *rr, *hh, *rep, *knots;
  uint8_t* labels;
  float* prob;
  uint32_t unknown_bin, rows;
  int shift, K, last_k;
  float inv_seg, g_above, g_below_delta, g_per_m, s_base, thr, inv_v_gnd, inv_v_slope, inv_foot, deep;
  uint32_t* below_groups;
  std::size_t* below_count;
  uint32_t* deep_groups;
  std::size_t* deep_count;
};

// Appends the lane bits of eight lanes as the two groups of four the lists hold.
inline void appendGroups(uint32_t* groups, std::size_t* count, std::size_t i, int bits) {
  const uint32_t g = static_cast<uint32_t>(i >> 2);
  if (bits & 0xF) groups[(*count)++] = g << 4 | static_cast<uint32_t>(bits & 0xF);
  if (bits & 0xF0) groups[(*count)++] = (g + 1) << 4 | static_cast<uint32_t>(bits >> 4);
}

// labelPoints()'s 4-wide loop for the default settings with 8 lanes (AVX2), the knots and the
// representatives of the rows below and above read by gathers. Every lane repeats the 4-wide
// loop's arithmetic operation for operation, so P(obstacle) and the labels are bit-identical to
// it. Returns the first return it left to the caller.
template <bool kDeep>
__attribute__((target("avx2"))) std::size_t labelPointsAvx2(const LabelPass& L) {
  const __m256 v_inv_seg = _mm256_set1_ps(L.inv_seg);
  const __m256 v_last_k = _mm256_set1_ps(static_cast<float>(L.last_k));
  const __m256 v_K = _mm256_set1_ps(static_cast<float>(L.K));
  const __m256 v_zero = _mm256_setzero_ps(), v_one = _mm256_set1_ps(1.f);
  const __m256 v_abs = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 v_sign = _mm256_castsi256_ps(_mm256_set1_epi32(static_cast<int>(0x80000000u)));
  const __m256 v_g_above = _mm256_set1_ps(L.g_above), v_g_below_delta = _mm256_set1_ps(L.g_below_delta);
  const __m256 v_g_per_m = _mm256_set1_ps(L.g_per_m);
  const __m256 v_s_base = _mm256_set1_ps(L.s_base);
  const __m256 v_thr = _mm256_set1_ps(L.thr), v_inv_v_gnd = _mm256_set1_ps(L.inv_v_gnd);
  const __m256i v_invalid = _mm256_set1_epi32(static_cast<int>(L.unknown_bin));
  const __m128i v_shift = _mm_cvtsi32_si128(L.shift);
  const __m256i v_row_mask = _mm256_set1_epi32(static_cast<int>(L.rows - 1));
  const __m256 v_pad = _mm256_set1_ps(0.02f);
  const __m256 v_inv_v_slope = _mm256_set1_ps(L.inv_v_slope);
  const __m256 v_inv_foot = _mm256_set1_ps(L.inv_foot);
  const __m256 v_deep = _mm256_set1_ps(L.deep);
  const LabelBytes bytes;
  const float* __restrict knots = L.knots;
  const float* __restrict rep = L.rep;
  float* __restrict prob = L.prob;
  uint8_t* __restrict labels = L.labels;
  std::size_t i = 0;
  for (; i + 8 <= L.n; i += 8) {
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(L.bins + i));
    const __m256i invalid = _mm256_cmpeq_epi32(b, v_invalid);
    const int invalid_bits = _mm256_movemask_ps(_mm256_castsi256_ps(invalid));
    if (invalid_bits == 0xFF) continue;  // binPoints labelled them unknown
    const __m256 r = _mm256_loadu_ps(L.rr + i);
    const __m256 h = _mm256_loadu_ps(L.hh + i);
    // The column's ground line at r: knots k - 1, k and k + 1 of each lane.
    const __m256 col = _mm256_cvtepi32_ps(_mm256_srl_epi32(b, v_shift));
    const __m256 f = _mm256_mul_ps(r, v_inv_seg);
    const __m256 kf = _mm256_min_ps(_mm256_cvtepi32_ps(_mm256_cvttps_epi32(f)), v_last_k);
    const __m256i knot_i = _mm256_andnot_si256(invalid, _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(col, v_K), kf)));
    const __m256 kp = _mm256_i32gather_ps(knots - 1, knot_i, 4);
    const __m256 k0 = _mm256_i32gather_ps(knots, knot_i, 4);
    const __m256 k1 = _mm256_i32gather_ps(knots + 1, knot_i, 4);
    const __m256 ground = _mm256_add_ps(k0, _mm256_mul_ps(_mm256_sub_ps(k1, k0), _mm256_sub_ps(f, kf)));
    // Eqs 3.10, 3.11, 3.15.
    const __m256 gnd_error = _mm256_sub_ps(ground, h);
    const __m256 abs_error = _mm256_and_ps(gnd_error, v_abs);
    const __m256 above = _mm256_cmp_ps(gnd_error, v_zero, _CMP_GT_OQ);
    const int below_line_bits = _mm256_movemask_ps(above);  // GndError > 0
    if (kDeep) {
      const int deep_bits = _mm256_movemask_ps(_mm256_cmp_ps(gnd_error, v_deep, _CMP_GT_OQ)) & ~invalid_bits;
      if (deep_bits) appendGroups(L.deep_groups, L.deep_count, i, deep_bits);
    }
    const __m256 g_max = _mm256_add_ps(_mm256_add_ps(v_g_above, _mm256_and_ps(above, v_g_below_delta)),
                                       _mm256_mul_ps(v_g_per_m, r));
    const __m256 gt = _mm256_min_ps(_mm256_div_ps(abs_error, g_max), v_one);
    const __m256 st = _mm256_min_ps(_mm256_div_ps(abs_error, _mm256_mul_ps(r, v_s_base)), v_one);
    __m256 p8 = _mm256_mul_ps(gt, st);
    // The vertical-surface and foot terms (vertical_probability()).
    const __m256 above_foot = _mm256_sub_ps(h, _mm256_min_ps(_mm256_min_ps(kp, k0), ground));
    const __m256 g_foot = _mm256_min_ps(_mm256_mul_ps(above_foot, v_inv_v_gnd), v_one);
    const __m256 need = _mm256_cmp_ps(g_foot, _mm256_max_ps(v_thr, p8), _CMP_GT_OQ);
    const int need_bits = _mm256_movemask_ps(need) & ~invalid_bits;
    if (need_bits) {
      const __m256 g = _mm256_min_ps(_mm256_mul_ps(_mm256_xor_ps(gnd_error, v_sign), v_inv_v_gnd), v_one);
      const __m256i bv = _mm256_andnot_si256(invalid, b);
      const __m256i b2 = _mm256_add_epi32(bv, bv);
      const __m256 r_hi = _mm256_i32gather_ps(rep + 2, b2, 4), h_hi = _mm256_i32gather_ps(rep + 3, b2, 4);
      const __m256i row = _mm256_and_si256(bv, v_row_mask);
      const __m256 has_hi = _mm256_and_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(v_row_mask, row)),
                                          _mm256_cmp_ps(r_hi, v_zero, _CMP_GE_OQ));
      const __m256 rise = _mm256_div_ps(_mm256_sub_ps(h_hi, h),
                                        _mm256_add_ps(_mm256_and_ps(_mm256_sub_ps(r, r_hi), v_abs), v_pad));
      const __m256 u = _mm256_min_ps(_mm256_mul_ps(rise, v_inv_foot), v_one);
      __m256 best = _mm256_blendv_ps(p8, _mm256_max_ps(_mm256_mul_ps(g_foot, u), p8), has_hi);
      if (_mm256_movemask_ps(_mm256_cmp_ps(g, best, _CMP_GT_OQ)) & need_bits) {
        const __m256 r_lo = _mm256_i32gather_ps(rep - 2, b2, 4), h_lo = _mm256_i32gather_ps(rep - 1, b2, 4);
        const __m256 has_lo = _mm256_and_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(row, _mm256_setzero_si256())),
                                            _mm256_cmp_ps(r_lo, v_zero, _CMP_GE_OQ));
        const __m256 sl_lo = _mm256_div_ps(_mm256_and_ps(_mm256_sub_ps(h, h_lo), v_abs),
                                           _mm256_add_ps(_mm256_and_ps(_mm256_sub_ps(r, r_lo), v_abs), v_pad));
        const __m256 sl_hi = _mm256_and_ps(rise, v_abs);
        const __m256 one_side = _mm256_blendv_ps(_mm256_and_ps(has_hi, sl_hi), sl_lo, has_lo);
        const __m256 both = _mm256_and_ps(has_lo, has_hi);
        const __m256 local = _mm256_blendv_ps(one_side, _mm256_min_ps(sl_hi, sl_lo), both);
        const __m256 v = _mm256_min_ps(_mm256_mul_ps(local, v_inv_v_slope), v_one);
        best = _mm256_max_ps(_mm256_mul_ps(g, v), best);
      }
      const __m256 take = _mm256_andnot_ps(_mm256_castsi256_ps(invalid), need);
      p8 = _mm256_blendv_ps(p8, best, take);
    }
    p8 = _mm256_andnot_ps(_mm256_castsi256_ps(invalid), p8);  // unknown: 0 as binPoints wrote
    const int obstacle_bits = _mm256_movemask_ps(_mm256_cmp_ps(p8, v_thr, _CMP_GT_OQ)) & ~invalid_bits;
    // Negative obstacles are rare: their groups are listed.
    const int below_bits = obstacle_bits & below_line_bits;
    if (below_bits) appendGroups(L.below_groups, L.below_count, i, below_bits);
    _mm256_storeu_ps(prob + i, p8);
    const uint32_t lo = bytes.of(obstacle_bits & 0xF, invalid_bits & 0xF);
    const uint32_t hi = bytes.of(obstacle_bits >> 4, invalid_bits >> 4);
    std::memcpy(labels + i, &lo, 4);
    std::memcpy(labels + i + 4, &hi, 4);
  }
  return i;
}

}  // namespace
#endif

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
    const LabelBytes bytes;
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
    auto sse_loop = [=, &below_count, &deep_count](std::size_t from, auto negative_c, auto vertical_c, auto foot_c,
                                                   auto support_gate_c, auto growing_slope_tolerance_c,
                                                   auto deep_c) mutable LADAR_ALWAYS_INLINE {
      for (i = from; i + 4 <= n; i += 4) {
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
        const uint32_t label4 = bytes.of(obstacle_bits, invalid_bits);
        std::memcpy(labels + i, &label4, 4);
      }
      return i;
    };
    if (negative && vertical && foot && support_gate && s_per_m == 0.f) {
#if defined(LADAR_CLONES)
      if (cpuHasAvx2()) {
        const LabelPass pass{n, bins, rr, hh, rep, knots, labels, prob, unknown_bin_, rows, shift, K, last_k,
                             inv_seg, g_above, g_below_delta, g_per_m, s_base, thr, inv_v_gnd, inv_v_slope,
                             inv_foot, g_below - 1e-3f, below_groups, &below_count, deep_groups, &deep_count};
        i = list_deep ? labelPointsAvx2<true>(pass) : labelPointsAvx2<false>(pass);
      }
#endif
      if (list_deep) {
        i = sse_loop(i, std::true_type{}, std::true_type{}, std::true_type{}, std::true_type{}, std::false_type{},
                     std::true_type{});
        deep_count_ = deep_count;
        deep_listed_ = true;
      } else {
        i = sse_loop(i, std::true_type{}, std::true_type{}, std::true_type{}, std::true_type{}, std::false_type{},
                     std::false_type{});
      }
    } else {
      i = sse_loop(i, negative, vertical, foot, support_gate, true, std::false_type{});
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

}  // namespace ladar_perception
