// The ambiguity of a 2D ladar's extrinsic over flat ground (beyond the thesis). A 2D ladar's scan
// plane meets a flat ground in a line; rotating the mount about that line keeps every ground
// return on the ground (for a SICK tilted down by pitch p at height h, the family h / sin(p) =
// const with x compensated), so ground returns alone cannot tell these mounts apart: only the
// returns on objects (their top edges, their faces seen from several places while driving) can.
// A local optimiser started anywhere on the family slides along it (to the degenerate member
// lying in the ground plane), so the calibrator searches the family explicitly.
#pragma once

#include <cstddef>
#include <vector>

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

// A member of the calibrator's sweep along that family: its rotation about the ground line (from
// a fixed member), its score and its pose refined with that rotation held.
struct SweepMember {
  double angle = 0.0;
  double cost = 0.0;
  Pose6 pose = Pose6::Zero();
};

// True when two members were refined alike, i.e. are comparable: their x and y agree within
// `tolerance` [m] once `a` is rotated to `b`'s angle. (A member refined before x and y converged
// scores several times higher than one refined after, whatever its rotation.)
bool refinedAlike(const SweepMember& a, const SweepMember& b, double ground_z, double tolerance);

// The rotation at the minimum of the least-squares parabola cost(angle) through the members
// refined alike with `best` (refinedAlike), clamped to their range; *nearest is the index of the
// member of those closest to it. False when fewer than three remain or the parabola has no
// minimum. *relative_curvature (optional): the parabola's curvature over its value at its
// minimum (the cost rises by that times angle^2, relatively, away from the minimum).
bool sweepProfileMinimum(const std::vector<SweepMember>& members, const SweepMember& best,
                         double ground_z, double tolerance, double* minimum, std::size_t* nearest,
                         double* relative_curvature = nullptr);

}  // namespace calibration
}  // namespace ladar_perception
