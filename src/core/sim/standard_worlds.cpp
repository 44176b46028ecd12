// The generated standard worlds (makeStandardWorld). All at 0.1 m cells, so slopes of up to
// 15 degrees step at most 2.7 cm between cells and never read as curbs (SurfaceModel).
#include <algorithm>
#include <cmath>
#include <functional>

#include "ladar_perception/sim/random.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

namespace {

constexpr double kCell = 0.1;
constexpr double kTwoPi = 6.283185307179586;

double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Helpers that draw into a World. Shapes are rasterised by cell centre.
class Painter {
 public:
  explicit Painter(World* w) : w_(w) {}

  // Sets every cell from a function of the cell centre.
  void ground(const std::function<void(double x, double y, float* h, SurfaceClass* c)>& f) {
    for (int iy = 0; iy < w_->cellsY(); ++iy) {
      const double y = centreY(iy);
      for (int ix = 0; ix < w_->cellsX(); ++ix) {
        float h = 0.f;
        SurfaceClass c = SurfaceClass::kTerrain;
        f(centreX(ix), y, &h, &c);
        w_->setCell(ix, iy, h, c);
      }
    }
  }

  // A box of length x width (along its yaw) whose top is base + profile(a, b), with (a, b) the
  // cell centre in the box frame.
  void box(double cx, double cy, double yaw, double length, double width,
           const std::function<double(double a, double b)>& profile, float base, SurfaceClass c) {
    const double ca = std::cos(yaw), sa = std::sin(yaw);
    const double ext = 0.5 * (std::abs(length * ca) + std::abs(width * sa)) + kCell;
    const double eyt = 0.5 * (std::abs(length * sa) + std::abs(width * ca)) + kCell;
    forCells(cx - ext, cy - eyt, cx + ext, cy + eyt, [&](int ix, int iy, double x, double y) {
      const double dx = x - cx, dy = y - cy;
      const double a = dx * ca + dy * sa, b = -dx * sa + dy * ca;
      if (std::abs(a) <= 0.5 * length && std::abs(b) <= 0.5 * width) {
        w_->setCell(ix, iy, static_cast<float>(base + profile(a, b)), c);
      }
    });
  }

  // An axis-aligned ellipse with semi-axes rx, ry; top = f(rho) with rho in [0, 1] the
  // normalised radius.
  void ellipse(double cx, double cy, double rx, double ry,
               const std::function<double(double rho)>& top, SurfaceClass c) {
    forCells(cx - rx - kCell, cy - ry - kCell, cx + rx + kCell, cy + ry + kCell,
             [&](int ix, int iy, double x, double y) {
               const double u = (x - cx) / rx, v = (y - cy) / ry;
               const double rho2 = u * u + v * v;
               if (rho2 <= 1.0) w_->setCell(ix, iy, static_cast<float>(top(std::sqrt(rho2))), c);
             });
  }

  // A cylinder (pole, tree trunk) standing on the ground under its centre.
  void pole(double cx, double cy, double radius, double height, SurfaceClass c = SurfaceClass::kPole) {
    const float base = w_->height(cx, cy);
    ellipse(cx, cy, radius, radius, [&](double) { return base + height; }, c);
  }

  // A parked car (or car-sized block) with hood and trunk lower than the cabin.
  void car(double cx, double cy, double yaw, double length, double width, double cabin_height) {
    const float base = w_->height(cx, cy);
    const double hood = 0.62 * cabin_height;
    box(cx, cy, yaw, length, width,
        [&](double a, double b) {
          double top = std::abs(a) > 0.5 * length - 1.1 ? hood : cabin_height;
          if (std::abs(b) > 0.5 * width - 0.15) top -= 0.12;  // rounded sides
          return top;
        },
        base, SurfaceClass::kCar);
  }

  double centreX(int ix) const { return w_->originX() + (ix + 0.5) * w_->resolution(); }
  double centreY(int iy) const { return w_->originY() + (iy + 0.5) * w_->resolution(); }

