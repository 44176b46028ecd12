// Hough ground fit for a vertically mounted 2D ladar (thesis 3.3.4; algorithms.md).
#include "ladar_perception/ground/hough_ground.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "param_access.h"

namespace ladar_perception {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kMaxCells = 4096;  // per accumulator axis: bounds the memory of a bad setting

float positiveOr(float v, float fallback) { return std::isfinite(v) && v > 0.f ? v : fallback; }

}  // namespace

HoughGroundParams houghGroundThesisParams() {
  HoughGroundParams p;
  p.tolerances = ObstacleToleranceParams();  // the vertical scan method's tolerances
  p.refine = false;  // the thesis takes the accumulator's argmax as the ground line
  p.bend_segments = 0;  // one straight line
  p.slope_error_min_distance = 0.05f;  // as the vertical scan method's Height / r
  return p;
}

HoughGroundParams houghGroundDefaultParams() { return HoughGroundParams(); }

namespace {

const std::vector<ParamAccess<HoughGroundParams>>& houghTable() {
  static const std::vector<ParamAccess<HoughGroundParams>> rows = {
#define LADAR_PARAM(...) LADAR_PARAM_ACCESS(HoughGroundParams, __VA_ARGS__)
#include "ladar_perception/ground/hough_params.def"
  };
  return rows;
}

}  // namespace

bool setHoughGroundParam(HoughGroundParams* p, const std::string& key, double value,
                         std::string* error) {
  return setParam(houghTable(), "Hough ground", p, key, value, error);
}

bool getHoughGroundParam(const HoughGroundParams& p, const std::string& key, double* value) {
  return getParam(houghTable(), p, key, value);
}

const std::vector<ParamInfo>& houghGroundParamTable() {
  static const std::vector<ParamInfo> infos = paramInfos(houghTable());
  return infos;
}

// --------------------------------------------------------------------------------------------
// The accumulator.

HoughLineFitter::HoughLineFitter(const HoughGroundParams& params) { setParams(params); }

void HoughLineFitter::setParams(const HoughGroundParams& in) {
  HoughGroundParams p = in;
  // Bad settings are repaired, never trusted: positive resolutions, ordered ranges.
  p.ground_resolution = positiveOr(p.ground_resolution, 0.04f);
  p.slope_resolution = positiveOr(p.slope_resolution, 0.01f);
  p.error_tolerance = positiveOr(p.error_tolerance, 0.1f);
  if (!std::isfinite(p.ground_min)) p.ground_min = -1.f;
  if (!std::isfinite(p.ground_max) || p.ground_max < p.ground_min) p.ground_max = p.ground_min;
  if (!std::isfinite(p.slope_min)) p.slope_min = -0.35f;
  if (!std::isfinite(p.slope_max) || p.slope_max < p.slope_min) p.slope_max = p.slope_min;
  if (!(p.min_fit_distance > 0.f)) p.min_fit_distance = 0.05f;
  if (!(p.max_fit_distance >= p.min_fit_distance)) p.max_fit_distance = p.min_fit_distance;
  p.min_inliers = std::max(p.min_inliers, 2);
  p.bend_segments = std::min(std::max(p.bend_segments, 0), GroundLineFit::kMaxBends);
  p.segment_length = positiveOr(p.segment_length, 10.f);
  if (!(p.max_bend >= 0.f)) p.max_bend = 0.f;
  p.min_segment_inliers = std::max(p.min_segment_inliers, 2);
  p.slope_error_min_distance = positiveOr(p.slope_error_min_distance, 0.05f);
  p.refine_iterations = std::max(p.refine_iterations, 0);
  n_ground_ = std::min(kMaxCells, static_cast<int>(std::floor((p.ground_max - p.ground_min) /
                                                              p.ground_resolution + 1e-4f)) + 1);
  n_slope_ = std::min(kMaxCells, static_cast<int>(std::floor((p.slope_max - p.slope_min) /
                                                             p.slope_resolution + 1e-4f)) + 1);
  // Window half-width in cells so that the window spans about +-ErrorTolerance.
  pad_ = std::max(0, static_cast<int>(std::lround(p.error_tolerance / p.ground_resolution - 0.5f)));
  pad_ = std::min(pad_, kMaxCells);
  // Rows of counts are padded to a multiple of 8 cells (whole SSE2 vectors, no scalar tails).
  stride_ = (n_ground_ + 7) & ~7;
  row_ = stride_ + 2 * pad_;
  votes_.assign(static_cast<std::size_t>(n_slope_) * row_, 0);
  row_scratch_.assign(stride_, 0);
  row_max_.assign(n_slope_, 0);
  counts_.assign(static_cast<std::size_t>(n_slope_) * stride_, 0);
  params_ = p;
}

