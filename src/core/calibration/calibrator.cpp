#include "ladar_perception/calibration/calibrator.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <cmath>
#include <sstream>

#include <time.h>

#include "ground_line_sweep.h"

namespace ladar_perception {
namespace calibration {

bool parseMetric(const std::string& name, Metric* metric) {
  if (name == "auto") {
    *metric = Metric::kAuto;
  } else if (name == "closest_point_raw") {
    *metric = Metric::kClosestPointRaw;
  } else if (name == "closest_point") {
    *metric = Metric::kClosestPoint;
  } else if (name == "average_height") {
    *metric = Metric::kAverageHeight;
  } else {
    return false;
  }
  return true;
}

const std::vector<std::string>& methodNames() {
  static const std::vector<std::string> names = {
      "coarse_to_fine", "refine",   "particle_filter",    "interval",
      "semi_independent", "gradient", "gradient_multiscale"};
  return names;
}

std::string defaultMethod() { return "coarse_to_fine"; }

bool isMethod(const std::string& name) {
  if (name.empty() || name == "default") return true;
  for (const std::string& n : methodNames()) {
    if (n == name) return true;
  }
  return false;
}

CalibrationParams thesisParticleFilterParams() {
  CalibrationParams p;
  p.method = "particle_filter";
  p.metric = Metric::kClosestPoint;
  p.bin_size = 3.0;
  p.trim_fraction = 0.5;
  p.use_minima = true;
  p.search.particles_per_step = 100;
  p.search.resampling_centres = 10;
  p.search.max_iterations = 150;
  p.search.min_spread << 0.01, 0.01, 0.01, 0.001, 0.001, 0.001;
  return p;
}

HypothesisCost::HypothesisCost(const CalibrationInput& input, const CalibrationParams& params)
    : params_(params), extractor_(params.bin_size) {
  target_ = thinScans(input.target, params.feature_voxel,
                      static_cast<std::size_t>(std::max(0, params.feature_max_points)));
  PointVector reference;
  accumulate(input.reference, input.reference_extrinsic, &reference);
  reference = voxelDownsample(reference, params.feature_voxel);
  if (reference.empty() || target_.empty()) return;
  sparse_ = isSparseTarget(input.target, params);
  if (params_.metric == Metric::kAuto) {
    params_.metric = isSparseTarget(input.target, params) ? Metric::kClosestPointRaw
                                                          : Metric::kClosestPoint;
  }
  if (params_.metric == Metric::kClosestPointRaw) {
    target_ = thinScans(input.target, params.feature_voxel,
                        static_cast<std::size_t>(std::max(0, params.raw_max_points)));
    const PointVector ref_points = voxelDownsample(reference, params.raw_reference_voxel);
    ref_points_.build(ref_points);
    ref_points_grid_.build(ref_points, static_cast<float>(params.raw_max_distance));
    valid_ = true;
    return;
  }
  if (params_.metric == Metric::kAverageHeight) {
    ref_grid_.build(reference, params.bin_size);
    valid_ = !ref_grid_.empty();
    return;
  }
  FeatureSet ref_features;
  extractor_.extract(reference, &ref_features);
  ref_maxima_.build(ref_features.maxima);
  ref_minima_.build(ref_features.minima);
  valid_ = !ref_maxima_.empty();
}

double HypothesisCost::operator()(const Pose6& target_extrinsic) {
  if (!valid_) return std::numeric_limits<double>::infinity();
  for (int i = 0; i < 6; ++i) {  // outside the search region
    const double d = i < 3 ? std::abs(target_extrinsic[i] - params_.initial[i])
                           : std::abs(wrapAngle(target_extrinsic[i] - params_.initial[i]));
    if (params_.spread[i] > 0 && d > params_.region * params_.spread[i]) {
      return std::numeric_limits<double>::infinity();
    }
  }
  if (sparse_ && grazesGround(target_extrinsic, params_.ground_z, params_.min_ground_incidence,
                              params_.target_max_range)) {
    return std::numeric_limits<double>::infinity();
  }
  accumulate(target_, toIsometry(target_extrinsic), &accumulated_);
  if (params_.metric == Metric::kAverageHeight) return ref_grid_.error(accumulated_);
  if (params_.metric == Metric::kClosestPointRaw) {
    // eq 4.1 over the points, with distances capped (a far point costs the cap, and the KD-tree
    // search stops there).
    const float cap2 = static_cast<float>(params_.raw_max_distance * params_.raw_max_distance);
    scratch_.resize(accumulated_.size());
    for (std::size_t i = 0; i < accumulated_.size(); ++i) {
      float d2 = cap2;
      int j = ref_points_grid_.nearest(accumulated_[i], &d2, cap2);
      if (j == NearestGrid::kUndecided) j = ref_points_.nearest(accumulated_[i], &d2, cap2);
      if (j < 0) d2 = cap2;
      scratch_[i] = d2;
    }
    return trimmedMean(&scratch_, params_.trim_fraction);
  }
  extractor_.extract(accumulated_, &features_);
  if (features_.maxima.empty()) return std::numeric_limits<double>::infinity();
  // eq 4.1 over the local maxima, and over the local minima when enabled; one trimmed mean
  // over both sets so that each feature counts once.
  scratch_.clear();
  scratch_.reserve(2 * features_.maxima.size());
  for (const Eigen::Vector3f& f : features_.maxima) {
    float d2 = 0;
    ref_maxima_.nearest(f, &d2);
    scratch_.push_back(d2);
  }
  if (params_.use_minima) {
    for (const Eigen::Vector3f& f : features_.minima) {
      float d2 = 0;
      ref_minima_.nearest(f, &d2);
      scratch_.push_back(d2);
    }
  }
  return trimmedMean(&scratch_, params_.trim_fraction);
}

bool isSparseTarget(const ScanSet& target, const CalibrationParams& params) {
  const double per_scan = static_cast<double>(target.numPoints()) /
                          std::max<std::size_t>(1, target.numScans());
  return per_scan < params.sparse_scan_points;
}

bool insideRegion(const Pose6& p, const CalibrationParams& params) {
  for (int i = 0; i < 6; ++i) {
    const double d = i < 3 ? std::abs(p[i] - params.initial[i])
                           : std::abs(wrapAngle(p[i] - params.initial[i]));
    if (params.spread[i] > 0 && d > params.region * params.spread[i]) return false;
  }
  return true;
}

double sparseTargetCost(const Linearisation& lin, std::size_t target_points,
                        const RefinementParams& params) {
  if (target_points == 0) return std::numeric_limits<double>::infinity();
  return robustCostOverAll(lin, target_points, params.max_correspondence_end, params.huber);
}

namespace {


using Clock = std::chrono::steady_clock;

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// The search's hypothesis score, the reference's dense surface model, the refinement's target
// and the 2D sweep's thinned targets: built once per calibrate() and shared by its coarse-search
// restarts, which differ from the first attempt in the seed only.
struct SharedModels {
  std::unique_ptr<HypothesisCost> cost;
  bool built = false;  // model and target
  SurfaceModel model;
  ScanSet target;
  ScanSet sweep_coarse_target, sweep_fine_target;  // empty until the sweep first needs them
};

CalibrationResult calibrateAttempt(const CalibrationInput& input,
                                   const CalibrationParams& params_in, const ProgressFn& progress,
                                   SharedModels* shared);

}  // namespace

CalibrationResult calibrate(const CalibrationInput& input, const CalibrationParams& params,
                            const ProgressFn& progress) {
  SharedModels shared;
  return calibrateAttempt(input, params, progress, &shared);
}

namespace {

// The search of a method (chapter 4.3): coarse_to_fine's particle filter stops early, the
// refinement takes over.
SearchResult coarseSearch(const CalibrationParams& params, const CostFn& cost, SearchParams search,
                          const ProgressFn& progress) {
  if (params.method == "coarse_to_fine") {
    search.min_spread = params.coarse_min_spread;
    search.max_iterations = params.coarse_max_iterations;
    search.patience = std::max(search.patience, 6);
    return particleFilter(cost, search, progress);
  }
  if (params.method == "particle_filter") return particleFilter(cost, search, progress);
  if (params.method == "interval") return intervalSearch(cost, search, progress);
  if (params.method == "semi_independent") return semiIndependentIntervalSearch(cost, search, progress);
  if (params.method == "gradient") return gradientDescent(cost, search, progress);
  return multiScaleGradientDescent(cost, search, progress);
}

// The step s with applyStep(from, s) == to (refinement.h's parametrisation).
Pose6 stepBetween(const Pose6& to, const Pose6& from) {
  const Eigen::Isometry3d a = toIsometry(to), b = toIsometry(from);
  const Eigen::AngleAxisd w(a.linear() * b.linear().transpose());
  Pose6 step;
  step.head<3>() = a.translation() - b.translation();
  step.tail<3>() = w.angle() * w.axis();
  return step;
}

// The refinement with the roles swapped (3D targets): the target, accumulated at `estimate`,
// becomes the surface model, and the reference's extrinsic is refined against it from its known
// value R. The reference's correction X moved onto the target, R X^-1 E, is that direction's
// estimate of the target. Each direction's error comes mostly from the noise of its own surface
// model, so the two errors are largely independent and their mean halves their variance.
Pose6 swappedEstimate(const CalibrationInput& input, const CalibrationParams& params,
                      const Pose6& estimate) {
  PointVector target_cloud;
  const Eigen::Isometry3d e = toIsometry(estimate);
  accumulate(input.target, e, &target_cloud);
  target_cloud = voxelDownsample(target_cloud, params.refinement.reference_voxel);
  SurfaceModel target_model;
  target_model.build(target_cloud, params.refinement);
  const ScanSet reference = refinementTarget(input.reference, params.refinement);
  RefinementParams rp = params.refinement;
  rp.max_correspondence_start = rp.max_correspondence_end;  // already converged
  // The weighting by the target's range noise describes the target, not the reference.
  rp.noise_floor = 0.0;
  rp.range_noise_per_m2 = 0.0;
  const Pose6 r = fromIsometry(input.reference_extrinsic);
  const Pose6 x = refine(target_model, reference, r, rp).extrinsic;
  return fromIsometry(input.reference_extrinsic * toIsometry(x).inverse() * e);
}

CalibrationResult calibrateAttempt(const CalibrationInput& input,
                                   const CalibrationParams& params_in, const ProgressFn& progress,
                                   SharedModels* shared) {
  const auto t0 = Clock::now();
  const double cpu0 = threadCpuSeconds();
  CalibrationResult out;
  CalibrationParams params = params_in;
  if (params.method.empty() || params.method == "default") params.method = defaultMethod();
  out.method = params.method;
  out.extrinsic = params.initial;
  const auto finish = [&](CalibrationResult& r) -> CalibrationResult& {
    r.elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    r.cpu_time = threadCpuSeconds() - cpu0;
    return r;
  };
  // The coarse search is stochastic: another draw of its particles (the next seed) may find the
  // right basin. At most params.coarse_restarts times; the result counts this attempt's work.
  const auto restartCoarseSearch = [&]() -> CalibrationResult {
    CalibrationParams again = params;
    again.coarse_restarts = params.coarse_restarts - 1;
    again.search.seed = params.search.seed + 1;
    CalibrationResult retry = calibrateAttempt(input, again, progress, shared);
    retry.evaluations += out.evaluations;
    retry.restarts += 1;
    return finish(retry);
  };
  if (!isMethod(params.method)) {
    out.message = "unknown method '" + params.method + "'";
    return finish(out);
  }
  if (input.reference.empty() || input.target.empty()) {
    out.message = std::string("no data: ") + std::to_string(input.reference.numScans()) +
                  " reference and " + std::to_string(input.target.numScans()) +
                  " target scans with points";
    return finish(out);
  }
  if (!params.initial.allFinite() || !params.spread.allFinite() || (params.spread.array() < 0).any()) {
    out.message = "the initial guess and spread must be finite and the spread non-negative";
    return finish(out);
  }
  SearchParams search = params.search;
  search.initial = params.initial;
  search.spread = params.spread;
  for (int i = 0; i < 6; ++i) search.active[i] = search.active[i] && params.spread[i] > 0;

  Pose6 estimate = params.initial;
  bool cancelled = false;
  const bool refine_only = params.method == "refine";
  if (!refine_only) {
    if (!shared->cost) shared->cost.reset(new HypothesisCost(input, params));
    HypothesisCost& cost_fn = *shared->cost;
    if (!cost_fn.valid()) {
      out.message = "the reference gives no features (empty after thinning?)";
      return finish(out);
    }
    const CostFn cost = [&cost_fn](const Pose6& p) { return cost_fn(p); };
    out.search = coarseSearch(params, cost, search, progress);
    estimate = out.search.best;
    out.final_cost = out.search.best_cost;
    out.evaluations = out.search.evaluations;
    out.trace = out.search.trace;
    cancelled = out.search.cancelled;
  }

  // The dense surface model serves the refinement and the observability check of every method.
  const bool sparse = isSparseTarget(input.target, params);
  if (sparse && params.sparse_keep_edges) params.refinement.keep_edges = true;
  if (sparse && params.sparse_noise_floor > 0) params.refinement.noise_floor = params.sparse_noise_floor;
  if (sparse) params.refinement.extrapolation_steps = params.sparse_extrapolation_steps;
  if (!shared->built) {
    PointVector reference;
    accumulate(input.reference, input.reference_extrinsic, &reference);
    reference = voxelDownsample(reference, params.refinement.reference_voxel);
    shared->model.build(reference, params.refinement);
    shared->target = refinementTarget(input.target, params.refinement);
    shared->built = true;
  }
  const SurfaceModel& model = shared->model;
  const ScanSet& target = shared->target;
  Linearisation lin;
  if (!cancelled && params.method == "coarse_to_fine" && sparse && params.plane_sweep_steps > 0) {
    groundLineSweep(input, params, progress, shared->model, shared->target, &shared->sweep_coarse_target,
                    &shared->sweep_fine_target, &estimate, &cancelled, &out);
  }
  // The coarse search settled where no member of the sweep stays possible (every refinement of
  // one left the search region or laid the scan plane flat): a wrong basin. The full refinement
  // from there would only walk off (2-3 m, ~5 s CPU) before the restart below; the coarse search
  // restarts now instead. (Its last attempt still goes on, so that the failure is reported.)
  if (!cancelled && params.method == "coarse_to_fine" && sparse && params.plane_sweep_steps > 0 &&
      out.plane_sweep.empty() && params.coarse_restarts > 0) {
    return restartCoarseSearch();
  }
  const bool after_sweep = sparse && !out.plane_sweep.empty();  // a 2D ladar's swept member
  // The final refinement's target: a 2D ladar's, thinned in normal space at the sweep's member
  // (CalibrationParams::sparse_level_keep_every).
  ScanSet level_thinned;
  const ScanSet* final_target = &target;
  if (!cancelled && after_sweep && params.sparse_level_keep_every > 1) {
    level_thinned = thinLevelSurfaceReturns(model, target, estimate,
                                            params.refinement.max_correspondence_end,
                                            params.sparse_level_normal_z,
                                            params.sparse_level_keep_every);
    final_target = &level_thinned;
  }
  double swept_member_moved = 0;  // [m] in x and y, by the final refinement
  // The polish's profile along the ground-line family: its rise two steps from its minimum.
  double family_rise = std::numeric_limits<double>::quiet_NaN();
  // The refinement's own minimum, before a 3D target's two directions are averaged: the
  // observability is read there (the mean is not a minimum of the cost the check reads, and
  // along a direction the scene does not fix it could sit anywhere).
  Pose6 one_way = estimate;
  if (!cancelled && (refine_only || params.method == "coarse_to_fine")) {
    RefinementParams rp = params.refinement;
    if (after_sweep) {
      rp.max_correspondence_start = rp.max_correspondence_end;  // already on the right member
      if (params.sparse_final_iterations > 0) rp.max_iterations = params.sparse_final_iterations;
      if (final_target != &target) rp.extrapolation_steps = params.sparse_level_extrapolation_steps;
      if (!groundLineStepDirection(estimate, params.ground_z, &rp.frozen_direction)) {
        rp.frozen_direction.setZero();
      }
    }
    out.refinement = refine(model, *final_target, estimate, rp, progress);
    swept_member_moved = (out.refinement.extrinsic.head<2>() - estimate.head<2>()).norm();
    cancelled = out.refinement.cancelled;
    estimate = out.refinement.extrinsic;
    if (!cancelled && after_sweep && swept_member_moved <= params.plane_sweep_consistency) {
      family_rise = polishGroundLineRotation(params, progress, model, target, *final_target, rp,
                                             &estimate, &out.refinement, &cancelled, &out);
    }
    out.trace.insert(out.trace.end(), out.refinement.trace.begin(), out.refinement.trace.end());
    out.evaluations += out.refinement.iterations;
    lin = out.refinement.at_solution;
    out.final_cost = lin.cost;
    one_way = estimate;
    if (!cancelled && !sparse && params.symmetric_refinement) {
      const Pose6 swapped = swappedEstimate(input, params, estimate);
      estimate = applyStep(estimate, 0.5 * stepBetween(swapped, estimate));
    }
  }
  // A solution outside the search region: the coarse search settled in a wrong basin, and it
  // restarts with its next seed before the observability check is spent on it. So does a 2D
  // ladar's solution that the final refinement moved farther in x and y from the sweep's member
  // than the members refined alike differ (plane_sweep_consistency): that member had not
  // converged, and the sweep was run from a wrong basin (seed 3's trial 0: 1.6 m off in x).
  const bool outside = !insideRegion(estimate, params);
  const bool member_unconverged =
      after_sweep && swept_member_moved > params.plane_sweep_consistency;
  if ((outside || member_unconverged) && !cancelled && params.method == "coarse_to_fine" &&
      params.coarse_restarts > 0) {
    return restartCoarseSearch();
  }
  // The curvature means something only at a minimum of the dense cost. A search method that is
  // not refined (the thesis's particle filter, ...) may stop on a slope of it; the observability
  // is then read at the nearest minimum (a copy refined from the solution, the reported extrinsic
  // stays the method's), and a solution far from that minimum is reported as not converged
  // instead of blaming the scene.
  Pose6 at = one_way;
  Pose6 to_minimum = Pose6::Zero();
  if (!cancelled && !(refine_only || params.method == "coarse_to_fine")) {
    RefinementParams rp = params.refinement;
    rp.max_correspondence_start = rp.max_correspondence_end;
    at = refine(model, target, estimate, rp).extrinsic;
    to_minimum = poseDifference(at, estimate);
  }
  // The check reads the whole target (what the data can fix), not the refinement's thinned one,
  // with the residuals' scores summed per surface patch for the reported standard deviations.
  const double max_corr = params.refinement.max_correspondence_end;
  lin = linearise(model, target, at, max_corr, params.refinement, nullptr,
                  params.observability.score_cluster);
  const CostAlong cost_along = [&](const Pose6& step) {
    return linearise(model, target, applyStep(at, step), max_corr, params.refinement).cost;
  };
  const LossesAlong losses_along = [&](const Pose6& step, std::vector<float>* losses) {
    linearise(model, target, applyStep(at, step), max_corr, params.refinement, losses);
  };
  out.observability = analyseObservability(
      lin.hessian, lin.residual_variance, lin.correspondences, lin.lever_arm, params.observability,
      cost_along, losses_along,
      lin.score_clusters >= params.observability.min_score_clusters ? &lin.score_covariance
                                                                     : nullptr);
  out.stddev = out.observability.stddev;
  out.unobservable = out.observability.unobservable_names;
  out.extrinsic = estimate;
  // A flat profile along the ground-line family: its rotation is not determined by the data,
  // whatever the curvature at the solution says. The DOFs it moves are named (a rotation axis
  // carrying 30 % of the rotation; a translation moving 1 cm or more per 0.01 rad).
  Pose6 family;
  if (family_rise < params.plane_sweep_flat_rise &&
      groundLineStepDirection(estimate, params.ground_z, &family)) {
    const double turn = family.tail<3>().norm();
    for (int i = 0; i < 6 && turn > 0; ++i) {
      const double per_rad = std::abs(family[i]) / turn;
      if (per_rad < (i < 3 ? 1.0 : 0.3)) continue;
      out.stddev[i] = std::numeric_limits<double>::infinity();
      const std::string name = dofName(i);
      if (std::find(out.unobservable.begin(), out.unobservable.end(), name) == out.unobservable.end()) {
        out.unobservable.push_back(name);
      }
    }
  }

  std::ostringstream msg;
  if (cancelled) {
    msg << "cancelled";
  } else if (outside) {
    msg << "the solution left the search region (initial guess +- " << params.region
        << " x spread): " << estimate.transpose();
  } else if (std::max(to_minimum.head<3>().cwiseAbs().maxCoeff(),
                      lin.lever_arm * to_minimum.tail<3>().cwiseAbs().maxCoeff()) >
             params.observability.max_stddev) {
    msg << params.method << " did not converge: the nearest minimum of the dense point-to-plane "
        << "cost is " << to_minimum.transpose() << " (x y z m, roll pitch yaw rad) away";
  } else if (lin.correspondences < 100) {
    msg << "too few correspondences between the clouds at the solution (" << lin.correspondences
        << "): do the sensors see the same surfaces?";
  } else if (!out.unobservable.empty()) {
    out.partial = !member_unconverged;
    msg << "the scene cannot fix " << joinNames(out.unobservable)
        << " (cost curvature " << out.observability.relative_min
        << " of the strongest): their values are not determined by the data; the other DOFs are";
  } else if (member_unconverged) {
    msg << "the final refinement moved the ground-line sweep's member by " << swept_member_moved
        << " m in x and y: the sweep did not converge (a wrong basin of the coarse search)";
  } else {
    out.success = true;
    msg << params.method << ": " << out.evaluations << " evaluations, final cost "
        << out.final_cost;
  }
  out.message = msg.str();
  finish(out);
  if (!out.message.empty() && out.success) {
    std::ostringstream t;
    t << out.message << ", " << out.elapsed << " s";
    out.message = t.str();
  }
  return out;
}

}  // namespace

Pose6 repeatability(const CalibrationInput& input, const CalibrationParams& params,
                    const Pose6& solution, int windows, std::vector<Pose6>* window_solutions) {
  Pose6 spread = Pose6::Constant(std::numeric_limits<double>::quiet_NaN());
  const std::size_t n = std::min(input.reference.numScans(), input.target.numScans());
  windows = std::max(2, windows);
  if (n < static_cast<std::size_t>(windows)) return spread;
  std::vector<Pose6> sols;
  for (int w = 0; w < windows; ++w) {
    // Disjoint windows by time: scan indices [w n / W, (w+1) n / W) of each sensor.
    CalibrationInput part;
    part.reference_extrinsic = input.reference_extrinsic;
    const std::size_t nr = input.reference.numScans(), nt = input.target.numScans();
    part.reference = input.reference.subset(w * nr / windows, (w + 1) * nr / windows);
    part.target = input.target.subset(w * nt / windows, (w + 1) * nt / windows);
    PointVector reference;
    accumulate(part.reference, part.reference_extrinsic, &reference);
    reference = voxelDownsample(reference, params.refinement.reference_voxel);
    SurfaceModel model;
    model.build(reference, params.refinement);
    const ScanSet target = refinementTarget(part.target, params.refinement);
    RefinementParams rp = params.refinement;
    rp.max_correspondence_start = rp.max_correspondence_end;
    sols.push_back(refine(model, target, solution, rp).extrinsic);
  }
  Pose6 mean = Pose6::Zero();
  for (const Pose6& s : sols) mean += s;
  mean /= sols.size();
  Pose6 var = Pose6::Zero();
  for (const Pose6& s : sols) var += poseDifference(s, mean).cwiseAbs2();
  spread = (var / static_cast<double>(sols.size() - 1)).cwiseSqrt();
  if (window_solutions) *window_solutions = sols;
  return spread;
}

}  // namespace calibration
}  // namespace ladar_perception
