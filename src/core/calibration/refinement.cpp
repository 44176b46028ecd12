#include "ladar_perception/calibration/refinement.h"

#include <cmath>
#include <limits>
#include <unordered_map>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace ladar_perception {
namespace calibration {

void SurfaceModel::build(const PointVector& points, const RefinementParams& params) {
  points_.clear();
  normals_.clear();
  spreads_.clear();
  neighbours_ = std::max(5, params.normal_neighbours);
  KdTree all(points);
  std::vector<int> idx;
  std::vector<float> d2;
  const int k = std::max(5, params.normal_neighbours);
  const float r2 = static_cast<float>(params.normal_radius * params.normal_radius);
  for (std::size_t i = 0; i < points.size(); ++i) {
    all.knn(points[i], k, &idx, &d2);
    int n = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < idx.size(); ++j) {
      if (d2[j] > r2) break;
      mean += points[idx[j]].cast<double>();
      ++n;
    }
    if (n < 5) {
      if (params.keep_edges) {
        points_.push_back(points[i]);
        normals_.push_back(Eigen::Vector3f::Zero());
        spreads_.push_back(static_cast<float>(params.normal_radius));  // isolated: unknown
      }
      continue;
    }
    mean /= n;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d d = points[idx[j]].cast<double>() - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector3d ev = es.eigenvalues();  // ascending
    const double sum = ev.sum();
    if (!(sum > 0) || ev[0] / sum > params.max_curvature) {  // not a surface point
      if (params.keep_edges) {
        points_.push_back(points[i]);
        normals_.push_back(Eigen::Vector3f::Zero());
        spreads_.push_back(static_cast<float>(std::sqrt(std::max(0.0, sum) / n)));
      }
      continue;
    }
    points_.push_back(mean.cast<float>());  // the local plane's centroid: noise averaged
    normals_.push_back(es.eigenvectors().col(0).cast<float>());
    spreads_.push_back(static_cast<float>(std::sqrt(std::max(0.0, ev[0]) / n)));
  }
  tree_.build(points_);
  grid_.build(points_, static_cast<float>(std::max(0.05, params.max_correspondence_end)));
}