int HoughLineFitter::count(int slope_cell, int ground_cell) const {
  if (slope_cell < 0 || slope_cell >= n_slope_ || ground_cell < 0 || ground_cell >= n_ground_) {
    return 0;
  }
  return static_cast<int>(counts_[static_cast<std::size_t>(slope_cell) * stride_ + ground_cell]);
}

int HoughLineFitter::vote(const float* r, const float* height, int n, const GroundLineFit* exclude) {
  const HoughGroundParams& p = params_;
  std::fill(votes_.begin(), votes_.end(), int16_t(0));
  const float inv_gres = 1.f / p.ground_resolution;
  const float last_row = static_cast<float>(n_slope_ - 1);
  const float row_f = static_cast<float>(n_ground_ + 2 * pad_);  // cells past it stay 0
  // Eq 3.12, voting: a return votes in each Slope row for the Ground cell of the line through
  // it, Ground = Height - r * Slope. Along the rows that cell moves by r * dSlope / dGround, so
  // only the rows where it stays inside the (padded) row are visited.
  int votes = 0;
  for (int i = 0; i < n; ++i) {
    const float ri = r[i], hi = height[i];
    if (!std::isfinite(ri) || !std::isfinite(hi)) continue;
    const float ar = std::fabs(ri);
    if (ar < p.min_fit_distance || ar > p.max_fit_distance) continue;
    if (exclude && std::fabs(hi - exclude->ground - ri * exclude->slope) < p.error_tolerance) continue;
    // Padded cell index (+0.5: round to the nearest cell centre) in row j: c0 - j * dc.
    const float c0 = (hi - ri * p.slope_min - p.ground_min) * inv_gres + static_cast<float>(pad_) + 0.5f;
    const float dc = ri * p.slope_resolution * inv_gres;
    if (!(std::fabs(c0) < 16384.f) || !(std::fabs(dc) < 16384.f)) continue;  // far off the grid
    float j_lo, j_hi;
    if (dc > 0.f) {
      j_lo = (c0 - row_f) / dc;
      j_hi = c0 / dc;
    } else {
      j_lo = c0 / dc;
      j_hi = (c0 - row_f) / dc;
    }
    const int j0 = static_cast<int>(std::max(0.f, std::floor(j_lo)));
    const int j1 = static_cast<int>(std::min(last_row, std::ceil(j_hi)));
    if (j0 > j1) continue;
    // 16.16 fixed point along the rows: one subtraction and shift per vote. The cell moves
    // monotonically with j, so trimming the row range's ends leaves only in-range cells.
    const int64_t fixed0 = static_cast<int64_t>(static_cast<double>(c0) * 65536.0);
    const int64_t dfixed = static_cast<int64_t>(static_cast<double>(dc) * 65536.0);
    const int64_t cells = n_ground_ + 2 * pad_;
    auto cellAt = [&](int j) { return (fixed0 - static_cast<int64_t>(j) * dfixed) >> 16; };
    int a = j0, b = j1;
    while (a <= b && (cellAt(a) < 0 || cellAt(a) >= cells)) ++a;
    while (b >= a && (cellAt(b) < 0 || cellAt(b) >= cells)) --b;
    if (a > b) continue;
    ++votes;
    const int row = row_;  // a local: the stores through acc could alias the member
    int16_t* acc = votes_.data() + static_cast<std::size_t>(a) * row;
    int64_t f = fixed0 - static_cast<int64_t>(a) * dfixed;
    for (int j = a; j <= b; ++j, f -= dfixed, acc += row) ++acc[f >> 16];
  }
  return votes;
}

