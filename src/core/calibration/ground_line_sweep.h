// calibrate()'s ground-line sweep for a 2D ladar target and the search-region test it shares
// with calibrate() (private to the calibration core).
#pragma once

#include "ladar_perception/calibration/calibrator.h"

namespace ladar_perception {
namespace calibration {

// True when p lies within params.region spreads of the initial guess in every searched DOF.
bool insideRegion(const Pose6& p, const CalibrationParams& params);

// The ground-line ambiguity of a 2D ladar (scan_plane.h): from the coarse *estimate, the cost
// is profiled along the family of poses rotated about the scan plane's ground line, each member
// briefly refined with that rotation held; *estimate moves to the profile's minimum. The
// members go to out->plane_sweep, their refinements to out->evaluations and out->trace. The
// sweep's thinned targets are built once into *sweep_coarse_target and *sweep_fine_target.
void groundLineSweep(const CalibrationInput& input, const CalibrationParams& params,
                     const ProgressFn& progress, const SurfaceModel& model, const ScanSet& target,
                     ScanSet* sweep_coarse_target, ScanSet* sweep_fine_target, Pose6* estimate,
                     bool* cancelled, CalibrationResult* out);

// After the final refinement (which holds the sweep's rotation about the ground line): the
// rotation polished on the refinement's own target. Members at -2..+2 plane_sweep_polish_step
// about *estimate are each refined with that rotation held (final_rp on final_target, as the
// final refinement) and scored with the sweep's weighting on the whole target; the
// least-squares parabola through them places the minimum (walking on, at most
// plane_sweep_walks times, while it lies at an edge). *estimate and *refinement move to the
// member refined there when it scores lower than *estimate. The sweep placed the rotation on
// thinner targets from briefly refined members: up to 0.005 rad (5 cm in z at the ground line's
// 10 m) off a minimum that the whole target shows clearly. Returns the profile's rise two steps
// from its minimum (relative to the minimum's score; NaN when no profile was fitted).
double polishGroundLineRotation(const CalibrationParams& params, const ProgressFn& progress,
                              const SurfaceModel& model, const ScanSet& target,
                              const ScanSet& final_target, const RefinementParams& final_rp,
                              Pose6* estimate, RefinementResult* refinement, bool* cancelled,
                              CalibrationResult* out);

}  // namespace calibration
}  // namespace ladar_perception
