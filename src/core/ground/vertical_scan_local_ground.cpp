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

// Runs after labelFromLaserNeighbours(): its face test reads the range image binPoints() wrote,
// and the feet of faces are looked for in the cells that pass marked (next to an obstacle).
void VerticalScanGround::relabelFromLocalGround(GroundClassification* out) {
  const VerticalScanParams& p = params_;
  const std::size_t n = bin_.size();
  const int shift = row_shift_;
  const uint32_t* __restrict bins = bin_.data();
  const float* __restrict rr = r_.data();
  const float* __restrict hh = height_.data();
  uint8_t* __restrict labels = out->labels.data();
  float* __restrict prob = out->p_obstacle.data();
  const int cols = columns_;
  const float inv_cell = 1.f / p.local_ground_cell;
  // The rings out to the farthest knot the scan used (its farthest return lies before it).
  const int rings = std::max(1, std::min(local_rings_,
      static_cast<int>(static_cast<float>(knots_used_) * p.segment_length * inv_cell) + 2));
  const int last_ring = rings - 1;
  const std::size_t cells = static_cast<std::size_t>(rings) * cols;
  // A face rises from return i: walking up its sub-column of the range image, the returns
  // stay within face_dr of it in r, the first rises no more than two row spacings at its
  // range, and one reaches face_height above it. An empty cell is passed over.
  const uint32_t* __restrict cell = cell_.data();
  const uint32_t* __restrict image = range_image_.data();
  const int cell_shift = cell_row_shift_;
  const uint32_t row_step = 1u << cell_shift;
  const uint32_t rows = static_cast<uint32_t>(rows_);
  const float face_dr = p.local_ground_face_dr, face_height = p.local_ground_face_height;
  constexpr uint32_t kMaxFaceRows = 8;
  auto faceRises = [&](std::size_t i) {
    const uint32_t c = cell[i];
    const uint32_t row = c >> cell_shift;
    const float r = rr[i], h = hh[i];
    const float first_rise = std::max(face_height, 2.f * r * row_gap_tan_[row]);
    bool first = true;
    for (uint32_t k = 1; k <= kMaxFaceRows && row + k < rows; ++k) {
      const uint32_t cn = c + k * row_step;
      const uint32_t j = image[cn];
      if (!(j < n && cell[j] == cn)) continue;
      if (std::fabs(rr[j] - r) > face_dr) return false;
      const float rise = hh[j] - h;
      if (first && rise > first_rise) return false;
      first = false;
      if (rise >= face_height) return true;
    }
    return false;
  };

  // One pass over the ground returns. First the feet of faces: a ground return from which a
  // face rises (the lowest returns of a wall, a fence or a car's side, which the per-column
  // terms take for ground) is an obstacle. Looked for in the cells that
  // labelFromLaserNeighbours() marked (next to an obstacle: a face's foot lies below one), in
  // all when it marked none. The other ground returns are summed per cell of the grid, ring-major
  // (cell = ring * cols + column): sum of heights, sum of squared heights, count.
  const float thr = p.tolerances.obstacle_threshold;
  const float above_threshold = std::nextafter(thr, 2.f);
  const bool feet = above_threshold <= 1.f;  // else no return can be an obstacle
  const uint8_t* mark = cell_mark_.data() + row_step;
  const uint8_t stamp = mark_stamp_;
  const bool marked = deep_listed_;
  float* __restrict grid = local_grid_.data();
  std::fill(grid, grid + 3 * cells, 0.f);
  forEachLabelled(labels, n, kLabelGround, [&](std::size_t i) LADAR_ALWAYS_INLINE {
    if (feet && (!marked || mark[cell[i]] == stamp) && faceRises(i)) {
      labels[i] = kLabelObstacle;
      prob[i] = std::max(prob[i], above_threshold);
      return;
    }
    int ring = static_cast<int>(rr[i] * inv_cell);  // a ground return is a known one
    ring = ring < last_ring ? ring : last_ring;
    float* g = grid + 3 * (static_cast<std::size_t>(ring) * cols + (bins[i] >> shift));
    const float h = hh[i];
    g[0] += h;
    g[1] += h * h;
    g[2] += 1.f;
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
  forEachLabelled(labels, n, kLabelObstacle, [=](std::size_t i) {
    const float* lh = band + 2 * static_cast<std::size_t>(bins[i]);
    const float h = hh[i];
    if (!(h >= lh[0] && h <= lh[1])) return;
    if (faceRises(i)) return;
    labels[i] = kLabelGround;
    prob[i] = std::min(prob[i], thr);
  });
}

}  // namespace ladar_perception