uint32_t HoughLineFitter::argmax(bool store, int* best_j, int* best_c) {
  // count(|ErrorValue| < ErrorTolerance) of each cell: a window of 2 pad + 1 cells over the
  // single-cell votes, and its maximum. Signed 16-bit counts, locals and restrict, so the
  // compiler vectorises the loops with plain SSE2.
  const int window = 2 * pad_ + 1;
  const int ng = n_ground_, ns = n_slope_, row = row_, stride = stride_;
  int16_t best = 0;
  for (int j = 0; j < ns; ++j) {
    const int16_t* __restrict v = votes_.data() + static_cast<std::size_t>(j) * row;
    int16_t* __restrict out =
        store ? counts_.data() + static_cast<std::size_t>(j) * stride : row_scratch_.data();
    for (int c = 0; c < stride; ++c) out[c] = v[c];
    for (int k = 1; k < window; ++k) {
      const int16_t* __restrict vk = v + k;
      for (int c = 0; c < stride; ++c) out[c] = static_cast<int16_t>(out[c] + vk[c]);
    }
    for (int c = ng; c < stride; ++c) out[c] = 0;  // padding cells: no hypothesis
    int16_t m = 0;
    for (int c = 0; c < stride; ++c) m = std::max(m, out[c]);
    row_max_[j] = m;
    best = std::max(best, m);
  }
  *best_j = -1;
  *best_c = -1;
  if (best == 0 || !store) return static_cast<uint32_t>(best);
  // Ties (the window makes plateaus) go to the cell with more returns of its own, then to the
  // lowest Ground (obstacles stand on the ground and shadow it, so a tie is more likely
  // resolved correctly downward, as WeightBias in eq 3.6).
  int16_t best_centre = -1;
  for (int j = 0; j < ns; ++j) {
    if (row_max_[j] != best) continue;
    const int16_t* v = votes_.data() + static_cast<std::size_t>(j) * row + pad_;
    const int16_t* cnt = counts_.data() + static_cast<std::size_t>(j) * stride;
    for (int c = 0; c < ng; ++c) {
      if (cnt[c] != best) continue;
      if (v[c] > best_centre || (v[c] == best_centre && c < *best_c)) {
        best_centre = v[c];
        *best_j = j;
        *best_c = c;
      }
    }
  }
  return static_cast<uint32_t>(best);
}

GroundLineFit HoughLineFitter::fit(const float* r, const float* height, int n) {
  const HoughGroundParams& p = params_;
  GroundLineFit fit;
  // The returns that can vote: finite, |r| in [min_fit_distance, max_fit_distance]; at most
  // 32767, so that no 16-bit count overflows (far more than any vertical scan holds).
  fr_.clear();
  fh_.clear();
  for (int i = 0; i < n && fr_.size() < 32767u; ++i) {
    const float ri = r[i], hi = height[i];
    const float ar = std::fabs(ri);
    if (ar >= p.min_fit_distance && ar <= p.max_fit_distance && std::isfinite(hi)) {  // NaN fails
      fr_.push_back(ri);
      fh_.push_back(hi);
    }
  }
  const int m = static_cast<int>(fr_.size());
  fit.votes = vote(fr_.data(), fh_.data(), m, nullptr);
  int best_j = -1, best_c = -1;
  const uint32_t best = argmax(true, &best_j, &best_c);
  if (best_j < 0 || static_cast<int>(best) < p.min_inliers) return fit;
  fit.cell_count = static_cast<int>(best);
  fit.cell_ground = p.ground_min + static_cast<float>(best_c) * p.ground_resolution;
  fit.cell_slope = p.slope_min + static_cast<float>(best_j) * p.slope_resolution;
  fit.ground = fit.cell_ground;
  fit.slope = fit.cell_slope;

  // Runner-up (confidence, beyond the thesis): the most returns any line explains among the
  // returns the winning cell does not explain, i.e. the best competing ground hypothesis.
  // A second vote without the winner's inliers; the stored accumulator stays the first one.
  vote(fr_.data(), fh_.data(), m, &fit);
  int j2, c2;
  const uint32_t runner = argmax(false, &j2, &c2);
  fit.runner_up = static_cast<int>(runner);
  fit.margin = static_cast<float>(best - std::min(best, runner)) / static_cast<float>(best);

  refine(fr_.data(), fh_.data(), m, &fit);
  if (fit.valid && p.bend_segments > 0) bend(r, height, n, &fit);
  return fit;
}