Linearisation linearise(const SurfaceModel& model, const ScanSet& target, const Pose6& extrinsic,
                        double max_correspondence, double huber, double noise_floor,
                        double range_noise, double reference_noise,
                        std::vector<float>* point_loss, double score_cluster,
                        double range_noise_per_m2) {
  Linearisation lin;
  if (point_loss) point_loss->assign(target.numPoints(), std::numeric_limits<float>::quiet_NaN());
  if (model.empty()) return lin;
  const Eigen::Isometry3d t_bs = toIsometry(extrinsic);
  const Eigen::Matrix3d r_bs = t_bs.linear();
  const float max2 = static_cast<float>(max_correspondence * max_correspondence);
  const bool range_weighted = noise_floor > 0 && (range_noise > 0 || range_noise_per_m2 > 0);
  const double nf2 = noise_floor * noise_floor, rn2 = range_noise * range_noise;
  const double ref2 = reference_noise * reference_noise;
  const double inv_k = 1.0 / std::max(1, model.neighbours());
  Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
  Pose6 g = Pose6::Zero();
  double loss = 0, wr2 = 0, wsum = 0, lever2 = 0;
  long n = 0;
  // Score sums per cluster (score_cluster > 0), keyed by the surface point's cube.
  const bool clustered = score_cluster > 0;
  const double inv_cluster = clustered ? 1.0 / score_cluster : 0.0;
  std::unordered_map<int64_t, int> cluster_of;
  std::vector<Pose6> cluster_scores;
  for (std::size_t k = 0; k < target.numScans(); ++k) {
    const Eigen::Isometry3d t_os = target.vehicle_poses[k] * t_bs;
    const Eigen::Matrix3f r_os = t_os.linear().cast<float>();
    const Eigen::Vector3f p_os = t_os.translation().cast<float>();
    const Eigen::Matrix3d r_ob = target.vehicle_poses[k].linear();
    for (uint32_t i = target.scan_begin[k]; i < target.scan_begin[k + 1]; ++i) {
      const Eigen::Vector3f& ps = target.points[i];
      const Eigen::Vector3f po = r_os * ps + p_os;
      float d2 = 0;
      const int j = model.nearest(po, &d2, max2);
      if (j < 0) continue;
      const Eigen::Vector3d nrm = model.normals()[j].cast<double>();
      const Eigen::Vector3d lever = r_bs * ps.cast<double>();
      Eigen::Vector3d e = (po - model.points()[j]).cast<double>();
      const bool edge = nrm.squaredNorm() < 0.25;
      // The residual's scale: 1, or noise_floor over its expected spread (RefinementParams).
      double scale = 1.0;
      if (noise_floor > 0) {
        const double sj2 = static_cast<double>(model.spreads()[j]) * model.spreads()[j];
        if (range_weighted) {
          double rn2_here = rn2;
          if (range_noise_per_m2 > 0) {  // sigma = range_noise + range_noise_per_m2 r^2
            const double sigma = range_noise + range_noise_per_m2 * ps.squaredNorm();
            rn2_here = sigma * sigma;
          }
          double var = rn2_here + sj2;  // edge: the whole range error is in the residual
          if (!edge) {
            const double un = (po - p_os).cast<double>().dot(nrm) /
                              std::max(1e-6, static_cast<double>(ps.norm()));
            var = rn2_here * un * un + sj2 * inv_k + ref2;
          }
          scale = noise_floor / std::sqrt(std::max(var, 1e-12));
        } else {
          scale = noise_floor / std::sqrt(nf2 + sj2);
        }
        e *= scale;
      }
      // Plane: r = n . e (eq. of the surface); edge: |e| over the three odom axes.
      const double r = edge ? e.norm() : nrm.dot(e);
      const double ar = std::abs(r);
      const double w = ar <= huber ? 1.0 : huber / ar;  // Huber weight (IRLS)
      const double li = ar <= huber ? 0.5 * r * r : huber * (ar - 0.5 * huber);
      loss += li;
      if (point_loss) (*point_loss)[i] = static_cast<float>(li);
      Pose6 score = Pose6::Zero();  // this point's w r J (when clustered)
      if (edge) {
        for (int a = 0; a < 3; ++a) {
          const Eigen::Vector3d m = scale * r_ob.row(a).transpose();  // odom axis a, base_link
          Eigen::Matrix<double, 6, 1> jac;
          jac.head<3>() = m;
          jac.tail<3>() = lever.cross(m);
          h.noalias() += w * jac * jac.transpose();
          g.noalias() += w * e[a] * jac;
          if (clustered) score.noalias() += w * e[a] * jac;
        }
      } else {
        const Eigen::Vector3d m = scale * (r_ob.transpose() * nrm);  // normal in base_link axes
        Eigen::Matrix<double, 6, 1> jac;
        jac.head<3>() = m;
        jac.tail<3>() = lever.cross(m);
        h.noalias() += w * jac * jac.transpose();
        g.noalias() += w * r * jac;
        if (clustered) score.noalias() = w * r * jac;
      }
      if (clustered) {
        // The cube's coordinates, 21 bits each (+-2^20 cubes, clamped beyond).
        const Eigen::Array3d c = (model.points()[j].cast<double>() * inv_cluster)
                                     .array().floor().max(-1048575.0).min(1048575.0) + 1048576.0;
        const int64_t key = (static_cast<int64_t>(c.x()) << 42) |
                            (static_cast<int64_t>(c.y()) << 21) | static_cast<int64_t>(c.z());
        const auto added = cluster_of.emplace(key, static_cast<int>(cluster_scores.size()));
        if (added.second) cluster_scores.push_back(Pose6::Zero());  // a new cube
        cluster_scores[added.first->second] += score;
      }
      wr2 += w * r * r;
      wsum += w;
      lever2 += lever.squaredNorm();
      ++n;
    }
  }
  lin.hessian = h;
  lin.gradient = g;
  if (clustered && cluster_scores.size() > 1) {
    // The covariance of the cluster sums about their mean, times their number (with the small
    // sample correction): sum_c (s_c - s) (s_c - s)^T * C / (C - 1).
    const double count = static_cast<double>(cluster_scores.size());
    const Pose6 mean = g / count;
    Matrix6 m = Matrix6::Zero();
    for (const Pose6& sc : cluster_scores) m.noalias() += (sc - mean) * (sc - mean).transpose();
    lin.score_covariance = m * (count / (count - 1.0));
    lin.score_clusters = static_cast<long>(cluster_scores.size());
  }
  lin.correspondences = n;
  lin.cost = n > 0 ? loss / n : std::numeric_limits<double>::infinity();
  lin.residual_variance = wsum > 0 ? wr2 / wsum : 0;
  lin.lever_arm = n > 0 ? std::sqrt(lever2 / n) : 1.0;
  return lin;
}

