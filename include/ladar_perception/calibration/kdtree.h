// A small 3D KD-tree for the closest-point metric (eq 4.1) and the refinement's correspondences:
// built once per reference cloud, then queried per hypothesis without allocation.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace ladar_perception {
namespace calibration {

class KdTree {
 public:
  KdTree() = default;
  explicit KdTree(const std::vector<Eigen::Vector3f>& points) { build(points); }

  // Copies the points (reordered internally); indices returned refer to the input order.
  void build(const std::vector<Eigen::Vector3f>& points);
  std::size_t size() const { return points_.size(); }
  bool empty() const { return points_.empty(); }

  // Index of the closest point within sqrt(max_sq_dist), or -1; *sq_dist its squared distance.
  int nearest(const Eigen::Vector3f& query, float* sq_dist,
              float max_sq_dist = std::numeric_limits<float>::infinity()) const;
  // The k closest points, closest first (fewer when the tree holds fewer). Uses the caller's
  // vectors as storage.
  void knn(const Eigen::Vector3f& query, int k, std::vector<int>* indices,
           std::vector<float>* sq_dists) const;
  const Eigen::Vector3f& point(int index) const { return points_[position_[index]]; }

 private:
  struct Node {
    float split = 0;
    int axis = -1;  // -1 for a leaf
    int left = -1, right = -1;
    int begin = 0, end = 0;
  };
  int buildNode(int begin, int end, int depth);
  void nearestIn(int node, const Eigen::Vector3f& q, float* best_d2, int* best) const;
  void knnIn(int node, const Eigen::Vector3f& q, int k, std::vector<int>* idx,
             std::vector<float>* d2) const;

  std::vector<Eigen::Vector3f> points_;  // reordered
  std::vector<int> original_;            // reordered position -> input index
  std::vector<int> position_;            // input index -> reordered position
  std::vector<Node> nodes_;
  static constexpr int kLeafSize = 8;
};

}  // namespace calibration
}  // namespace ladar_perception