 private:
  template <typename F>
  void forCells(double x0, double y0, double x1, double y1, F f) {
    const int i0 = std::max(0, w_->cellX(x0)), i1 = std::min(w_->cellsX() - 1, w_->cellX(x1));
    const int j0 = std::max(0, w_->cellY(y0)), j1 = std::min(w_->cellsY() - 1, w_->cellY(y1));
    for (int iy = j0; iy <= j1; ++iy) {
      for (int ix = i0; ix <= i1; ++ix) f(ix, iy, centreX(ix), centreY(iy));
    }
  }
  World* w_;
};

// Keeps random objects apart (circles).
class Placement {
 public:
  bool free(double x, double y, double r) const {
    for (const Eigen::Vector3d& c : taken_) {
      if (std::hypot(x - c.x(), y - c.y()) < r + c.z()) return false;
    }
    return true;
  }
  void take(double x, double y, double r) { taken_.emplace_back(x, y, r); }

 private:
  std::vector<Eigen::Vector3d> taken_;
};

bool setDrive(World* w, const std::vector<Eigen::Vector2d>& points, double speed, std::string* error) {
  Trajectory t;
  if (!Trajectory::fromWaypoints(points, speed, &t, error)) return false;
  w->setStandardDrive(t);
  return true;
}

// --- thesis: the calibration test world of 5.2.1 (an image with black = 2 m): flat ground
// with car-sized blocks, a few walls and poles; the 10 m around the origin (where the random
// vehicle poses are drawn) and a drive corridor along y = 0 are kept clear.
bool makeThesis(uint32_t seed, World* w, std::string* error) {
  if (!w->reset(-80, -80, kCell, 1600, 1600, 0.f, SurfaceClass::kTerrain, error)) return false;
  Rng rng(seed);
  Painter paint(w);
  const double p1 = rng.uniform(0, kTwoPi), p2 = rng.uniform(0, kTwoPi);
  paint.ground([&](double x, double y, float* h, SurfaceClass* c) {
    *h = static_cast<float>(0.03 * std::sin(kTwoPi * x / 23.0 + p1) * std::sin(kTwoPi * y / 31.0 + p2));
    *c = SurfaceClass::kTerrain;
  });
  Placement taken;
  taken.take(0, 0, 9.0);
  auto inCorridor = [](double x, double y, double r) { return std::abs(y) < 3.5 + r && std::abs(x) < 45; };
  int placed = 0;
  for (int attempt = 0; attempt < 2000 && placed < 45; ++attempt) {
    const double range = rng.uniform(9.0, 62.0), bearing = rng.uniform(-M_PI, M_PI);
    const double x = range * std::cos(bearing), y = range * std::sin(bearing);
    const double yaw = rng.uniform(-M_PI, M_PI);
    const double length = rng.uniform(3.8, 5.0), width = rng.uniform(1.7, 2.1);
    const double cabin = rng.uniform(1.4, 2.0);
    const double r = 0.5 * std::hypot(length, width) + 0.8;
    if (inCorridor(x, y, r) || !taken.free(x, y, r)) continue;
    paint.car(x, y, yaw, length, width, cabin);
    taken.take(x, y, r);
    ++placed;
  }
  for (int k = 0, attempt = 0; k < 6 && attempt < 500; ++attempt) {
    const double range = rng.uniform(15.0, 60.0), bearing = rng.uniform(-M_PI, M_PI);
    const double x = range * std::cos(bearing), y = range * std::sin(bearing);
    const double length = rng.uniform(8.0, 18.0), yaw = rng.uniform(-M_PI, M_PI);
    const double r = 0.5 * length + 1.0;
    if (inCorridor(x, y, r) || !taken.free(x, y, r)) continue;
    paint.box(x, y, yaw, length, 0.4, [](double, double) { return 2.0; }, w->height(x, y),
              SurfaceClass::kWall);
    taken.take(x, y, r);
    ++k;
  }
  for (int k = 0, attempt = 0; k < 12 && attempt < 500; ++attempt) {
    const double range = rng.uniform(10.0, 60.0), bearing = rng.uniform(-M_PI, M_PI);
    const double x = range * std::cos(bearing), y = range * std::sin(bearing);
    if (inCorridor(x, y, 1.0) || !taken.free(x, y, 1.0)) continue;
    paint.pole(x, y, rng.uniform(0.12, 0.3), rng.uniform(2.0, 4.0));
    taken.take(x, y, 1.0);
    ++k;
  }
  return setDrive(w, {{-30, 0}, {30, 0}}, 3.0, error);
}

// --- urban: an east-west street. Road |y| <= 5 crowned 10 cm (2 % cross slope), 15 cm curbs,
// 3 m sidewalks rising 2 cm away from the road, buildings north, a grass verge with trees south,
// cars parked in both parking lanes (|y| ~ 4), lamp posts, and a person standing in the
// oncoming lane 22 m from the drive's start. The drive runs along the eastbound lane, y = -1.5.
bool makeUrban(uint32_t seed, World* w, std::string* error) {
  if (!w->reset(-70, -40, kCell, 2400, 800, 0.f, SurfaceClass::kRoad, error)) return false;
  Rng rng(seed);
  Painter paint(w);
  const double g1 = rng.uniform(0, kTwoPi), g2 = rng.uniform(0, kTwoPi);
  paint.ground([&](double x, double y, float* h, SurfaceClass* c) {
    const double ay = std::abs(y);
    if (ay <= 5.0) {
      *h = static_cast<float>(0.10 * (1.0 - (y / 5.0) * (y / 5.0)));  // crown
      *c = SurfaceClass::kRoad;
    } else if (ay <= 8.0) {
      *h = static_cast<float>(0.15 + 0.02 * (ay - 5.0) / 3.0);  // curb 15 cm above the gutter
      *c = SurfaceClass::kSidewalk;
    } else {
      *h = static_cast<float>(0.17 + 0.04 * std::sin(kTwoPi * x / 9.0 + g1) *
                                         std::sin(kTwoPi * y / 7.0 + g2) * smoothstep(ay - 8.0));
      *c = SurfaceClass::kTerrain;
    }
  });
  // Buildings north of the sidewalk, separated by driveways.
  for (double x = -68.0; x < 168.0;) {
    const double length = rng.uniform(18.0, 40.0);
    const double height = rng.uniform(6.0, 12.0);
    const double x1 = std::min(x + length, 168.0);
    paint.box(0.5 * (x + x1), 24.25, 0.0, x1 - x, 31.5, [&](double, double) { return height; }, 0.f,
              SurfaceClass::kWall);
    x = x1 + rng.uniform(4.0, 8.0);
  }
  // Trees on the grass verge and lamp posts on the north sidewalk.
  Placement taken;
  for (int k = 0, attempt = 0; k < 45 && attempt < 2000; ++attempt) {
    const double x = rng.uniform(-68.0, 168.0), y = rng.uniform(-30.0, -9.5);
    if (!taken.free(x, y, 2.5)) continue;
    paint.pole(x, y, rng.uniform(0.12, 0.3), rng.uniform(3.0, 6.0));
    taken.take(x, y, 2.5);
    ++k;
  }
  for (double x = -60.0; x < 165.0; x += 25.0) paint.pole(x, 7.5, 0.1, 5.0);
  // The person: 22 m from the start of the drive (0, -1.5), standing in the oncoming lane.
  const double person_y = 1.5, person_x = std::sqrt(22.0 * 22.0 - 3.0 * 3.0);
  // Parked cars along both curbs, leaving the person's surroundings clear.
  for (int side = -1; side <= 1; side += 2) {
    for (double x = -68.0 + rng.uniform(0.0, 6.0); x < 165.0;) {
      const double length = rng.uniform(4.0, 4.9);
      const double cx = x + 0.5 * length;
      if (rng.uniform() < 0.75 && std::abs(cx - person_x) > 6.0) {
        paint.car(cx, side * 4.0, side > 0 ? M_PI : 0.0, length, rng.uniform(1.7, 1.9),
                  rng.uniform(1.4, 1.6));
      }
      x += length + rng.uniform(1.5, 8.0);
    }
  }
  const float ground = w->height(person_x, person_y);
  paint.ellipse(person_x, person_y, 0.16, 0.26,
                [&](double rho) { return ground + (rho < 0.6 ? 1.75 : 1.45); }, SurfaceClass::kPerson);
  return setDrive(w, {{0, -1.5}, {100, -1.5}}, 5.0, error);
}

// --- hillside: flat valley floor for x < 0, then a hill whose slope rises smoothly to about
// 10 degrees and flattens again near x = 90; undulations on top bring local slopes to at most
// 15 degrees. A car is parked at the foot of the hill, trees stand on the slope.
bool makeHillside(uint32_t seed, World* w, std::string* error) {
  const double x0 = -70.0;
  const int nx = 2000, ny = 1200;
  if (!w->reset(x0, -60, kCell, nx, ny, 0.f, SurfaceClass::kTerrain, error)) return false;
  Rng rng(seed);
  Painter paint(w);
  // The hill profile by integrating its slope along x (cell centres).
  std::vector<double> hill(nx);
  double h = 0.0;
  const int sub = 10;
  for (int ix = 0; ix < nx; ++ix) {
    const double xc = x0 + (ix + 0.5) * kCell;
    for (int s = 0; s < sub; ++s) {
      const double x = xc - kCell + (s + 0.5) * kCell / sub;  // integrate over the previous cell
      const double slope = 0.18 * smoothstep(x / 20.0) * (1.0 - smoothstep((x - 70.0) / 20.0));
      h += slope * kCell / sub;
    }
    hill[ix] = h;
  }
  const double p1 = rng.uniform(0, kTwoPi), p2 = rng.uniform(0, kTwoPi), p3 = rng.uniform(0, kTwoPi);
  int ix = 0;
  paint.ground([&](double x, double y, float* out, SurfaceClass* c) {
    ix = std::clamp(static_cast<int>((x - x0) / kCell), 0, nx - 1);
    const double und = 0.10 * std::sin(kTwoPi * x / 13.0 + p1) * std::sin(kTwoPi * y / 11.0 + p2) +
                       0.03 * std::sin(kTwoPi * (x + y) / 6.5 + p3);
    *out = static_cast<float>(hill[ix] + und);
    *c = SurfaceClass::kTerrain;
  });
  paint.car(-2.0, 5.0, 0.4, 4.5, 1.8, 1.5);  // the obstacle at the foot of the hill
  Placement taken;
  taken.take(-2.0, 5.0, 4.0);
  for (int k = 0, attempt = 0; k < 30 && attempt < 2000; ++attempt) {
    const double x = rng.uniform(-60.0, 120.0), y = rng.uniform(-55.0, 55.0);
    if (std::abs(y) < 5.0 || !taken.free(x, y, 3.0)) continue;
    paint.pole(x, y, rng.uniform(0.12, 0.3), rng.uniform(3.0, 6.0));
    taken.take(x, y, 3.0);
    ++k;
  }
  return setDrive(w, {{-40, 0}, {90, 0}}, 4.0, error);
}

// --- potholes: a 12 m wide road flush with the terrain beside it; potholes (bowls 8-25 cm
// deep) beside the driving line y = 0 and a group straight ahead beyond the end of the drive.
bool makePotholes(uint32_t seed, World* w, std::string* error) {
  if (!w->reset(-70, -40, kCell, 2400, 800, 0.f, SurfaceClass::kRoad, error)) return false;
  Rng rng(seed);
  Painter paint(w);
  const double g1 = rng.uniform(0, kTwoPi), g2 = rng.uniform(0, kTwoPi);
  paint.ground([&](double x, double y, float* h, SurfaceClass* c) {
    if (std::abs(y) <= 6.0) {
      *h = 0.f;
      *c = SurfaceClass::kRoad;
    } else {
      *h = static_cast<float>(0.02 * std::sin(kTwoPi * x / 8.0 + g1) * std::sin(kTwoPi * y / 6.0 + g2) *
                              smoothstep(std::abs(y) - 6.0));
      *c = SurfaceClass::kTerrain;
    }
  });
  Placement taken;
  auto pothole = [&](double x, double y, double rx, double ry, double depth) {
    paint.ellipse(x, y, rx, ry, [&](double rho) { return -depth * std::sqrt(std::max(0.0, 1.0 - rho * rho)) - 0.03; },
                  SurfaceClass::kPothole);
    taken.take(x, y, std::max(rx, ry) + 0.5);
  };
  for (int k = 0, attempt = 0; k < 30 && attempt < 3000; ++attempt) {
    const double x = rng.uniform(3.0, 125.0);
    const double rx = rng.uniform(0.2, 0.7), ry = rng.uniform(0.2, 0.7);
    const double side = rng.uniform() < 0.5 ? -1.0 : 1.0;
    const double y = side * rng.uniform(1.4 + ry, 5.5);
    if (!taken.free(x, y, std::max(rx, ry) + 0.5)) continue;
    pothole(x, y, rx, ry, rng.uniform(0.08, 0.25));
    ++k;
  }
  // Straight ahead, past the end of the drive (x = 120).
  pothole(132.0, 0.3, 0.6, 0.9, 0.2);
  pothole(141.0, -0.8, 1.2, 0.8, 0.25);
  pothole(150.0, 0.5, 0.4, 0.4, 0.15);
  return setDrive(w, {{0, 0}, {120, 0}}, 5.0, error);
}

// --- rural: a two-lane rural road on a low embankment through farmland, the crowned road of the
// thesis (3.1, 3.2) in a cross-section built like a real one (AASHTO-style rural two-lane road):
//  - 3.5 m lanes |y| <= 3.5 with a steep 3 % crown (the upper end for paved rural roads), the
//    crown 0.6 m above the nominal field level;
//  - 2 m gravel shoulders 3.5 < |y| <= 5.5 falling at 6 %;
//  - 1:4 foreslopes down to drainage ditches 0.5 m below the field level (flat bottoms, 1 m
//    wide, at 9.0 <= |y| <= 10.0), 1:4 backslopes up to the fields at |y| = 12;
//  - fields beyond, gently undulating (+-0.2 m over tens of metres), with a fence line (posts
//    every 4 m at |y| = 12.85), trees, round hay bales, a barn and a farm hand standing in the
//    north field;
//  - on the road: cars parked on the shoulders, a car stopped in the westbound lane, a person
//    walking on the north shoulder, mailboxes on the shoulder edges.
// Everything beside the road lies 0.6-1.1 m below the road surface, so no single plane (or
// first harmonic per laser) describes the ground the sensor sees; every slope stays within
// 15 degrees. The drive runs along the eastbound lane, y = -1.75.
bool makeRural(uint32_t seed, World* w, std::string* error) {
  if (!w->reset(-70, -60, kCell, 2400, 1200, 0.f, SurfaceClass::kTerrain, error)) return false;
  Rng rng(seed);
  Painter paint(w);
  constexpr double kCrown = 0.03, kShoulder = 0.06, kSide = 0.25;  // cross slopes
  constexpr double kEmbankment = 0.6, kDitch = -0.5;               // crown, ditch bottom
  const double p1 = rng.uniform(0, kTwoPi), p2 = rng.uniform(0, kTwoPi), p3 = rng.uniform(0, kTwoPi);
  paint.ground([&](double x, double y, float* h, SurfaceClass* c) {
    const double ay = std::abs(y);
    const double edge = kEmbankment - kCrown * 3.5 - kShoulder * 2.0;  // shoulder edge
    const double ditch0 = 5.5 + (edge - kDitch) / kSide;               // foot of the foreslope
    const double ditch1 = ditch0 + 1.0;
    const double field = ditch1 + (0.0 - kDitch) / kSide;              // top of the backslope
    double z;
    if (ay <= 3.5) {
      z = kEmbankment - kCrown * ay;
      *c = SurfaceClass::kRoad;
    } else {
      *c = SurfaceClass::kTerrain;
      if (ay <= 5.5) z = kEmbankment - kCrown * 3.5 - kShoulder * (ay - 3.5);
      else if (ay <= ditch0) z = edge - kSide * (ay - 5.5);
      else if (ay <= ditch1) z = kDitch;
      else if (ay <= field) z = kDitch + kSide * (ay - ditch1);
      else {
        const double und = 0.15 * std::sin(kTwoPi * x / 37.0 + p1) * std::sin(kTwoPi * y / 29.0 + p2) +
                           0.05 * std::sin(kTwoPi * (x - y) / 13.0 + p3);
        z = und * smoothstep((ay - field) / 6.0);
      }
    }
    *h = static_cast<float>(z);
  });
  Placement taken;
  // Road users first: the person walking on the north shoulder 25 m ahead of the drive's start
  // (0, -1.75), a car stopped in the westbound lane 55 m ahead, cars parked on the shoulders.
  const double person_x = std::sqrt(25.0 * 25.0 - 6.25 * 6.25), person_y = 4.5;
  {
    const float ground = w->height(person_x, person_y);
    paint.ellipse(person_x, person_y, 0.16, 0.26,
                  [&](double rho) { return ground + (rho < 0.6 ? 1.75 : 1.45); }, SurfaceClass::kPerson);
    taken.take(person_x, person_y, 5.0);
  }
  paint.car(55.0, 1.75, M_PI, 4.6, 1.8, 1.5);
  taken.take(55.0, 1.75, 4.0);
  for (int k = 0, attempt = 0; k < 6 && attempt < 500; ++attempt) {
    const double x = rng.uniform(-60.0, 160.0), side = rng.uniform() < 0.5 ? -1.0 : 1.0;
    if (!taken.free(x, side * 4.6, 3.5)) continue;
    paint.car(x, side * 4.6, side > 0 ? M_PI : 0.0, rng.uniform(4.2, 5.2), rng.uniform(1.7, 1.9),
              rng.uniform(1.4, 1.9));
    taken.take(x, side * 4.6, 3.5);
    ++k;
  }
  // Mailboxes on the shoulder edges (a post with the box on top, 1.1 m).
  for (int k = 0, attempt = 0; k < 8 && attempt < 500; ++attempt) {
    const double x = rng.uniform(-65.0, 165.0), y = (rng.uniform() < 0.5 ? -1.0 : 1.0) * 5.3;
    if (!taken.free(x, y, 1.5)) continue;
    paint.pole(x, y, 0.12, 1.1);
    taken.take(x, y, 1.5);
    ++k;
  }
  // Fence lines along both fields: 1.2 m posts (12 cm) every 4 m, on cell centres so that each
  // post covers at least one cell.
  for (int side = -1; side <= 1; side += 2) {
    const double x0 = -67.95 + 0.1 * rng.uniformInt(0, 39);
    for (int k = 0; x0 + 4.0 * k < 168.0; ++k) paint.pole(x0 + 4.0 * k, side * 12.85, 0.06, 1.2);
  }
  // A barn and a farm hand in the north field, hay bales and trees in both.
  const double barn_x = rng.uniform(20.0, 80.0);
  paint.box(barn_x, 38.0, 0.0, 20.0, 12.0, [](double, double) { return 6.0; }, w->height(barn_x, 38.0),
            SurfaceClass::kWall);
  taken.take(barn_x, 38.0, 13.0);
  for (int attempt = 0; attempt < 500; ++attempt) {
    const double x = rng.uniform(25.0, 45.0), y = rng.uniform(16.0, 22.0);
    if (!taken.free(x, y, 1.0)) continue;
    const float ground = w->height(x, y);
    paint.ellipse(x, y, 0.16, 0.26, [&](double rho) { return ground + (rho < 0.6 ? 1.75 : 1.45); },
                  SurfaceClass::kPerson);
    taken.take(x, y, 1.0);
    break;
  }
  for (int k = 0, attempt = 0; k < 24 && attempt < 2000; ++attempt) {
    const double x = rng.uniform(-65.0, 165.0), y = (rng.uniform() < 0.5 ? -1.0 : 1.0) * rng.uniform(15.0, 55.0);
    if (!taken.free(x, y, 2.5)) continue;
    const float ground = w->height(x, y);
    const double r = rng.uniform(0.7, 0.8), top = rng.uniform(1.2, 1.5);
    paint.ellipse(x, y, r, r, [&](double) { return ground + top; }, SurfaceClass::kWall);
    taken.take(x, y, 2.5);
    ++k;
  }
  for (int k = 0, attempt = 0; k < 30 && attempt < 2000; ++attempt) {
    const double x = rng.uniform(-65.0, 165.0), y = (rng.uniform() < 0.5 ? -1.0 : 1.0) * rng.uniform(14.0, 58.0);
    if (!taken.free(x, y, 3.0)) continue;
    paint.pole(x, y, rng.uniform(0.12, 0.3), rng.uniform(3.0, 6.0));
    taken.take(x, y, 3.0);
    ++k;
  }
  return setDrive(w, {{0, -1.75}, {100, -1.75}}, 5.0, error);
}

// --- alley: two 5 m walls 6 m apart, 220 m long, longer than the Velodyne sees, on flat
// ground: along the alley nothing constrains x.
bool makeAlley(uint32_t, World* w, std::string* error) {
  if (!w->reset(-70, -30, kCell, 2400, 600, 0.f, SurfaceClass::kRoad, error)) return false;
  Painter paint(w);
  for (int side = -1; side <= 1; side += 2) {
    paint.box(50.0, side * 3.2, 0.0, 220.0, 0.4, [](double, double) { return 5.0; }, 0.f,
              SurfaceClass::kWall);
  }
  return setDrive(w, {{0, 0}, {100, 0}}, 5.0, error);
}

bool makeFlat(uint32_t, World* w, std::string* error) {
  if (!w->reset(-80, -80, kCell, 2600, 1600, 0.f, SurfaceClass::kRoad, error)) return false;
  return setDrive(w, {{0, 0}, {100, 0}}, 5.0, error);
}

}  // namespace

std::vector<std::string> standardWorldNames() {
  return {"thesis", "urban", "rural", "hillside", "potholes", "alley", "flat"};
}

bool makeStandardWorld(const std::string& name, uint32_t seed, World* out, std::string* error) {
  bool ok = false;
  if (name == "thesis") ok = makeThesis(seed, out, error);
  else if (name == "urban") ok = makeUrban(seed, out, error);
  else if (name == "rural") ok = makeRural(seed, out, error);
  else if (name == "hillside") ok = makeHillside(seed, out, error);
  else if (name == "potholes") ok = makePotholes(seed, out, error);
  else if (name == "alley") ok = makeAlley(seed, out, error);
  else if (name == "flat") ok = makeFlat(seed, out, error);
  else {
    if (error) {
      *error = "unknown world '" + name + "' (standard worlds:";
      for (const std::string& n : standardWorldNames()) *error += " " + n;
      *error += ")";
    }
    return false;
  }
  if (!ok) return false;
  out->setName(name);
  out->finalize();
  return true;
}

}  // namespace sim
}  // namespace ladar_perception
