#include "ladar_perception/sim/ray_caster.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ladar_perception {
namespace sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The ray in grid units: x-y in cells (u, v), z in metres, parameter t in metres of range.
struct GridRay {
  double ou, ov, oz;
  double du, dv, dz;
  double inv_du, inv_dv;
  int sx, sy;
};

// Clips [t0, t1] to the slab 0 <= o + d t <= n. False when empty.
inline bool clipSlab(double o, double d, double n, double* t0, double* t1) {
  if (d == 0.0) return o >= 0.0 && o < n;
  double a = (0.0 - o) / d, b = (n - o) / d;
  if (a > b) std::swap(a, b);
  *t0 = std::max(*t0, a);
  *t1 = std::min(*t1, b);
  return *t0 < *t1;
}

bool setup(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
           double max_range, GridRay* r, double* t_start, double* t_end) {
  if (world.empty() || !world.finalized() || !(max_range > 0.0) || !origin.allFinite() ||
      !direction.allFinite()) {
    return false;
  }
  const double inv_res = 1.0 / world.resolution();
  r->ou = (origin.x() - world.originX()) * inv_res;
  r->ov = (origin.y() - world.originY()) * inv_res;
  r->oz = origin.z();
  r->du = direction.x() * inv_res;
  r->dv = direction.y() * inv_res;
  r->dz = direction.z();
  // A zero component gets a huge positive inverse: its boundary (ahead, since s = +1) is then
  // never the nearest, and no inf * 0 can make a NaN.
  r->inv_du = r->du != 0.0 ? 1.0 / r->du : 1e300;
  r->inv_dv = r->dv != 0.0 ? 1.0 / r->dv : 1e300;
  r->sx = r->du >= 0.0 ? 1 : -1;
  r->sy = r->dv >= 0.0 ? 1 : -1;
  double t0 = 0.0, t1 = max_range;
  if (!clipSlab(r->ou, r->du, world.cellsX(), &t0, &t1)) return false;
  if (!clipSlab(r->ov, r->dv, world.cellsY(), &t0, &t1)) return false;
  // Above the highest cell and not descending: nothing to hit.
  if (r->dz >= 0.0 && r->oz + r->dz * t0 > world.maxHeight()) return false;
  *t_start = t0;
  *t_end = t1;
  return true;
}

inline int clampInt(int v, int lo, int hi) { return v < lo ? lo : (v > hi ? hi : v); }

// floor() to int without a libm call (baseline x86-64 has no rounding instruction); callers
// clamp the result to the grid, and coordinates stay far inside int's range.
inline int floorInt(double x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<double>(i) ? 1 : 0);
}

// Class of a vertical face of cell (i, j) entered from the neighbour (pi, pj).
inline SurfaceClass sideFaceClass(const World& world, int i, int j, int pi, int pj) {
  const SurfaceClass c = world.cellClass(i, j);
  if (!world.validCell(pi, pj)) return c;
  const SurfaceClass p = world.cellClass(pi, pj);
  if (p == SurfaceClass::kPothole) return SurfaceClass::kPothole;  // the wall of a pothole
  if (isGroundClass(c) &&
      world.cellHeight(i, j) - world.cellHeight(pi, pj) >= world.surfaceModel().curb_min_step) {
    return SurfaceClass::kCurb;
  }
  return c;
}

// The hit at a level-0 cell (i, j) whose segment [t, t_exit] reaches at or below its top.
// step_axis: how the ray entered the cell (0: x step, 1: y step, -1: start or grid entry).
inline void resolveCellHit(const World& world, const GridRay& r, int i, int j, float h, double t,
                           int step_axis, RayHit* hit) {
  const double z0 = r.oz + r.dz * t;
  if (z0 <= h) {
    // Entered through a side face.
    hit->range = t;
    if (step_axis == 0) {
      hit->normal = Eigen::Vector3f(static_cast<float>(-r.sx), 0.f, 0.f);
      hit->surface = sideFaceClass(world, i, j, i - r.sx, j);
    } else if (step_axis == 1) {
      hit->normal = Eigen::Vector3f(0.f, static_cast<float>(-r.sy), 0.f);
      hit->surface = sideFaceClass(world, i, j, i, j - r.sy);
    } else {
      hit->normal = Eigen::Vector3f::UnitZ();
      hit->surface = world.cellClass(i, j);
    }
  } else {
    hit->range = (h - r.oz) / r.dz;  // dz < 0 here: the ray descends through the top
    hit->normal = Eigen::Vector3f::UnitZ();
    hit->surface = world.cellClass(i, j);
  }
}

}  // namespace

bool castRay(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
             double max_range, RayHit* hit) {
  return castRay(world, origin, direction, max_range, -1, hit);
}

int startLevelFor(const World& world, const Eigen::Vector3d& origin) {
  if (!world.finalized()) return -1;
  const int ix = world.cellX(origin.x()), iy = world.cellY(origin.y());
  if (!world.validCell(ix, iy)) return -1;
  int best = -1;
  for (int l = 0; l < world.pyramidLevels(); ++l) {
    const float h = world.levelData(l)[static_cast<std::size_t>(iy >> l) * world.levelWidth(l) + (ix >> l)];
    if (h < origin.z()) best = l; else break;
  }
  return best;
}

