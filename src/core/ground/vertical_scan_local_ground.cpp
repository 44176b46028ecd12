// The local ground height stage of the vertical scan method (beyond the thesis: the
// ground-height estimate shared across azimuth that 5.1.2 names as future work). See
// VerticalScanParams::local_ground.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ladar_perception/ground/vertical_scan.h"
#include "label_scan.h"

namespace ladar_perception {

using vertical_scan::forEachLabelled;

// Runs after labelFromLaserNeighbours() (its face test reads the range image binPoints() wrote).
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
  // (sum of heights, count) of the ground returns per cell, ring-major: cell = ring * cols +
  // column. The obstacle returns are tested against the cell of their bin's representative
  // (3.3 step 1; bin_cell): the returns of a bin, one laser across one column, mostly lie
  // within a cell of it in r.
  float* __restrict grid = local_grid_.data();
  std::fill(grid, grid + 2 * cells, 0.f);
  const std::size_t bin_count = static_cast<std::size_t>(cols) << shift;
  uint32_t* __restrict bin_cell = local_bin_cell_.data();
  const float* rep_rh = rep_.data() + 2;
  for (std::size_t b = 0; b < bin_count; ++b) {
    const float r = rep_rh[2 * b];
    int ring = static_cast<int>(std::max(r, 0.f) * inv_cell);
    ring = ring < last_ring ? ring : last_ring;
    bin_cell[b] = static_cast<uint32_t>(ring * cols + static_cast<int>(b >> shift));
  }
  // A return labelled ground is a known one: its bin is in the grid.
  forEachLabelled(labels, n, kLabelGround, [=](std::size_t i) {
    int ring = static_cast<int>(rr[i] * inv_cell);
    ring = ring < last_ring ? ring : last_ring;
    float* g = grid + 2 * (static_cast<std::size_t>(ring) * cols + (bins[i] >> shift));
    g[0] += hh[i];
    g[1] += 1.f;
  });

  // The neighbourhood of each cell: local_ground_rings cells along r, then
  // local_ground_columns columns each side (around the circle), summed.
  const int wr = p.local_ground_rings;
  const int wc = std::min(p.local_ground_columns, (cols - 1) / 2);
  float* __restrict around = local_around_.data();
  if (wr > 0) {
    for (int k = 0; k < rings; ++k) {
      float* dst = around + 2 * static_cast<std::size_t>(k) * cols;
      std::fill(dst, dst + 2 * cols, 0.f);
      for (int q = std::max(0, k - wr); q <= std::min(last_ring, k + wr); ++q) {
        const float* src = grid + 2 * static_cast<std::size_t>(q) * cols;
        for (int c = 0; c < 2 * cols; ++c) dst[c] += src[c];
      }
    }
    std::copy(around, around + 2 * cells, grid);
  }
  // Across columns: the interior of a ring 2 * cols floats at a time, its wc first and last
  // columns around the circle.
  for (int k = 0; k < rings; ++k) {
    const float* __restrict src = grid + 2 * static_cast<std::size_t>(k) * cols;
    float* __restrict dst = around + 2 * static_cast<std::size_t>(k) * cols;
    std::copy(src, src + 2 * cols, dst);
    for (int d = 1; d <= wc; ++d) {
      for (int q = 2 * wc; q < 2 * (cols - wc); ++q) dst[q] += src[q - 2 * d] + src[q + 2 * d];
    }
    auto edge = [&](int c) {
      float s = 0.f, m = 0.f;
      for (int d = -wc; d <= wc; ++d) {
        const int cc = (c + d + cols) % cols;
        s += src[2 * cc];
        m += src[2 * cc + 1];
      }
      dst[2 * c] = s;
      dst[2 * c + 1] = m;
    };
    for (int c = 0; c < wc; ++c) edge(c);
    for (int c = cols - wc; c < cols; ++c) edge(c);
  }

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

  // Obstacle returns level with the ground around them become ground: per bin, the band of
  // heights around the mean ground height of its cell's neighbourhood (empty where it has fewer
  // than local_ground_min_returns ground returns).
  const float min_returns = static_cast<float>(p.local_ground_min_returns);
  const float below = p.local_ground_below, above = p.local_ground_above;
  const float thr = p.tolerances.obstacle_threshold;
  float* __restrict band = local_bin_band_.data();
  for (std::size_t b = 0; b < bin_count; ++b) {
    const float* a = around + 2 * static_cast<std::size_t>(bin_cell[b]);
    const bool enough = a[1] >= min_returns;
    const float mean = enough ? a[0] / a[1] : 0.f;
    band[2 * b] = enough ? mean - below : 1e30f;
    band[2 * b + 1] = enough ? mean + above : -1e30f;
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