Linearisation linearise(const SurfaceModel& model, const ScanSet& target, const Pose6& extrinsic,
                        double max_correspondence, const RefinementParams& params,
                        std::vector<float>* point_loss, double score_cluster) {
  return linearise(model, target, extrinsic, max_correspondence, params.huber, params.noise_floor,
                   params.range_noise, params.reference_noise, point_loss, score_cluster,
                   params.range_noise_per_m2);
}

double robustCostOverAll(const Linearisation& lin, std::size_t target_points,
                         double max_correspondence, double huber) {
  if (target_points == 0) return std::numeric_limits<double>::infinity();
  const double cap = max_correspondence;
  const double miss = cap <= huber ? 0.5 * cap * cap : huber * (cap - 0.5 * huber);
  const long n = std::min<long>(lin.correspondences, static_cast<long>(target_points));
  const double sum = n > 0 ? lin.cost * static_cast<double>(n) : 0.0;
  return (sum + miss * static_cast<double>(target_points - n)) / static_cast<double>(target_points);
}

Pose6 applyStep(const Pose6& extrinsic, const Pose6& step) {
  Eigen::Isometry3d t = toIsometry(extrinsic);
  const Eigen::Vector3d w = step.tail<3>();
  const double angle = w.norm();
  if (angle > 0) t.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() * t.linear();
  t.translation() += step.head<3>();
  Pose6 out = fromIsometry(t);
  return out;
}

ScanSet refinementTarget(const ScanSet& target, const RefinementParams& params) {
  return thinScans(target, params.target_voxel,
                   static_cast<std::size_t>(std::max(0, params.max_target_points)));
}

ScanSet thinLevelSurfaceReturns(const SurfaceModel& model, const ScanSet& target,
                                const Pose6& extrinsic, double max_correspondence,
                                double min_normal_z, int keep_every) {
  if (keep_every <= 1 || model.empty()) return target;
  PointVector projected;  // the target in the odom frame at `extrinsic`
  accumulate(target, toIsometry(extrinsic), &projected);
  const float max2 = static_cast<float>(max_correspondence * max_correspondence);
  const float nz_min = static_cast<float>(min_normal_z);
  ScanSet out;
  out.points.reserve(target.numPoints());
  PointVector kept;
  long level = 0;
  for (std::size_t k = 0; k < target.numScans(); ++k) {
    kept.clear();
    for (uint32_t i = target.scan_begin[k]; i < target.scan_begin[k + 1]; ++i) {
      float d2 = 0;
      const int j = model.nearest(projected[i], &d2, max2);
      if (j >= 0 && std::abs(model.normals()[j].z()) >= nz_min && level++ % keep_every != 0) {
        continue;
      }
      kept.push_back(target.points[i]);
    }
    out.addScan(target.stamps[k], target.vehicle_poses[k], kept);
  }
  return out;
}

