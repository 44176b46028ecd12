// The simulator's world (thesis 4.2.1, 5.2.1): a 2.5D height field of flat-topped square cell
// columns plus a per-cell class layer, the ground truth every simulated return carries.
// Frames: x east, y north, z up, metres; the world frame is odom.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ladar_perception/sim/trajectory.h"

namespace ladar_perception {
namespace sim {

// What a cell (or a simulated return) is. Ground classes are drivable surface; obstacle
// classes include the curb face and the pothole (a negative obstacle).
enum class SurfaceClass : uint8_t {
  kRoad = 0,
  kSidewalk = 1,
  kTerrain = 2,
  kCurb = 3,
  kCar = 4,
  kWall = 5,
  kPole = 6,    // poles and tree trunks
  kPerson = 7,
  kPothole = 8,
  kNone = 255,  // no hit
};
constexpr int kNumSurfaceClasses = 9;  // kRoad .. kPothole

bool isGroundClass(SurfaceClass c);    // road, sidewalk, terrain
bool isObstacleClass(SurfaceClass c);  // curb face, car, wall, pole, person, pothole
const char* className(SurfaceClass c); // "road", ..., "none"
// Parses a className() string; false for an unknown name.
bool classFromName(const std::string& name, SurfaceClass* c);
// Display colour of a class (top-down pictures and class images use the same palette).
void classColor(SurfaceClass c, uint8_t rgb[3]);

// How an image becomes a world (thesis 4.2.1: intensity is height, black = high).
struct ImageWorldOptions {
  double metres_per_pixel = 0.1;
  double height_scale = 2.0;     // height of a black pixel; white is 0 m
  // World coordinates of the image centre (the image's top row is north, largest y).
  double centre_x = 0.0;
  double centre_y = 0.0;
  // Without a class image: cells higher than this above the lowest cell are kWall (a generic
  // obstacle), the others kTerrain.
  double obstacle_height = 0.25;
};

// Parameters of the surface model that decide the class of a side-face hit.
struct SurfaceModel {
  // A ray hitting the vertical side of a step between two ground cells at least this high
  // reads as a curb face (kCurb); lower steps keep the cell's ground class, so slopes drawn
  // as fine flat-topped cells (0.1 m) do not read as curbs.
  float curb_min_step = 0.05f;
};

class World {
 public:
  World() = default;

  // A world of nx x ny cells of `resolution` metres whose lower-left corner is (origin_x,
  // origin_y), every cell at `fill_height` with class `fill_class`. Call finalize() after
  // editing cells.
  bool reset(double origin_x, double origin_y, double resolution, int nx, int ny,
             float fill_height, SurfaceClass fill_class, std::string* error);

  // Loads a height image (PGM or PNG, intensity -> height, black = high) and an optional class
  // image (same size; gray value = SurfaceClass code, or an RGB image in classColor()'s
  // palette). The result is finalized; its standard drive is empty.
  static bool fromImage(const std::string& height_image, const std::string& class_image,
                        const ImageWorldOptions& options, World* out, std::string* error);

  const std::string& name() const { return name_; }
  void setName(const std::string& name) { name_ = name; }

  // --- Geometry.
  double resolution() const { return resolution_; }
  double originX() const { return origin_x_; }
  double originY() const { return origin_y_; }
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }
  double maxX() const { return origin_x_ + nx_ * resolution_; }
  double maxY() const { return origin_y_ + ny_ * resolution_; }
  bool empty() const { return nx_ == 0 || ny_ == 0; }
  bool contains(double x, double y) const;
  // Cell of a point (may be outside 0..n-1 for points outside the world).
  int cellX(double x) const;
  int cellY(double y) const;
  bool validCell(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_; }

  // Surface height at a point: the top of the cell column under it; NaN outside the world.
  float height(double x, double y) const;
  // Class of the cell under a point; kNone outside.
  SurfaceClass surfaceClass(double x, double y) const;
  // Bilinear interpolation of cell-centre heights (a smooth ground for vehicle poses).
  float smoothHeight(double x, double y) const;

