// The analog signal approach (thesis 3.2; algorithms.md).
#include "ladar_perception/ground/analog_signal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {

namespace {
constexpr float kPi = 3.14159265358979f;
constexpr uint32_t kNoBin = std::numeric_limits<uint32_t>::max();
constexpr int kMaxRows = 128;
}  // namespace

AnalogSignalGround::AnalogSignalGround(const AnalogSignalParams& params) : params_(params) {
  row_table_.build(params_.laser_elevations_deg.empty() ? hdl64eElevationsDeg()
                                                        : params_.laser_elevations_deg);
  const float width = std::min(90.f, std::max(0.5f, params_.sector_deg));
  sectors_per_row_ = std::max(4, static_cast<int>(std::lround(360.f / width)));
}

void AnalogSignalGround::classify(const PointCloudView& view, const SensorPose& pose,
                                  GroundClassification* out) {
  const std::size_t n = view.size();
  out->resize(n);
  r_.resize(n);
  z_.resize(n);
  s_.resize(n);
  theta_.resize(n);
  row_.resize(n);
  bin_.resize(n);
  const Eigen::Matrix3f R = pose.sensor_to_ground.linear();
  const float h = std::max(0.3f, pose.height());
  const float C = -1.f / h;  // the ground plane's C for ground below the sensor
  const int rows = view.hasRing() ? kMaxRows : row_table_.rows();
  const int S = sectors_per_row_;
  const float sectors_per_rad = static_cast<float>(S) / (2.f * kPi);
  const float min2 = params_.min_range * params_.min_range;
  const float max2 = params_.max_range * params_.max_range;
  const std::size_t nbins = static_cast<std::size_t>(rows) * S;
  start_.assign(nbins + 1, 0);

  // s(theta) = (1 - C z) / r per return (the point's own elevation, so no per-laser
  // calibration error), binned by laser row and azimuth sector.
  for (std::size_t i = 0; i < n; ++i) {
    out->labels[i] = kLabelUnknown;
    out->p_obstacle[i] = 0.f;
    bin_[i] = kNoBin;
    const Eigen::Vector3f p = view.xyz(i);
    const float d2 = p.squaredNorm();
    if (!std::isfinite(d2) || d2 < min2 || d2 > max2) continue;
    const Eigen::Vector3f q = R * p;  // gravity aligned, origin at the sensor
    const float r = std::hypot(q.x(), q.y());
    if (!(r > 0.05f)) continue;
    int row = view.hasRing() ? view.ring(i) : row_table_.row(q.z(), r);
    if (row < 0 || row >= rows) continue;
    const float theta = std::atan2(q.y(), q.x());
    int sector = static_cast<int>((theta + kPi) * sectors_per_rad);
    sector = sector < 0 ? 0 : (sector >= S ? S - 1 : sector);
    r_[i] = r;
    z_[i] = q.z();
    s_[i] = (1.f - C * q.z()) / r;
    theta_[i] = theta;
    row_[i] = row;
    bin_[i] = static_cast<uint32_t>(row * S + sector);
    ++start_[bin_[i] + 1];
  }
  for (std::size_t b = 0; b < nbins; ++b) start_[b + 1] += start_[b];
  order_.resize(start_[nbins]);
  fill_.assign(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (bin_[i] != kNoBin) order_[fill_[bin_[i]]++] = static_cast<uint32_t>(i);
  }

  // One value per (laser, sector): the median s (robust to the few obstacle returns of a
  // sector), with the r and z of that return.
  sectors_.clear();
  const float max_tan = std::tan(params_.max_fit_elevation_deg * kPi / 180.f);
  for (std::size_t b = 0; b < nbins; ++b) {
    const uint32_t lo = start_[b], hi = start_[b + 1];
    if (hi == lo) continue;
    scratch_.clear();
    for (uint32_t k = lo; k < hi; ++k) scratch_.emplace_back(s_[order_[k]], order_[k]);
    auto mid = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
    std::nth_element(scratch_.begin(), mid, scratch_.end());
    const uint32_t i = mid->second;
    if (z_[i] / r_[i] >= max_tan) continue;  // this laser does not look at the ground here
    const int sector = static_cast<int>(b) % S;
    // The first round starts from level ground at sensor_height (A = B = 0, no bias), as
    // Algorithm 1 is seeded: sectors whose median is more than initial_gate off it (walls that
    // fill a laser's view) wait until the model explains them.
    const bool near_level = std::fabs(h * r_[i] * mid->first) < params_.initial_gate;
    sectors_.push_back({static_cast<int>(b) / S, (static_cast<float>(sector) + 0.5f) / sectors_per_rad - kPi,
                        mid->first, r_[i], z_[i], near_level});
  }

  // Joint least squares for A, B and each laser's DC bias, the biases eliminated by centring
  // each laser's cos, sin and s on their means. Rounds drop sectors whose residual, as a height,
  // exceeds the threshold (obstacles that fill a sector).
  fit_.bias.assign(rows, 0.0);
  fit_.valid = false;
  fit_.a = fit_.b = 0.0;
  std::vector<double>& bias = fit_.bias;
  const float thr = params_.threshold > 0.f ? params_.threshold : 0.2f;
  std::vector<double> sum_c(rows), sum_s(rows), sum_v(rows), count(rows);
  for (int round = 0; round < std::max(1, params_.fit_rounds); ++round) {
    std::fill(sum_c.begin(), sum_c.end(), 0.0);
    std::fill(sum_s.begin(), sum_s.end(), 0.0);
    std::fill(sum_v.begin(), sum_v.end(), 0.0);
    std::fill(count.begin(), count.end(), 0.0);
    for (const Sector& sec : sectors_) {
      if (!sec.active) continue;
      sum_c[sec.row] += std::cos(sec.theta);
      sum_s[sec.row] += std::sin(sec.theta);
      sum_v[sec.row] += sec.s;
      count[sec.row] += 1.0;
    }
    double m00 = 0, m01 = 0, m11 = 0, v0 = 0, v1 = 0;
    int used = 0;
    for (const Sector& sec : sectors_) {
      if (!sec.active || count[sec.row] < 2) continue;
      const double cn = std::cos(sec.theta) - sum_c[sec.row] / count[sec.row];
      const double sn = std::sin(sec.theta) - sum_s[sec.row] / count[sec.row];
      const double vn = sec.s - sum_v[sec.row] / count[sec.row];
      m00 += cn * cn;
      m01 += cn * sn;
      m11 += sn * sn;
      v0 += cn * vn;
      v1 += sn * vn;
      ++used;
    }
    // A weak prior toward the seed (A = B = 0, level ground), worth kPriorSectors sectors: it
    // keeps a direction the sectors do not constrain (an alley seen only along its axis) level
    // instead of amplifying noise; with the ground seen all around it is negligible.
    constexpr double kPriorSectors = 4.0;
    m00 += kPriorSectors;
    m11 += kPriorSectors;
    const double det = m00 * m11 - m01 * m01;
    if (used < 3 || !(std::fabs(det) > 1e-12)) break;
    fit_.a = (m11 * v0 - m01 * v1) / det;
    fit_.b = (m00 * v1 - m01 * v0) / det;
    for (int l = 0; l < rows; ++l) {
      bias[l] = count[l] > 0 ? (sum_v[l] - fit_.a * sum_c[l] - fit_.b * sum_s[l]) / count[l] : 0.0;
    }
    fit_.valid = true;
    fit_.sectors = used;
    // Next round without the sectors the model does not explain.
    bool changed = false;
    for (Sector& sec : sectors_) {
      const double model = fit_.a * std::cos(sec.theta) + fit_.b * std::sin(sec.theta) + bias[sec.row];
      const bool inside = std::fabs(h * sec.r * (sec.s - model)) < thr;
      changed |= inside != sec.active;
      sec.active = inside;
    }
    if (!changed) break;
  }
  if (!fit_.valid) return;  // no ground signal: every return stays unknown

  // The obstacle signal of every return: what is left after removing the first harmonic and
  // the laser's DC bias, as a height above the fitted ground: h r (s - s_fit).
  for (std::size_t i = 0; i < n; ++i) {
    if (bin_[i] == kNoBin) continue;
    const double model = fit_.a * std::cos(theta_[i]) + fit_.b * std::sin(theta_[i]) + bias[row_[i]];
    const float height = static_cast<float>(h * r_[i] * (s_[i] - model));
    const float a = std::fabs(height);
    out->labels[i] = a < thr ? kLabelGround : kLabelObstacle;
    out->p_obstacle[i] = std::min(a / (2.f * thr), 1.f);
  }
}

}  // namespace ladar_perception
