#include "ladar_perception/calibration/kdtree.h"

#include <algorithm>
#include <numeric>

namespace ladar_perception {
namespace calibration {

void KdTree::build(const std::vector<Eigen::Vector3f>& points) {
  points_ = points;
  original_.resize(points.size());
  std::iota(original_.begin(), original_.end(), 0);
  nodes_.clear();
  nodes_.reserve(2 * points.size() / kLeafSize + 2);
  if (!points_.empty()) buildNode(0, static_cast<int>(points_.size()), 0);
  // Apply the permutation chosen on original_ to the points.
  std::vector<Eigen::Vector3f> reordered(points.size());
  position_.resize(points.size());
  for (std::size_t i = 0; i < original_.size(); ++i) {
    reordered[i] = points[original_[i]];
    position_[original_[i]] = static_cast<int>(i);
  }
  points_.swap(reordered);
}

int KdTree::buildNode(int begin, int end, int depth) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  nodes_[id].begin = begin;
  nodes_[id].end = end;
  if (end - begin <= kLeafSize) return id;
  // Split the widest axis at the median (points_ still in input order; sort original_).
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  for (int i = begin; i < end; ++i) {
    lo = lo.cwiseMin(points_[original_[i]]);
    hi = hi.cwiseMax(points_[original_[i]]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(original_.begin() + begin, original_.begin() + mid, original_.begin() + end,
                   [&](int a, int b) { return points_[a][axis] < points_[b][axis]; });
  const float split = points_[original_[mid]][axis];
  const int left = buildNode(begin, mid, depth + 1);
  const int right = buildNode(mid, end, depth + 1);
  Node& n = nodes_[id];
  n.axis = axis;
  n.split = split;
  n.left = left;
  n.right = right;
  return id;
}

void KdTree::nearestIn(int node, const Eigen::Vector3f& q, float* best_d2, int* best) const {
  const Node& n = nodes_[node];
  if (n.axis < 0) {
    for (int i = n.begin; i < n.end; ++i) {
      const float d2 = (points_[i] - q).squaredNorm();
      if (d2 < *best_d2) {
        *best_d2 = d2;
        *best = i;
      }
    }
    return;
  }
  const float diff = q[n.axis] - n.split;
  const int near = diff < 0 ? n.left : n.right;
  const int far = diff < 0 ? n.right : n.left;
  nearestIn(near, q, best_d2, best);
  if (diff * diff < *best_d2) nearestIn(far, q, best_d2, best);
}

int KdTree::nearest(const Eigen::Vector3f& query, float* sq_dist, float max_sq_dist) const {
  if (nodes_.empty()) return -1;
  float best_d2 = max_sq_dist;
  int best = -1;
  nearestIn(0, query, &best_d2, &best);
  if (sq_dist) *sq_dist = best_d2;
  return best < 0 ? -1 : original_[best];
}

void KdTree::knnIn(int node, const Eigen::Vector3f& q, int k, std::vector<int>* idx,
                   std::vector<float>* d2) const {
  const Node& n = nodes_[node];
  if (n.axis < 0) {
    for (int i = n.begin; i < n.end; ++i) {
      const float d = (points_[i] - q).squaredNorm();
      if (static_cast<int>(d2->size()) == k && d >= d2->back()) continue;
      // Insertion into the sorted list.
      auto pos = std::upper_bound(d2->begin(), d2->end(), d);
      const auto off = pos - d2->begin();
      d2->insert(pos, d);
      idx->insert(idx->begin() + off, i);
      if (static_cast<int>(d2->size()) > k) {
        d2->pop_back();
        idx->pop_back();
      }
    }
    return;
  }
  const float diff = q[n.axis] - n.split;
  const int near = diff < 0 ? n.left : n.right;
  const int far = diff < 0 ? n.right : n.left;
  knnIn(near, q, k, idx, d2);
  if (static_cast<int>(d2->size()) < k || diff * diff < d2->back()) knnIn(far, q, k, idx, d2);
}

void KdTree::knn(const Eigen::Vector3f& query, int k, std::vector<int>* indices,
                 std::vector<float>* sq_dists) const {
  indices->clear();
  sq_dists->clear();
  if (nodes_.empty() || k <= 0) return;
  knnIn(0, query, k, indices, sq_dists);
  for (int& i : *indices) i = original_[i];
}

}  // namespace calibration
}  // namespace ladar_perception
