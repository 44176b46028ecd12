#include "ladar_perception/calibration/calibrator.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <cmath>
#include <sstream>

#include <time.h>

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

double sparseTargetCost(const Linearisation& lin, std::size_t target_points,
                        const RefinementParams& params) {
  if (target_points == 0) return std::numeric_limits<double>::infinity();
  return robustCostOverAll(lin, target_points, params.max_correspondence_end, params.huber);
}

namespace {

bool insideRegion(const Pose6& p, const CalibrationParams& params) {
  for (int i = 0; i < 6; ++i) {
    const double d = i < 3 ? std::abs(p[i] - params.initial[i])
                           : std::abs(wrapAngle(p[i] - params.initial[i]));
    if (params.spread[i] > 0 && d > params.region * params.spread[i]) return false;
  }
  return true;
}

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
    if (params.method == "coarse_to_fine") {
      search.min_spread = params.coarse_min_spread;
      search.max_iterations = params.coarse_max_iterations;
      search.patience = std::max(search.patience, 6);
      out.search = particleFilter(cost, search, progress);
    } else if (params.method == "particle_filter") {
      out.search = particleFilter(cost, search, progress);
    } else if (params.method == "interval") {
      out.search = intervalSearch(cost, search, progress);
    } else if (params.method == "semi_independent") {
      out.search = semiIndependentIntervalSearch(cost, search, progress);
    } else if (params.method == "gradient") {
      out.search = gradientDescent(cost, search, progress);
    } else {
      out.search = multiScaleGradientDescent(cost, search, progress);
    }
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
    // The ground-line ambiguity of a 2D ladar (scan_plane.h): a local refinement slides along
    // the family, so the cost is profiled along it instead. Each member (the coarse estimate
    // rotated about its scan plane's ground line) is refined briefly with that rotation held
    // fixed; a parabola through the best member and its neighbours places the minimum; the final
    // refinement keeps the rotation held there.
    RefinementParams brief = params.refinement;
    brief.max_iterations = std::max(1, params.plane_sweep_iterations);
    brief.max_correspondence_start = std::min(brief.max_correspondence_start, 1.0);
    // The first pass only tells the 0.05 rad bins apart (costs 20-100 % apart): a thinner target
    // and plain Gauss-Newton. The later passes compare members a few per cent apart, so their
    // members are refined to convergence in x and y (extrapolated steps, started at the end
    // correspondence distance from the previous pass's converged best member).
    brief.extrapolation_steps = 0;
    RefinementParams fine = params.refinement;
    fine.max_iterations = std::max(1, params.plane_sweep_fine_iterations);
    fine.max_correspondence_start = fine.max_correspondence_end;
    // The passes' targets: the input thinned to that many points (once per calibrate()), or the
    // refinement's (0).
    const auto thinned = [&](int points, ScanSet* own) -> const ScanSet& {
      if (points <= 0) return target;
      if (own->numScans() == 0) {
        RefinementParams rp = params.refinement;
        rp.max_target_points = points;
        *own = refinementTarget(input.target, rp);
      }
      return *own;
    };
    const ScanSet& coarse_target = thinned(params.plane_sweep_coarse_points, &shared->sweep_coarse_target);
    const ScanSet& fine_target = thinned(params.plane_sweep_fine_points, &shared->sweep_fine_target);
    const auto possible = [&](const Pose6& p) {
      return insideRegion(p, params) &&
             !grazesGround(p, params.ground_z, params.min_ground_incidence,
                           params.target_max_range);
    };
    // The members are refined with the refinement's weighting but scored with the 2D ladar's
    // range noise in it (RefinementParams::range_noise): the ground's range noise otherwise
    // favours the flatter members. (With it in the refinement as well, y came out 0.1-0.2 m off.)
    RefinementParams scored = brief;
    scored.range_noise = params.sparse_range_noise;
    scored.reference_noise = params.sparse_reference_noise;
    // Refines a member with its ground-line rotation frozen and scores it; infinity when
    // impossible.
    const auto member = [&](const Pose6& start_pose, bool fine_pass, Pose6* refined) {
      if (!possible(start_pose)) return std::numeric_limits<double>::infinity();
      RefinementParams rp = fine_pass ? fine : brief;
      const ScanSet& points = fine_pass ? fine_target : coarse_target;
      if (!groundLineStepDirection(start_pose, params.ground_z, &rp.frozen_direction)) {
        rp.frozen_direction.setZero();
      }
      const RefinementResult r = refine(model, points, start_pose, rp, progress);
      cancelled = cancelled || r.cancelled;
      out.evaluations += r.iterations;
      *refined = r.extrinsic;
      if (!possible(r.extrinsic)) return std::numeric_limits<double>::infinity();
      const Linearisation at = scored.range_noise > 0
                                   ? linearise(model, points, r.extrinsic,
                                               scored.max_correspondence_end, scored)
                                   : r.at_solution;
      return sparseTargetCost(at, points.numPoints(), scored);
    };
    // The coarse estimate's other DOFs converged first (with the rotation frozen), so that the
    // members differ by the rotation only; then plane_sweep_passes passes: the whole range, then
    // each over the best member and the two halfway to its neighbours of the previous pass (a
    // bisection; the best member's cost is kept), started from that member, or at the same
    // spacing while the best is at the pass's edge; a least-squares parabola through all the
    // later passes' members places the minimum.
    {
      Pose6 refined;
      if (std::isfinite(member(estimate, false, &refined))) estimate = refined;
    }
    int steps = std::max(1, params.plane_sweep_steps);
    double range = params.plane_sweep_range;
    double kept_cost = std::numeric_limits<double>::infinity();  // the best member's so far
    int passes = std::max(1, params.plane_sweep_passes);
    int walks = 0;
    // The later passes' members (converged in the other DOFs, on the same target), by their
    // rotation from the first pass's best member: the profile the minimum is placed in. Members
    // compare only when refined alike (refinedAlike, plane_sweep_consistency): the coarse
    // estimate may be a metre off in x, and a member refined before x converged must not be
    // reused for, or fitted with, those refined after.
    std::vector<SweepMember> profile;
    double base = 0.0;  // the rotation of `estimate` from the first pass's best member
    for (int pass = 0; pass < passes && !cancelled; ++pass) {
      const double spacing = steps == 1 ? 0.0 : 2.0 * range / (steps - 1);
      std::vector<double> costs(steps, std::numeric_limits<double>::infinity());
      std::vector<Pose6> members(steps, estimate);
      std::vector<double> angles(steps, 0.0);
      int best_k = -1;
      for (int k = 0; k < steps && !cancelled; ++k) {
        const double angle = steps == 1 ? 0.0 : -range + k * spacing;
        angles[k] = angle;
        Pose6 candidate = estimate;
        if (angle != 0.0 && !rotateAboutGroundLine(estimate, angle, params.ground_z, &candidate)) {
          continue;
        }
        // The best member's cost is kept from the previous pass of the same kind (the first
        // pass scores the thinner target: its best member is refined again on the fine one).
        bool kept = angle == 0.0 && pass > 1;
        if (kept) costs[k] = kept_cost;
        for (const SweepMember& m : profile) {  // a walking pass meets members already refined
          if (pass > 0 && !kept && std::abs(m.angle - (base + angle)) < 1e-9 &&
              refinedAlike(m, {base + angle, 0.0, candidate}, params.ground_z,
                           params.plane_sweep_consistency)) {
            costs[k] = m.cost;
            members[k] = m.pose;
            kept = true;
          }
        }
        if (!kept) costs[k] = member(candidate, pass > 0, &members[k]);
        if (std::isfinite(costs[k])) out.plane_sweep.emplace_back(angle, costs[k]);
        if (pass > 0 && !kept && std::isfinite(costs[k])) {
          // A member refined again replaces its stale profile entry.
          const double at = base + angle;
          profile.erase(std::remove_if(profile.begin(), profile.end(),
                                       [at](const SweepMember& m) { return std::abs(m.angle - at) < 1e-9; }),
                        profile.end());
          profile.push_back({at, costs[k], members[k]});
        }
        if (std::isfinite(costs[k]) && (best_k < 0 || costs[k] < costs[best_k])) best_k = k;
      }
      if (best_k < 0 || cancelled) break;
      estimate = members[best_k];
      kept_cost = costs[best_k];
      if (pass > 0) base += angles[best_k];
      // A later pass whose best member is at its edge has not bracketed the minimum (the first
      // pass chose its bin from members not yet converged): it walks on at the same spacing,
      // at most plane_sweep_walks times, instead of halving it.
      if (pass > 0 && (best_k == 0 || best_k + 1 == steps) && walks < params.plane_sweep_walks) {
        ++walks;
        ++passes;
        continue;
      }
      range = 0.5 * spacing;
      steps = 3;
    }
    // The minimum of the least-squares parabola through all the fine profile's members refined
    // alike with the best one, not only the last pass's three (the members differ by a few 1e-5
    // of a cost of ~1e-3, about their own noise, and the last three alone put the minimum up to
    // 0.007 rad off). Three alike members still place it: without a parabola the best member
    // stands, which left seed 2's trial 1 0.0063 rad (6 cm in z) off, with it 0.0011 rad.
    double minimum = 0.0;
    std::size_t nearest = 0;
    if (!cancelled && sweepProfileMinimum(profile, {base, kept_cost, estimate}, params.ground_z,
                                          params.plane_sweep_consistency, &minimum, &nearest)) {
      const SweepMember& m = profile[nearest];
      Pose6 moved, refined;
      if (std::abs(minimum - m.angle) < 1e-6) {
        estimate = m.pose;
      } else if (rotateAboutGroundLine(m.pose, minimum - m.angle, params.ground_z, &moved) &&
                 std::isfinite(member(moved, true, &refined))) {
        estimate = refined;
      }
    }
    out.trace.push_back(estimate);
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
    out.trace.insert(out.trace.end(), out.refinement.trace.begin(), out.refinement.trace.end());
    out.evaluations += out.refinement.iterations;
    lin = out.refinement.at_solution;
    out.final_cost = lin.cost;
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
  Pose6 at = estimate;
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
