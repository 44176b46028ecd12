// Vertical scan ground extraction for a Velodyne-style 3D ladar (thesis 3.3).
// Every reconfigurable field of VerticalScanParams has one row in vertical_scan_params.def, from
// which --set, the ROS mapping and cfg/VerticalScanGround.cfg are produced: a new field gets its
// row there (the parameter-table test fails otherwise).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"
#include "ladar_perception/ground/ground_model.h"
#include "ladar_perception/ground/obstacle_probability.h"
#include "ladar_perception/ground/param_table.h"

namespace ladar_perception {

enum CurbPolicy : int { kCurbObstacle = 0, kCurbGround = 1 };

struct VerticalScanParams {
  // --- Binning (3.3 step 1): rows by laser, columns by azimuth, median range per bin.
  float column_width_deg = 1.5f;          // azimuth width of a vertical scan [deg]
  // Laser elevations used to assign a row when the cloud has no `ring` field [deg];
  // empty = the HDL-64E table (laser_elevations.h).
  std::vector<float> laser_elevations_deg;
  float min_range = 1.0f;                 // returns closer than this are unknown [m]
  float max_range = 120.0f;               // returns farther than this are unknown [m]

  // --- Feasibility (eq 3.4): GroundSlopeMin < Height / r < GroundSlopeMax.
  float ground_slope_min = -0.35f;
  float ground_slope_max = 0.35f;

  // --- Slope estimate (eqs 3.6-3.9).
  int iterations = 9;
  float weight_bias = 0.02f;              // WeightBias of eq 3.6: biases the fit downward

  // --- Obstacle probability (eq 3.15).
  ObstacleToleranceParams tolerances;