  float cellHeight(int ix, int iy) const { return heights_[index(ix, iy)]; }
  SurfaceClass cellClass(int ix, int iy) const {
    return static_cast<SurfaceClass>(classes_[index(ix, iy)]);
  }
  void setCell(int ix, int iy, float h, SurfaceClass c) {
    heights_[index(ix, iy)] = h;
    classes_[index(ix, iy)] = static_cast<uint8_t>(c);
  }
  std::size_t index(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * nx_ + ix;
  }
  const std::vector<float>& heights() const { return heights_; }
  const std::vector<uint8_t>& classes() const { return classes_; }

  // Rebuilds the max-height pyramid the ray caster uses to skip empty space. Call after
  // editing cells (generators and fromImage() do).
  void finalize();
  bool finalized() const { return !pyramid_.empty(); }
  // Pyramid level L >= 1 holds the maximum cell height of each 2^L x 2^L block.
  int pyramidLevels() const { return static_cast<int>(pyramid_.size()); }  // incl. level 0
  const float* levelData(int level) const {
    return level == 0 ? heights_.data() : pyramid_[level].data();
  }
  int levelWidth(int level) const { return level_w_[level]; }
  float maxHeight() const { return max_height_; }
  float minHeight() const { return min_height_; }

  const SurfaceModel& surfaceModel() const { return surface_model_; }
  void setSurfaceModel(const SurfaceModel& m) { surface_model_ = m; }

  // --- A standard drive through the world: poses of base_link (on the ground, z = ground
  // height, roll and pitch following the terrain) over time, t in [0, driveDuration()].
  const Trajectory& standardDrive() const { return drive_; }
  void setStandardDrive(const Trajectory& drive) { drive_ = drive; }
  double driveDuration() const { return drive_.duration(); }
  Eigen::Isometry3d drivePose(double t) const;

  // base_link standing at (x, y) with heading yaw: z is the ground height, roll and pitch
  // from the smoothed ground under the wheels (a 2.8 m x 1.6 m footprint).
  Eigen::Isometry3d vehiclePose(double x, double y, double yaw) const;

 private:
  std::string name_;
  double origin_x_ = 0.0, origin_y_ = 0.0, resolution_ = 0.1;
  int nx_ = 0, ny_ = 0;
  std::vector<float> heights_;
  std::vector<uint8_t> classes_;
  std::vector<std::vector<float>> pyramid_;  // [0] unused (level 0 is heights_)
  std::vector<int> level_w_;
  float max_height_ = 0.f, min_height_ = 0.f;
  SurfaceModel surface_model_;
  Trajectory drive_;
};

// Generated standard worlds, deterministic for a seed:
//  thesis   - the calibration test world of 5.2.1: mostly flat, car-sized obstacles
//  urban    - crowned road, 15 cm curbs, sidewalks, parked cars, a building wall, trees, lamp
//             posts, a person standing in the road 22 m ahead of the drive's start
//  rural    - a two-lane rural road on a 0.6 m embankment: 3 % crown, 6 % gravel shoulders, 1:4
//             side slopes into drainage ditches, undulating fields with fence lines, hay bales,
//             trees, a barn; cars on the shoulders and in the oncoming lane, a person on the
//             shoulder 25 m ahead and one in the field (the crowned road where one ground plane
//             fails, thesis 3.1, 3.2)
//  hillside - slopes up to 15 degrees with undulations, a parked car at the foot of the hill
//  potholes - a road with negative obstacles beside the driving line
//  alley    - two long featureless walls (degenerate for calibration along the alley)
//  flat     - flat road
bool makeStandardWorld(const std::string& name, uint32_t seed, World* out, std::string* error);
std::vector<std::string> standardWorldNames();

}  // namespace sim
}  // namespace ladar_perception
