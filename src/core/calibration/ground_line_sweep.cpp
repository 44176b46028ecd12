// calibrate()'s ground-line sweep for a 2D ladar target (scan_plane.h; see ground_line_sweep.h).
#include "ground_line_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ladar_perception/calibration/scan_plane.h"

namespace ladar_perception {
namespace calibration {

void groundLineSweep(const CalibrationInput& input, const CalibrationParams& params,
                     const ProgressFn& progress, const SurfaceModel& model, const ScanSet& target,
                     ScanSet* sweep_coarse_target, ScanSet* sweep_fine_target, Pose6* estimate_io,
                     bool* cancelled_io, CalibrationResult* out_io) {
  Pose6& estimate = *estimate_io;
  bool& cancelled = *cancelled_io;
  CalibrationResult& out = *out_io;
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
  const ScanSet& coarse_target = thinned(params.plane_sweep_coarse_points, sweep_coarse_target);
  const ScanSet& fine_target = thinned(params.plane_sweep_fine_points, sweep_fine_target);
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

double polishGroundLineRotation(const CalibrationParams& params, const ProgressFn& progress,
                              const SurfaceModel& model, const ScanSet& target,
                              const ScanSet& final_target, const RefinementParams& final_rp,
                              Pose6* estimate_io, RefinementResult* refinement_io, bool* cancelled_io,
                              CalibrationResult* out_io) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  const double step = params.plane_sweep_polish_step;
  if (!(step > 0.0)) return none;
  bool& cancelled = *cancelled_io;
  CalibrationResult& out = *out_io;
  RefinementParams scored = final_rp;
  scored.range_noise = params.sparse_range_noise;
  scored.reference_noise = params.sparse_reference_noise;
  const double end = final_rp.max_correspondence_end;
  const auto score = [&](const Pose6& p) {
    return sparseTargetCost(linearise(model, target, p, end, scored), target.numPoints(), scored);
  };
  // A member: `from` rotated by `angle` about its ground line, refined with the rotation held.
  const auto member = [&](const Pose6& from, double angle, SweepMember* m, RefinementResult* r) {
    Pose6 start = from;
    if (angle != 0.0 && !rotateAboutGroundLine(from, angle, params.ground_z, &start)) return false;
    RefinementParams rp = final_rp;
    if (!groundLineStepDirection(start, params.ground_z, &rp.frozen_direction)) return false;
    *r = refine(model, final_target, start, rp, progress);
    cancelled = cancelled || r->cancelled;
    out.evaluations += r->iterations;
    if (!insideRegion(r->extrinsic, params)) return false;
    m->pose = r->extrinsic;
    m->cost = score(r->extrinsic);
    return std::isfinite(m->cost);
  };
  const double start_cost = score(*estimate_io);
  if (!std::isfinite(start_cost)) return none;
  std::vector<SweepMember> profile;
  std::vector<RefinementResult> refined;
  SweepMember centre{0.0, start_cost, *estimate_io};
  profile.push_back(centre);
  refined.push_back(*refinement_io);
  double minimum = 0.0, curvature = 0.0, rise = none;
  std::size_t nearest = 0;
  for (int walk = 0; walk <= params.plane_sweep_walks && !cancelled; ++walk) {
    for (int k = -2; k <= 2 && !cancelled; ++k) {
      const double angle = centre.angle + k * step;
      bool known = false;
      for (const SweepMember& m : profile) known = known || std::abs(m.angle - angle) < 1e-9;
      if (known) continue;
      SweepMember m;
      RefinementResult r;
      if (!member(centre.pose, angle - centre.angle, &m, &r)) continue;
      m.angle = angle;
      profile.push_back(m);
      refined.push_back(r);
    }
    if (cancelled ||
        !sweepProfileMinimum(profile, centre, params.ground_z, params.plane_sweep_consistency,
                             &minimum, &nearest, &curvature)) {
      return none;
    }
    // A profile that rises less than plane_sweep_polish_min_rise two steps from its minimum is
    // flat within the score's noise: its minimum says nothing, and the estimate stays.
    rise = curvature * 4.0 * step * step;
    if (rise < params.plane_sweep_polish_min_rise) return rise;
    // At the profile's edge the minimum is not bracketed: walk on from the edge member.
    double lo = profile[0].angle, hi = lo;
    for (const SweepMember& m : profile) {
      lo = std::min(lo, m.angle);
      hi = std::max(hi, m.angle);
    }
    if (minimum > lo + 1e-9 && minimum < hi - 1e-9) break;
    centre = profile[nearest];
  }
  if (cancelled) return rise;
  // The member at the minimum (refined from the nearest one), or the nearest itself.
  SweepMember best = profile[nearest];
  RefinementResult best_r = refined[nearest];
  if (std::abs(minimum - best.angle) > 1e-6) {
    SweepMember m;
    RefinementResult r;
    if (member(profile[nearest].pose, minimum - profile[nearest].angle, &m, &r) && m.cost < best.cost) {
      best = m;
      best_r = r;
    }
  }
  if (!(best.cost < start_cost)) return rise;
  *estimate_io = best.pose;
  *refinement_io = best_r;
  out.trace.push_back(best.pose);
  return rise;
}

}  // namespace calibration
}  // namespace ladar_perception