  // --- Beyond the thesis (5.1.2 future work). All off in the thesis mode.
  // Bent ground line: the column's ground is tracked outward through its representatives
  // (a return continues the ground when it lies within the tolerances of the line extrapolated
  // from the ground so far and the local slope to the last ground return is passable), so the
  // line bends where the terrain's slope changes and steps up a curb onto the sidewalk.
  bool bend_ground_line = true;
  float segment_length = 0.75f;           // knot spacing of the piecewise ground line [m]
  float track_max_step = 0.12f;           // highest return above the extrapolated ground [m]
  float track_max_drop = 0.02f;           // deepest return below it [m]
  float track_tolerance_per_m = 0.05f;    // track_max_step grows by this per metre of gap [m/m]
  // track_max_drop grows by this per metre of gap [m/m]: slower than a step's, since a hole's
  // first return at range otherwise lies within the grown drop and the line follows it down.
  float track_drop_per_m = 0.02f;
  float track_max_local_slope = 1.0f;     // steepest rise from the last ground return
  float track_min_local_slope = -0.4f;    // steepest fall from the last ground return
  float track_anchor_distance = 3.0f;     // the extrapolation slope spans at least this [m]
  // Before a column's first ground return its line runs from the ground point under the sensor
  // with the column's straight estimate, but rises no more steeply than this: the
  // vehicle stands on the ground, so the terrain a few metres away lies near its plane. A
  // column that a parked car beside the vehicle fills from the lowest laser up otherwise
  // takes the car's side and hood for a 0.3 slope. <= 0: off [-].
  float track_first_slope_max = 0.05f;
  float track_max_bend = 0.2f;            // extrapolation slope within +- this of the column's
                                          // straight estimate (eqs 3.4-3.9)
  float track_recover_distance = 0.8f;    // consistent returns below the line over this many
                                          // metres restart it there (ground behind an obstacle)
  // The foot of a face (5.1.2: vertical faces found before the slope test): a return with
  // another of its column within track_face_dr in r and track_face_height or more above it
  // does not continue the ground line. Over the shadow of a parked car the lowest return of the
  // wall behind it lies within the gap-grown step of the line, which then climbs the wall.
  // With it (track_face_dr > 0): the step's growth over a gap starts again at the last foot the
  // line refused, and a return that rises track_face_height or more above the last ground
  // return is refused (and a run below the line does not restart it) when the chord to it
  // passes track_face_height or more above a return in between.
  float track_face_dr = 0.75f;            // [m]; 0 = off
  float track_face_height = 0.3f;         // [m]
  bool couple_columns = true;             // neighbouring columns share ground evidence
  int coupling_radius = 2;                // columns on each side that are coupled
  int min_ground_returns = 3;             // fewer feasible returns: borrow from neighbours
  bool negative_obstacles = true;         // returns well below the ground line are obstacles
  // GndErrorMax for returns BELOW the ground line (potholes, ditches) at r = 0 [m]; grows with
  // r like tolerances.gnd_error_max_per_m. 0 = the same tolerance as above the line (thesis).
  float negative_gnd_error_max = 0.05f;
  // ... but only where the line is the column's own: within this distance of one of its ground
  // returns (knot k or k + 1 of the line at r; knot support 1 / (1 + distance)). Elsewhere the
  // line is interpolated or extrapolated through terrain the column did not track (ground seen
  // beside an obstacle in bins the obstacle fills, a slope falling away behind it), and a return
  // below it is an obstacle only on a vertical surface: P_vertical with its depth below the
  // line as the GndError factor. <= 0: no such gate [m].
  float negative_support_distance = 1.0f;
  // Vertical surfaces (curb faces, the lower parts of cars and walls): a second obstacle
  // probability from the local terrain slope |dHeight/dr| between a return and the
  // representatives of the laser rows just below and above it in its column (the smaller of
  // the two), combined with GndError as in eq 3.15. P = max(P_3.15, P_vertical).
  bool vertical_surfaces = true;
  float vertical_gnd_error_max = 0.03f;   // GndError at which P_vertical's first factor is 1 [m]
  float vertical_slope_max = 0.3f;        // local slope at which its second factor is 1
  // The foot of a vertical face (a curb's lower half, the bottom of a car's side): the line's
  // segment across a step smears it, so these returns lie below or barely above the line.
  // A third term, P_foot = min(height above the foot / vertical_gnd_error_max, 1) *
  // min(rise / vertical_foot_slope, 1), where the foot is the lowest of the line and its two
  // knots before r (the ground in front of the step) and the rise is dHeight / |dr| to the
  // representative of the laser row above. P = max(P_3.15, P_vertical, P_foot). 0 = off.
  float vertical_foot_slope = 1.0f;
  // Laser-neighbour context (beyond the thesis; on in the default settings, off here and in
  // the "bins" settings: it costs about a quarter more instructions per scan, see README).
  // Each return's neighbours are the returns of the laser rows just below and above it in the
  // same sub-column (neighbour_cells_per_column per column, about 0.19 degrees for 1.5 degree
  // columns), found through a range image, whatever the order of the input. First, a return
  // that eq 3.15 called a negative obstacle is scored again with its depth below the foot of a
  // step: the lower of the line and the line's previous segment extended (where a segment
  // climbs a curb within it, the road in front of the curb lies below the segment). Then a
  // return labelled ground becomes an obstacle when
  //  - it is on a vertical face: the neighbour above (or below) is an obstacle, higher (lower)
  //    by at least neighbour_min_step, and within neighbour_max_dr of it in r, but no more than
  //    neighbour_spacing_fraction of the spacing of the two rows on flat ground at that range
  //    (so the road just in front of a face is not taken for its foot);
  //  - it is the top of a hole's far wall: the neighbour below lies more than
  //    negative_gnd_error_max below the line, lower than this return, within
  //    2 * neighbour_max_dr of it in r.
  // Its P(obstacle) is then the neighbour's.
  bool laser_neighbours = false;
  // Curbs (needs laser_neighbours). SemanticKITTI and most labelled data sets call a curb's
  // face road or sidewalk; many planners want it as an obstacle. kCurbGround: a short face
  // between two ground returns of one sub-column (ground in front, ground on top, the face's
  // returns rising to the top by at most curb_max_height within curb_max_depth in r) is
  // ground, and neither the top nor the foot of that face becomes an obstacle through its
  // neighbours. kCurbObstacle: every face is an obstacle.
  int curb_policy = 0;                       // kCurbObstacle = 0, kCurbGround = 1
  float curb_max_height = 0.2f;              // [m]
  float curb_max_depth = 0.5f;               // [m]
  int neighbour_cells_per_column = 8;
  float neighbour_max_dr = 0.05f;            // [m]
  float neighbour_spacing_fraction = 0.3f;   // [-]
  float neighbour_min_step = 0.01f;          // [m]
  // Local ground height (beyond the thesis: the ground-height estimate shared across azimuth
  // that 5.1.2 names; on in the default settings, off in the thesis's and the bins', needs
  // laser_neighbours). After the labels above, first the feet of faces: a ground return next to
  // an obstacle (a cell the laser-neighbour pass marked) from which a face rises becomes an
  // obstacle. A face rises from a return when the returns of the rows above it in its sub-column
  // stay within local_ground_face_dr of it in r, the first one rises at most a row spacing at
  // its range, and one reaches local_ground_face_height above it (the foot of a wall, a car, a
  // fence). Then the returns called ground are averaged per cell of a polar grid (one column
  // wide, local_ground_cell long in r), and an obstacle return whose height lies within
  // [-local_ground_below, +local_ground_above] of the mean ground height of the cells around it
  // (local_ground_columns and local_ground_rings on each side, at least
  // local_ground_min_returns ground returns) becomes ground, unless a face rises from it or it
  // lies on a face: walking up and down its sub-column, each next return within
  // local_ground_face_dr in r of the one before and rising or falling at least as steeply as
  // vertical_foot_slope, the returns reached span local_ground_face_min_height or more (a curb's
  // face, a step; with curb_policy ground the laser-neighbour pass has made the curbs ground
  // before). With local_ground_roughness k > 0
  // the band widens, where the ground around is rough (grass, a verge), to k standard
  // deviations of its heights, at most local_ground_roughness_max (a local roughness model,
  // 5.1.2). It takes back the flat ground (rough grass, kerbside parking, the sidewalk) that the
  // per-column terms call obstacle on real scans, and with it returns of shallow holes within
  // the band of the ground around them. Costs about 3.7 M instructions per 124,000-return scan
  // (AVX2).
  bool local_ground = false;
  float local_ground_cell = 1.0f;            // [m]
  int local_ground_columns = 1;
  int local_ground_rings = 0;
  int local_ground_min_returns = 3;
  float local_ground_below = 0.03f;          // [m]
  float local_ground_above = 0.04f;          // [m]
  float local_ground_face_dr = 0.1f;         // [m]
  float local_ground_face_height = 0.2f;     // [m]
  float local_ground_face_min_height = 0.05f;  // [m]
  float local_ground_roughness = 0.f;        // [standard deviations]; 0 = off
  float local_ground_roughness_max = 0.1f;   // [m]
};

// Settings by name: "thesis" (the thesis's method and settings), "default" (beyond it), and
// "bins" (the default without laser_neighbours: the context of the bins alone, cheaper).
VerticalScanParams verticalScanThesisParams();
VerticalScanParams verticalScanDefaultParams();
VerticalScanParams verticalScanBinsParams();

// The params for a sensor of the lidar table (or a user's laser_elevations_deg): its beam
// elevations, for the row table and the spacing of adjacent rows, and the tracking step
// scaled for sparser beams: track_max_step (set for the HDL-64E) times sparseBeamScale().
// Consecutive ground returns of a column lie Delta_r ~ r^2 Delta_theta / h apart, so a sensor
// with wider beam spacing Delta_theta extrapolates the ground line over longer gaps, where the
// terrain bends more; the linear growth with the gap (track_tolerance_per_m) is unchanged.
VerticalScanParams paramsForLidarModel(VerticalScanParams params, const LidarModel& lidar);
// sqrt(Delta_theta / Delta_theta_HDL-64E) for the mean spacing of the downward beams, within
// [1, 2.5]: 1 for the HDL-64E and the 128-beam sensors, about 1.8 for the 32-beam ones, 2.2
// for the VLP-16.
float sparseBeamScale(const std::vector<float>& elevations_deg);

// Sets one parameter of the table by its name or field path ("weight_bias",
// "gnd_error_max_base" or "tolerances.gnd_error_max_base", "bend_ground_line" 0/1, ...): the
// tools' --set key=value. False with a reason for an unknown key or a value out of its range.
bool setVerticalScanParam(VerticalScanParams* params, const std::string& key, double value,
                          std::string* error);
// Reads one parameter of the table (bools as 0/1); false for an unknown key.
bool getVerticalScanParam(const VerticalScanParams& params, const std::string& key, double* value);
// The parameter table, in the order of vertical_scan_params.def.
const std::vector<ParamInfo>& verticalScanParamTable();

// The vertical scan method as a GroundModel with the given params (used by the nodelet, which
// rebuilds the model when dynamic_reconfigure changes a parameter).
std::unique_ptr<GroundModel> makeVerticalScanModel(const VerticalScanParams& params);

// Row assignment from the elevation angle for clouds without a `ring` field: a lookup table
// over tan(elevation) = z / r whose cells hold the nearest laser's row (the row index is the
// laser's position in the table sorted ascending, so it matches the velodyne driver's ring).
// Elevations outside the table go to the nearest end row.
class ElevationRowTable {
 public:
  void build(const std::vector<float>& elevations_deg);
  int rows() const { return rows_; }
  // Row of a return at height z and horizontal distance r > 0 (sensor frame).
  int row(float z, float r) const {
    const float t = z / r;
    float f = (t - t_min_) * inv_cell_;
    f = f < 0.f ? 0.f : (f > max_cell_ ? max_cell_ : f);
    return lut_[static_cast<int>(f)];
  }
  // The table itself, for vectorised lookups that repeat row()'s arithmetic lane by lane.
  const uint8_t* lut() const { return lut_.data(); }
  float tMin() const { return t_min_; }
  float invCell() const { return inv_cell_; }
  float maxCell() const { return max_cell_; }

