// Exact closest-point search within a short radius over a uniform grid, for the refinement's
// correspondences (the closest surface point within max_correspondence_end of each target
// point, and the coarse search's capped closest point of eq 4.1). A KD-tree query descends from
// the root and backtracks across splits for every target point; with cells as large as the
// search radius, every point within that radius of a query lies in the query's cell or one
// of its 26 neighbours. The query's own cell is scanned first, and a neighbour only when the
// query is nearer its shared face, edge or corner than the best point so far: near a surface,
// one or two cells answer it exactly.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace ladar_perception {
namespace calibration {

class NearestGrid {
 public:
  // Copies the points, sorted by cell; indices returned refer to the input order. cell [m] > 0.
  void build(const std::vector<Eigen::Vector3f>& points, float cell);
  bool empty() const { return points_.empty(); }
  float cell() const { return cell_; }

  // Index of the closest point within sqrt(max_sq_dist), or -1; *sq_dist its squared distance
  // (max_sq_dist when none). Exact when max_sq_dist <= cell^2, or when a point within one cell
  // size is found; otherwise returns kUndecided (the caller asks a KD-tree).
  static constexpr int kUndecided = -2;
  int nearest(const Eigen::Vector3f& query, float* sq_dist, float max_sq_dist) const;

 private:
  struct Cell {
    int64_t key;
    uint32_t begin, end;  // points_[begin, end)
  };
  static int64_t keyOf(int32_t ix, int32_t iy, int32_t iz);
  int cellIndex(int64_t key) const;  // into cells_, or -1

  float cell_ = 1.0f, inv_cell_ = 1.0f;
  std::vector<Eigen::Vector3f> points_;  // sorted by cell
  std::vector<int> original_;            // sorted position -> input index
  std::vector<Cell> cells_;
  std::vector<int32_t> slots_;  // open addressing: index into cells_, -1 when free
  uint64_t mask_ = 0;
};

}  // namespace calibration
}  // namespace ladar_perception