void HoughLineFitter::bend(const float* r, const float* height, int n, GroundLineFit* fit) {
  const HoughGroundParams& p = params_;
  const float tol = p.error_tolerance;
  const float L = p.segment_length;
  float r0 = fit->r_max;  // the line is supported up to its farthest inlier ahead
  if (!(r0 > 0.f)) return;
  float h0 = fit->ground + fit->slope * r0;
  float s_prev = fit->slope;
  const int candidates = static_cast<int>(std::floor(2.f * p.max_bend / p.slope_resolution)) + 1;
  for (int k = 0; k < p.bend_segments; ++k) {
    // The segment's returns relative to its start point.
    seg_d_.clear();
    seg_e_.clear();
    for (int i = 0; i < n; ++i) {
      const float d = r[i] - r0;
      if (d > 1e-3f && d <= L && std::isfinite(height[i])) {  // NaN r fails the comparison
        seg_d_.push_back(d);
        seg_e_.push_back(height[i] - h0);
      }
    }
    const int m = static_cast<int>(seg_d_.size());
    if (m < p.min_segment_inliers) break;
    // The slope through the start point that the most returns support (a 1-D accumulator);
    // ties to the smallest bend.
    int best = 0;
    float best_s = s_prev;
    for (int c = 0; c < candidates; ++c) {
      const float s = s_prev - p.max_bend + static_cast<float>(c) * p.slope_resolution;
      int count = 0;
      for (int j = 0; j < m; ++j) count += std::fabs(seg_e_[j] - s * seg_d_[j]) < tol;
      if (count > best || (count == best && std::fabs(s - s_prev) < std::fabs(best_s - s_prev))) {
        best = count;
        best_s = s;
      }
    }
    if (best < p.min_segment_inliers) break;
    // Least squares slope through the start point on the inliers.
    double sde = 0, sdd = 0;
    for (int j = 0; j < m; ++j) {
      if (std::fabs(seg_e_[j] - best_s * seg_d_[j]) < tol) {
        sde += static_cast<double>(seg_d_[j]) * seg_e_[j];
        sdd += static_cast<double>(seg_d_[j]) * seg_d_[j];
      }
    }
    float s = sdd > 0 ? static_cast<float>(sde / sdd) : best_s;
    s = std::min(std::max(s, s_prev - p.max_bend), s_prev + p.max_bend);
    fit->bend_r[k] = r0;
    fit->bend_h[k] = h0;
    fit->bend_slope[k] = s;
    fit->bends = k + 1;
    r0 += L;
    h0 += s * L;
    s_prev = s;
  }
}