 private:
  std::vector<uint8_t> lut_;
  float t_min_ = 0.f;
  float inv_cell_ = 1.f;
  float max_cell_ = 0.f;
  int rows_ = 0;
};

// One vertical scan (3.3 step 2): the representative returns of one azimuth column, sorted by
// increasing HorizontalDistance r. The column-level equations, exposed for the unit tests.
namespace vertical_scan {

// Eq 3.4: Slope_i = Height_i / r_i lies strictly between GroundSlopeMin and GroundSlopeMax.
inline bool feasible(float height, float r, const VerticalScanParams& p) {
  const float slope = height / r;
  return slope > p.ground_slope_min && slope < p.ground_slope_max;
}

// Eqs 3.4-3.9 on one column: feasibility, upper-half rejection (3.5), then `iterations`
// rounds of the weighted slope estimate seeded with `seed` (0 in the thesis). r must be sorted
// ascending. `weights` is scratch of at least n floats. Returns the SlopeEstimate; *support
// (optional) receives the number of returns that took part in the fit.
float estimateSlope(const float* r, const float* height, int n, const VerticalScanParams& p,
                    float seed, float* weights, int* support = nullptr);

// Eq 3.10 and 3.11 for a straight ground line through the ground point under the sensor.
inline float groundError(float slope_estimate, float r, float height) {
  return slope_estimate * r - height;
}
inline float slopeError(float slope_estimate, float r, float height) {
  return slope_estimate - height / r;
}

// A column's ground line: heights of the ground at the knots r = k * segment_length,
// k = 0..knots-1 (knot 0 is the ground point under the sensor, height 0). The thesis line is
// the special case of equal slopes. Evaluated by linear interpolation, constant slope beyond
// the last knot.
struct GroundLine {
  const float* knot_height = nullptr;
  int knots = 0;
  float inv_segment = 1.f;

