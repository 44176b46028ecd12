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

}  // namespace calibration
}  // namespace ladar_perception
