// The ambiguity of a 2D ladar's extrinsic over flat ground (beyond the thesis). A 2D ladar's scan
// plane meets a flat ground in a line; rotating the mount about that line keeps every ground
// return on the ground (for a SICK tilted down by pitch p at height h, the family h / sin(p) =
// const with x compensated), so ground returns alone cannot tell these mounts apart: only the
// returns on objects (their top edges, their faces seen from several places while driving) can.
// A local optimiser started anywhere on the family slides along it (to the degenerate member
// lying in the ground plane), so the calibrator searches the family explicitly.
#pragma once

#include "ladar_perception/calibration/pose.h"

namespace ladar_perception {
namespace calibration {

// The mount rotated by `angle` [rad] about the line where its scan plane (the sensor's x-y plane)
// meets the ground plane z = ground_z of base_link. False when the plane is (nearly) parallel to
// the ground or the line is more than max_distance metres away (no family to search).
bool rotateAboutGroundLine(const Pose6& extrinsic, double angle, double ground_z, Pose6* out,
                           double max_distance = 200.0);

// The rotation about that line as a step direction of the refinement's parametrisation
// (refinement.h: t += dt, R = Exp(dw) R): (d x (s - q), d) for the line through q along d.
bool groundLineStepDirection(const Pose6& extrinsic, double ground_z, Pose6* direction,
                             double max_distance = 200.0);

// The degenerate member of that family lies in the ground plane itself: every return, objects'
// included, lands on the ground, which fits any flat scene better than the truth. A real ladar
// does not measure the ground at grazing incidence, so a mount whose scan plane meets the ground
// (within max_range of the sensor) at less than min_incidence [rad] is physically impossible for
// a sensor that returned ground points. True when `extrinsic` is such a mount. A plane parallel
// to the ground above it (never meeting it within range) is fine.
bool grazesGround(const Pose6& extrinsic, double ground_z, double min_incidence, double max_range);

}  // namespace calibration
}  // namespace ladar_perception