  float heightAt(float r) const {
    const float f = r * inv_segment;
    int k = static_cast<int>(f);
    if (k > knots - 2) k = knots - 2;
    const float t = f - static_cast<float>(k);
    return knot_height[k] + (knot_height[k + 1] - knot_height[k]) * t;
  }
};

// The bent ground line (beyond the thesis, 5.1.2): walks the column's representatives (sorted
// by r) from the ground point under the sensor, extrapolating with the slope of the ground so
// far (seeded with the straight estimate `slope0`, eqs 3.4-3.9) and accepting a return as
// ground when (a) its residual to the extrapolation lies in [-(track_max_drop + gd dr),
// track_max_step + g dr] (dr = gap to the last ground return, g = track_tolerance_per_m,
// gd = track_drop_per_m), (b) its slope from the last ground return lies in
// [track_min_local_slope, track_max_local_slope], (c) no return of the column within
// track_face_dr of it in r lies track_face_height or more above it (the foot of a face) and
// (d) when it rises track_face_height or more above the last ground return, the chord to it
// passes no return in between by track_face_height or more. The gap dr of g dr counts from the
// last foot of a face refused since the last ground return, where it is nearer.
// Until the first return is accepted the line is only the straight estimate from the sensor's
// ground point, and the lower bound is -(track_max_step + gd dr). Returns below the line that
// continue each other over track_recover_distance restart it there (unless the chord to the
// first of them fails (d)); the ground returns the line took across a gap just before,
// standing above the restart more steeply than ground_slope_max (an object's top), leave it.
// (VerticalScanGround seeds it with the straight estimate over the representatives off
// vertical surfaces.) The accepted polyline is sampled at the knots; beyond the last ground
// return it is extrapolated with the tracked slope, but rising no faster than slope0 (flat
// where slope0 < 0): the terrain there is unobserved. knot_support gets 1 / (1 + distance to
// the nearest ground return).
// `scratch` holds at least 2 * (n + 1) floats. Returns the number of accepted returns.
int trackGroundLine(const float* r, const float* height, int n, const VerticalScanParams& p,
                    float slope0, int knots, float* knot_height, float* knot_support,
                    float* scratch);

}  // namespace vertical_scan

// A growable array that does not initialise its elements (per-scan workspace: every element
// is written before it is read, so zero-filling 124,000 points per scan would be wasted work).
template <typename T>
class ScratchBuffer {
 public:
  void resize(std::size_t n) {
    if (n > capacity_) {
      data_.reset(new T[n]);
      capacity_ = n;
    }
    size_ = n;
  }
  std::size_t size() const { return size_; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t size_ = 0, capacity_ = 0;
};

// The vertical scan ground model. Keep one instance per stream: its workspace buffers are
// reused, so steady-state scans do not allocate.
class VerticalScanGround : public GroundModel {
 public:
  explicit VerticalScanGround(const VerticalScanParams& params = verticalScanDefaultParams(),
                              std::string name = "vertical_scan");
  std::string name() const override { return name_; }
  void classify(const PointCloudView& view, const SensorPose& pose,
                GroundClassification* out) override;