void HoughLineFitter::refine(const float* r, const float* height, int n, GroundLineFit* fit) const {
  const HoughGroundParams& p = params_;
  double g = fit->ground, s = fit->slope;
  const int rounds = p.refine ? p.refine_iterations : 0;
  // The gate of each round: ErrorTolerance first, then three times the RMS residual of the
  // previous round (floor kMinGate), so the lowest returns of obstacle faces and walls, which
  // lie inside ErrorTolerance, stop pulling the line once it has converged onto the ground.
  constexpr double kMinGate = 0.02;
  double tol = p.error_tolerance;
  for (int round = 0; round < rounds; ++round) {
    // Least squares on the inliers of the current line (beyond the thesis).
    double sn = 0, sr = 0, sh = 0, srr = 0, srh = 0, shh = 0;
    for (int i = 0; i < n; ++i) {
      const double ri = r[i], hi = height[i];
      const double ar = std::fabs(ri);
      if (!(ar >= p.min_fit_distance && ar <= p.max_fit_distance)) continue;  // also NaN
      if (!(std::fabs(hi - g - s * ri) < tol)) continue;
      sn += 1;
      sr += ri;
      sh += hi;
      srr += ri * ri;
      srh += ri * hi;
      shh += hi * hi;
    }
    if (sn < 2) break;
    const double mr = sr / sn, mh = sh / sn;
    const double var_r = srr / sn - mr * mr;
    double ng, ns = s;
    // A slope needs support spread along r (0.25 m standard deviation); otherwise only the
    // offset is refitted at the accumulator's slope.
    if (var_r > 0.0625) ns = (srh / sn - mr * mh) / var_r;
    ng = mh - ns * mr;
    // Mean squared residual of the new line over the same returns (expanded sums).
    const double ms = std::max(0.0, shh / sn - 2 * ng * mh - 2 * ns * (srh / sn) + ng * ng +
                                        2 * ng * ns * mr + ns * ns * (srr / sn));
    tol = std::min<double>(p.error_tolerance, std::max(kMinGate, 3.0 * std::sqrt(ms)));
    const bool converged = std::fabs(ng - g) < 1e-6 && std::fabs(ns - s) < 1e-7;
    g = ng;
    s = ns;
    if (converged) break;
  }
  fit->ground = static_cast<float>(g);
  fit->slope = static_cast<float>(s);

  // Confidence of the final line.
  int inliers = 0;
  double sum_e2 = 0;
  float r_lo = std::numeric_limits<float>::max(), r_hi = -r_lo;
  for (int i = 0; i < n; ++i) {
    const float ri = r[i];
    const float ar = std::fabs(ri);
    if (!(ar >= p.min_fit_distance && ar <= p.max_fit_distance)) continue;
    const float e = height[i] - fit->ground - ri * fit->slope;
    if (!(std::fabs(e) < p.error_tolerance)) continue;
    ++inliers;
    sum_e2 += static_cast<double>(e) * e;
    r_lo = std::min(r_lo, ri);
    r_hi = std::max(r_hi, ri);
  }
  fit->inliers = inliers;
  fit->rms = inliers > 0 ? static_cast<float>(std::sqrt(sum_e2 / inliers)) : 0.f;
  fit->r_min = inliers > 0 ? r_lo : 0.f;
  fit->r_max = inliers > 0 ? r_hi : 0.f;
  fit->valid = inliers >= p.min_inliers;
}

// --------------------------------------------------------------------------------------------
// Labels (eqs 3.13-3.15).

void classifyAgainstLine(const GroundLineFit& fit, const float* r, const float* height, int n,
                         const ObstacleToleranceParams& tolerances, uint8_t* labels,
                         float* p_obstacle, float slope_error_min_distance) {
  for (int i = 0; i < n; ++i) {
    const float ri = r[i], hi = height[i];
    if (!fit.valid || !std::isfinite(ri) || !std::isfinite(hi)) {
      labels[i] = kLabelUnknown;
      p_obstacle[i] = 0.f;
      continue;
    }
    const float gnd_error = houghGndError(fit, ri, hi);        // eq 3.13
    const float slope_error = houghSlopeError(gnd_error, ri, slope_error_min_distance);  // eq 3.14
    const float prob = obstacleProbability(gnd_error, slope_error, std::fabs(ri), tolerances);
    p_obstacle[i] = prob;
    labels[i] = prob > tolerances.obstacle_threshold ? kLabelObstacle : kLabelGround;
  }
}

// --------------------------------------------------------------------------------------------
// The thesis's 1-DOF fit on a 2D vertical scan.