bool castRay(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
             double max_range, int start_level, RayHit* hit) {
  GridRay r;
  double t, t_end;
  if (!setup(world, origin, direction, max_range, &r, &t, &t_end)) return false;
  const int nx = world.cellsX(), ny = world.cellsY();
  int i = clampInt(floorInt((r.ou + r.du * t)), 0, nx - 1);
  int j = clampInt(floorInt((r.ov + r.dv * t)), 0, ny - 1);
  // A ray starting inside a column sees nothing; one entering the grid from outside below a
  // cell's top hits that cell's outer face.
  const float* h0 = world.levelData(0);
  if (r.oz + r.dz * t <= h0[static_cast<std::size_t>(j) * nx + i]) {
    if (t <= 0.0) return false;
    hit->range = t;
    hit->surface = world.cellClass(i, j);
    hit->normal = Eigen::Vector3f::UnitZ();
    return true;
  }
  constexpr int kMaxLevels = 16;
  const int top = std::min(world.pyramidLevels(), kMaxLevels) - 1;
  const float* level_data[kMaxLevels];
  std::size_t level_width[kMaxLevels];
  for (int l = 0; l <= top; ++l) {
    level_data[l] = world.levelData(l);
    level_width[l] = static_cast<std::size_t>(world.levelWidth(l));
  }
  // The boundary ahead of block b along an axis is (b + e) << level.
  const int ex = r.sx > 0 ? 1 : 0, ey = r.sy > 0 ? 1 : 0;
  int level = start_level >= 0 && start_level < top ? start_level : top;
  int step_axis = -1;
  for (;;) {
    const int bi = i >> level, bj = j >> level;
    const float h = level_data[level][static_cast<std::size_t>(bj) * level_width[level] + bi];
    // Where the ray leaves this block (x and y boundaries of the 2^level block).
    const double tx = (static_cast<double>((bi + ex) << level) - r.ou) * r.inv_du;
    const double ty = (static_cast<double>((bj + ey) << level) - r.ov) * r.inv_dv;
    double t_exit = std::max(std::min(tx, ty), t);
    const bool last = t_exit >= t_end;
    if (last) t_exit = t_end;
    const double z0 = r.oz + r.dz * t, z1 = r.oz + r.dz * t_exit;
    if (std::min(z0, z1) > h) {
      // The ray passes above the whole block: skip it.
      if (last) return false;
      t = t_exit;
      if (tx <= ty) {
        i = r.sx > 0 ? (bi + 1) << level : (bi << level) - 1;
        const int lo = bj << level, hi = std::min(((bj + 1) << level) - 1, ny - 1);
        j = clampInt(floorInt((r.ov + r.dv * t)), lo, hi);
        step_axis = 0;
      } else {
        j = r.sy > 0 ? (bj + 1) << level : (bj << level) - 1;
        const int lo = bi << level, hi = std::min(((bi + 1) << level) - 1, nx - 1);
        i = clampInt(floorInt((r.ou + r.du * t)), lo, hi);
        step_axis = 1;
      }
      if (i < 0 || j < 0 || i >= nx || j >= ny) return false;
      // Go up while the step also left the parent block: within the same parent, whose
      // segment did not clear it, going up would only come straight back down.
      const int oi = bi << level, oj = bj << level;
      while (level < top && ((i >> (level + 1)) != (oi >> (level + 1)) ||
                             (j >> (level + 1)) != (oj >> (level + 1)))) {
        ++level;
      }
      continue;
    }
    if (level > 0) {
      --level;
      continue;
    }
    resolveCellHit(world, r, i, j, h, t, step_axis, hit);
    return true;
  }
}

bool castRayBruteForce(const World& world, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double max_range, RayHit* hit) {
  GridRay r;
  double t, t_end;
  if (!setup(world, origin, direction, max_range, &r, &t, &t_end)) return false;
  const int nx = world.cellsX(), ny = world.cellsY();
  int i = clampInt(floorInt((r.ou + r.du * t)), 0, nx - 1);
  int j = clampInt(floorInt((r.ov + r.dv * t)), 0, ny - 1);
  if (r.oz + r.dz * t <= world.cellHeight(i, j)) {
    if (t <= 0.0) return false;
    hit->range = t;
    hit->surface = world.cellClass(i, j);
    hit->normal = Eigen::Vector3f::UnitZ();
    return true;
  }
  int step_axis = -1;
  for (;;) {
    const double tx = (i + (r.sx > 0 ? 1 : 0) - r.ou) * r.inv_du;
    const double ty = (j + (r.sy > 0 ? 1 : 0) - r.ov) * r.inv_dv;
    double t_exit = std::max(std::min(tx, ty), t);
    const bool last = t_exit >= t_end;
    if (last) t_exit = t_end;
    const float h = world.cellHeight(i, j);
    if (std::min(r.oz + r.dz * t, r.oz + r.dz * t_exit) <= h) {
      resolveCellHit(world, r, i, j, h, t, step_axis, hit);
      return true;
    }
    if (last) return false;
    t = t_exit;
    if (tx <= ty) { i += r.sx; step_axis = 0; } else { j += r.sy; step_axis = 1; }
    if (i < 0 || j < 0 || i >= nx || j >= ny) return false;
  }
}

}  // namespace sim
}  // namespace ladar_perception