RefinementResult refine(const SurfaceModel& model, const ScanSet& target, const Pose6& initial,
                        const RefinementParams& params, const ProgressFn& progress) {
  RefinementResult res;
  res.extrinsic = initial;
  const int iters = std::max(1, params.max_iterations);
  Linearisation reuse;  // at res.extrinsic with reuse_corr, from the extrapolation
  double reuse_corr = 0;
  bool reuse_valid = false;
  double accepted_multiple = 1.0;  // of the previous iteration's step (extrapolation_steps)
  for (int it = 0; it < iters; ++it) {
    // Correspondence distance shrinks over the first half, then stays at the end value.
    const double f = std::min(1.0, it / std::max(1.0, 0.5 * iters));
    const double max_corr = params.max_correspondence_start +
                            f * (params.max_correspondence_end - params.max_correspondence_start);
    // The previous iteration's extrapolation already linearised here (same distance): reused.
    const Linearisation lin = reuse_valid && reuse_corr == max_corr
                                  ? reuse
                                  : linearise(model, target, res.extrinsic, max_corr, params);
    reuse_valid = false;
    if (lin.correspondences < 6) break;
    Matrix6 a = lin.hessian;
    const double floor = 1e-9 * std::max(1e-12, a.diagonal().maxCoeff());
    for (int i = 0; i < 6; ++i) a(i, i) += params.damping * a(i, i) + floor;
    Pose6 step;
    if (params.frozen_direction.norm() > 0) {
      // Basis of the complement of the frozen direction; solve the 5-DOF system in it.
      const Pose6 v = params.frozen_direction.normalized();
      const Matrix6 proj = Matrix6::Identity() - v * v.transpose();
      Eigen::JacobiSVD<Matrix6> svd(proj, Eigen::ComputeFullU);
      const Eigen::Matrix<double, 6, 5> b = svd.matrixU().leftCols<5>();
      const Eigen::Matrix<double, 5, 5> ab = b.transpose() * a * b;
      step = -b * ab.ldlt().solve(b.transpose() * lin.gradient);
    } else {
      step = -a.ldlt().solve(lin.gradient);
    }
    if (!step.allFinite()) break;
    if (params.extrapolation_steps > 0) {
      // Each trial point is linearised in full: the accepted one serves the next iteration. The
      // trials start at half the previous iteration's accepted multiple (the pull-back is much
      // the same from one iteration to the next), or at the plain step if that raised the cost.
      const double current = robustCostOverAll(lin, target.numPoints(), max_corr, params.huber);
      const double cap = std::ldexp(1.0, params.extrapolation_steps);
      double multiple = std::max(1.0, 0.5 * accepted_multiple);
      reuse = linearise(model, target, applyStep(res.extrinsic, multiple * step), max_corr, params);
      double best = robustCostOverAll(reuse, target.numPoints(), max_corr, params.huber);
      if (multiple > 1.0 && !(best < current)) {
        multiple = 1.0;
        reuse = linearise(model, target, applyStep(res.extrinsic, step), max_corr, params);
        best = robustCostOverAll(reuse, target.numPoints(), max_corr, params.huber);
      }
      while (2.0 * multiple <= cap) {
        Linearisation longer = linearise(model, target, applyStep(res.extrinsic, 2.0 * multiple * step),
                                         max_corr, params);
        const double c = robustCostOverAll(longer, target.numPoints(), max_corr, params.huber);
        if (!(c < best)) break;
        best = c;
        multiple *= 2.0;
        reuse = longer;
      }
      step *= multiple;
      accepted_multiple = multiple;
      reuse_corr = max_corr;
      reuse_valid = true;
    }
    res.extrinsic = applyStep(res.extrinsic, step);
    res.iterations = it + 1;
    res.trace.push_back(res.extrinsic);
    if (progress) {
      SearchProgress p;
      p.stage = "refinement";
      p.iteration = it + 1;
      p.evaluations = it + 1;
      p.best_cost = lin.cost;
      p.estimate = res.extrinsic;
      p.spread = step.cwiseAbs();
      if (!progress(p)) {
        res.cancelled = true;
        break;
      }
    }
    if (f >= 1.0 && step.norm() < params.convergence) {
      res.converged = true;
      break;
    }
  }
  res.at_solution = reuse_valid && reuse_corr == params.max_correspondence_end
                        ? reuse
                        : linearise(model, target, res.extrinsic, params.max_correspondence_end,
                                    params);
  return res;
}

}  // namespace calibration
}  // namespace ladar_perception