GroundLineFit OneDofLineFitter::fit(const float* r, const float* height, int n,
                                    float min_fit_distance, float max_fit_distance) {
  GroundLineFit fit;
  pairs_.clear();
  for (int i = 0; i < n; ++i) {
    // The line from the ground point under the sensor: only returns ahead (r > 0).
    if (std::isfinite(height[i]) && r[i] >= min_fit_distance && r[i] <= max_fit_distance) {
      pairs_.emplace_back(r[i], height[i]);
    }
  }
  std::sort(pairs_.begin(), pairs_.end());  // eq 3.7 needs increasing r
  const int m = static_cast<int>(pairs_.size());
  r_.resize(m);
  h_.resize(m);
  w_.resize(m);
  for (int i = 0; i < m; ++i) {
    r_[i] = pairs_[i].first;
    h_[i] = pairs_[i].second;
  }
  fit.votes = m;
  int support = 0;
  const float slope = vertical_scan::estimateSlope(r_.data(), h_.data(), m, params_, 0.f,
                                                   w_.data(), &support);  // eqs 3.4-3.9
  fit.ground = 0.f;
  fit.slope = slope;
  fit.cell_slope = slope;
  fit.cell_count = support;
  const float tol = params_.tolerances.gnd_error_max_base;
  double sum_e2 = 0;
  for (int i = 0; i < m; ++i) {
    const float e = h_[i] - slope * r_[i];
    if (std::fabs(e) < tol) {
      if (fit.inliers == 0) fit.r_min = r_[i];
      fit.r_max = r_[i];
      ++fit.inliers;
      sum_e2 += static_cast<double>(e) * e;
    }
  }
  fit.rms = fit.inliers > 0 ? static_cast<float>(std::sqrt(sum_e2 / fit.inliers)) : 0.f;
  fit.valid = support > 0;
  return fit;
}

// --------------------------------------------------------------------------------------------
// One LaserScan.

HoughGround::HoughGround(const HoughGroundParams& params) : fitter_(params) {}

void HoughGround::setParams(const HoughGroundParams& params) { fitter_.setParams(params); }

bool HoughGround::classify(const LaserScanView& scan, const SensorPose& pose,
                           ScanGroundResult* out, std::string* error) {
  out->fit = GroundLineFit();
  if (!validateLaserScan(scan, error)) {
    out->classification.resize(0);
    out->r.clear();
    out->height.clear();
    return false;
  }
  const std::size_t n = scan.size;
  out->classification.resize(n);
  out->r.resize(n);
  out->height.resize(n);
  x_.resize(n);
  y_.resize(n);
  projector_.project(scan, x_.data(), y_.data());

  // The scan plane's horizontal direction u: perpendicular to the plane's normal (the sensor's
  // z axis) and to gravity, pointing forward.
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const Eigen::Vector3f t = pose.sensor_to_ground.translation();
  const Eigen::Vector3f normal = R.col(2);
  Eigen::Vector2f u(-normal.y(), normal.x());
  const float un = u.norm();
  out->signed_r = un > 0.866f;  // plane within 30 degrees of vertical
  if (out->signed_r) {
    u /= un;
    if (u.x() < -1e-6f || (std::fabs(u.x()) <= 1e-6f && u.y() < 0.f)) u = -u;
  } else {
    // Not a vertical scan: report the sensor's forward direction (for drawing the line).
    const Eigen::Vector2f fwd(R(0, 0), R(1, 0));
    u = fwd.norm() > 1e-6f ? Eigen::Vector2f(fwd.normalized()) : Eigen::Vector2f::UnitX();
  }
  out->direction = u;
  const Eigen::Vector3f ex = R.col(0), ey = R.col(1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t k = 0; k < n; ++k) {
    const float x = x_[k];
    if (!std::isfinite(x)) {
      out->r[k] = nan;
      out->height[k] = nan;
      continue;
    }
    const Eigen::Vector3f q = ex * x + ey * y_[k] + t;  // the return in the ground frame
    out->height[k] = q.z();
    out->r[k] = out->signed_r ? q.x() * u.x() + q.y() * u.y() : std::hypot(q.x(), q.y());
  }
  const int ni = static_cast<int>(n);
  out->fit = fitter_.fit(out->r.data(), out->height.data(), ni);
  classifyAgainstLine(out->fit, out->r.data(), out->height.data(), ni, params().tolerances,
                      out->classification.labels.data(), out->classification.p_obstacle.data(),
                      params().slope_error_min_distance);
  return true;
}

