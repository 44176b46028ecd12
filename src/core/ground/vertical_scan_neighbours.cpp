// Vertical scan ground extraction (thesis 3.3), the laser-neighbour stage (beyond the thesis):
// faces, hole rims and curbs from the returns of the laser rows above and below each return in
// its range-image sub-column.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ladar_perception/ground/vertical_scan.h"
#include "label_scan.h"
#include "vertical_scan_internal.h"

namespace ladar_perception {

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
                   groundLineHeight(static_cast<int>(bins[j] >> shift), rr[j]) - hh[j] > g_below) {
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

}  // namespace ladar_perception