  const VerticalScanParams& params() const { return params_; }
  void setParams(const VerticalScanParams& params);
  // setParams(paramsForLidarModel(params(), lidar)).
  void setLidarModel(const LidarModel& lidar) override;

  // Introspection of the last scan (tests, visualisation).
  int columns() const { return columns_; }
  int knotsPerColumn() const { return knots_; }
  // Ground height under the column `col` at horizontal distance r, in the ground frame
  // (beyond the scan's farthest return: its last segment extended).
  float groundHeight(int col, float r) const;
  int columnOf(float x, float y) const;
  // How the last scan's rows were read: from the ring or channel field or the rows of an
  // organised cloud (source), the highest ring seen (every 7th return), and whether the ring
  // numbers count from the top beam down (Ouster's driver; checked per scan from the returns'
  // elevations, then row = top_ring - ring). Source kNone: rows from the elevation table.
  struct RingInfo {
    PointCloudView::RingSource source = PointCloudView::RingSource::kNone;
    int max_ring = -1;
    int top_ring = -1;
    bool top_down = false;
  };
  const RingInfo& lastRings() const { return last_rings_; }

 private:
  // Column (0..columns_-1) of a ground-frame direction, through the atan LUT.
  float columnCoordinate(float x, float y) const;
  // groundHeight() for the stages, inlined (defined in the core's vertical_scan_internal.h).
  inline float groundLineHeight(int col, float r) const;
  template <bool kRing, bool kTilted, bool kFastXYZ, bool kSubColumns>
  void binPoints(const PointCloudView& view, const SensorPose& pose, GroundClassification* out);
  void readRingOrder(const PointCloudView& view);
  void fitColumns();
  void labelPoints(GroundClassification* out);
  void labelFromLaserNeighbours(float sensor_height, GroundClassification* out);
  void relabelCurbFaces(float g_below, const uint8_t* mark, uint8_t stamp, GroundClassification* out);
  void relabelFromLocalGround(GroundClassification* out);

  VerticalScanParams params_;
  std::string name_;
  ElevationRowTable row_table_;
  RingInfo last_rings_;
  int columns_ = 0;
  int rows_ = 0;       // rows per column in the bin grid (a power of two)
  int row_shift_ = 0;  // log2(rows_)
  int knots_ = 0;      // knots per column's ground line (the stride of knot_height_)
  int knots_used_ = 0;  // of which the last scan filled (out to its farthest return)
  float inv_column_width_ = 0.f;  // columns per radian
  float inv_segment_ = 0.f;