// --------------------------------------------------------------------------------------------
// The Hough fit per azimuth column of a 3D cloud.

namespace {

class HoughColumnsModel : public GroundModel {
 public:
  explicit HoughColumnsModel(const HoughColumnsParams& params) : params_(params), fitter_(params.fit) {
    const float width = std::min(360.f, std::max(0.1f, params_.column_width_deg));
    columns_ = std::max(1, static_cast<int>(std::lround(360.f / width)));
    inv_column_width_ = static_cast<float>(columns_) / (2.f * kPi);
  }
  std::string name() const override { return "hough"; }

  void classify(const PointCloudView& view, const SensorPose& pose,
                GroundClassification* out) override {
    const std::size_t n = view.size();
    out->resize(n);
    r_.resize(n);
    h_.resize(n);
    col_.resize(n);
    start_.assign(columns_ + 1, 0);
    const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
    const float sensor_z = pose.sensor_to_ground.translation().z();
    const RangeGate gate(params_.min_range, params_.max_range);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f p = view.xyz(i);
      out->labels[i] = kLabelUnknown;
      out->p_obstacle[i] = 0.f;
      if (!gate.admits(p)) {
        col_[i] = -1;
        continue;
      }
      const Eigen::Vector3f q = R * p;  // gravity aligned, sensor at (0, 0, sensor_z)
      r_[i] = std::hypot(q.x(), q.y());
      h_[i] = q.z() + sensor_z;
      int c = static_cast<int>((std::atan2(q.y(), q.x()) + kPi) * inv_column_width_);
      c = c < 0 ? 0 : (c >= columns_ ? columns_ - 1 : c);
      col_[i] = c;
      ++start_[c + 1];
    }
    // Counting sort of the valid points by column.
    for (int c = 0; c < columns_; ++c) start_[c + 1] += start_[c];
    order_.resize(start_[columns_]);
    fill_.assign(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      if (col_[i] >= 0) order_[fill_[col_[i]]++] = static_cast<uint32_t>(i);
    }
    for (int c = 0; c < columns_; ++c) {
      const int b = static_cast<int>(start_[c]), e = static_cast<int>(start_[c + 1]);
      const int m = e - b;
      if (m == 0) continue;
      cr_.resize(m);
      ch_.resize(m);
      cl_.resize(m);
      cp_.resize(m);
      for (int k = 0; k < m; ++k) {
        cr_[k] = r_[order_[b + k]];
        ch_[k] = h_[order_[b + k]];
      }
      const GroundLineFit fit = fitter_.fit(cr_.data(), ch_.data(), m);
      classifyAgainstLine(fit, cr_.data(), ch_.data(), m, params_.fit.tolerances, cl_.data(),
                          cp_.data(), fitter_.params().slope_error_min_distance);
      for (int k = 0; k < m; ++k) {
        out->labels[order_[b + k]] = cl_[k];
        out->p_obstacle[order_[b + k]] = cp_[k];
      }
    }
  }

 private:
  HoughColumnsParams params_;
  HoughLineFitter fitter_;
  int columns_ = 240;
  float inv_column_width_ = 1.f;
  std::vector<float> r_, h_, cr_, ch_, cp_;
  std::vector<int> col_;
  std::vector<uint32_t> start_, fill_, order_;
  std::vector<uint8_t> cl_;
};

}  // namespace

std::unique_ptr<GroundModel> makeHoughColumnsModel(const HoughColumnsParams& params) {
  return std::make_unique<HoughColumnsModel>(params);
}

}  // namespace ladar_perception