  // Per-scan workspace, reused.
  ScratchBuffer<float> r_;        // horizontal distance per input point (ground frame)
  ScratchBuffer<float> height_;   // height per input point (ground frame)
  ScratchBuffer<uint32_t> bin_;   // bin per input point, unknown_bin_ for unknown returns
  uint32_t unknown_bin_ = 0;      // one past the bin grid
  std::vector<uint32_t> bin_start_;   // counting sort of points by bin
  ScratchBuffer<uint32_t> run_start_;  // first point of each run of one bin, then n
  // The points' r and height by bin (input order within a bin); r padded for 4-wide reads
  // past the last bin.
  ScratchBuffer<float> order_r_, order_h_;
  std::vector<uint64_t> big_bin_;  // rangeKey()s of one large bin (median by selection)
  std::vector<float> atan_lut_;   // atan(t), t in [0, 1], in column units
  float octant_offset_[8] = {}, octant_sign_[8] = {};  // atan2 = offset + sign * atan LUT
  ScratchBuffer<float> col_r_, col_h_;         // each column's representatives
  std::vector<float> col_w_;
  // columns_ x knot_stride_ after kKnotPad floats, and kKnotPad after them: each column's
  // knots_ knots and a spare one that stays 0 (kh[0] of the next column is 0 too), so that
  // labelPoints() reads kh[k - 1 .. k + 2] of every knot k in one 16-byte load, kh[-1] = 0.
  static constexpr std::size_t kKnotPad = 4;
  int knot_stride_ = 0;
  std::vector<float> knot_height_;
  std::vector<float> knot_support_;            // columns_ x knot_stride_ (no leading pad)
  std::vector<float> coupled_;                 // like knot_height_
  // labelPoints: groups of four returns with a negative obstacle, (group << 4) | lane bits.
  std::vector<uint32_t, DefaultInitAllocator<uint32_t>> below_line_groups_;
  std::size_t below_line_count_ = 0;   // groups listed in the last scan
  bool below_line_listed_ = false;     // the 4-wide loop listed them (support gate on)
  std::size_t below_line_from_ = 0;    // where the scalar loop took over (not listed)
  // laser_neighbours: groups of four with a return deeper than negative_gnd_error_max under
  // the line, listed by the same loop (deep_listed_: it ran), as below_line_groups_.
  std::vector<uint32_t, DefaultInitAllocator<uint32_t>> deep_groups_;
  std::size_t deep_count_ = 0;
  bool deep_listed_ = false;
  std::vector<float> slope_coupled_;           // columns_
  std::vector<float> rep_;  // bin representatives' (r, height) pairs, r < 0: empty bin
  std::vector<float> column_slope_;            // straight estimate per column
  std::vector<int> column_support_;
  std::vector<int> column_count_;
  // laser_neighbours: each return's range-image cell (binPoints), the range image (the last
  // return written to each cell; a cell's entry is valid when that return's own cell is the
  // cell, so the image is never cleared), the tangent of the angle to the next row up per
  // row, and the returns to relabel.
  ScratchBuffer<uint32_t> cell_;
  int cell_row_shift_ = 0;  // cell = row << cell_row_shift_ | sub-column
  std::vector<uint32_t> range_image_;
  // One byte per range-image cell (and one before and after): the cells next to an obstacle
  // or above a deep return carry this scan's stamp, so only their ground returns are tested.
  std::vector<uint8_t> cell_mark_;
  uint8_t mark_stamp_ = 0;
  std::vector<float> row_gap_tan_;
  std::vector<std::pair<uint32_t, float>> neighbour_obstacles_;
  // curb_policy kCurbGround: the curb faces' returns to relabel ground.
  std::vector<uint32_t> curb_ground_;
  // local_ground: (height sum, squared height sum, count) of the ground returns per cell of the
  // polar grid (ring-major), the same summed over each cell's neighbourhood, and the rings out
  // to max_range.
  std::vector<float> local_grid_, local_around_;
  int local_rings_ = 0;
  // Per bin: its representative's cell, and the band of heights that is level with the ground
  // there (low, high).
  std::vector<uint32_t> local_bin_cell_;
  std::vector<float> local_bin_band_;
};

}  // namespace ladar_perception
