// Analytic vertical scans for the Hough ground tests: a 2D ladar scanning the vertical (r, Height)
// plane from Height = sensor_height above the ground point under it, ray cast exactly onto line
// segments (ground lines, obstacle faces), so every return's truth is known.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace hough_test {

struct Segment {
  Eigen::Vector2d a, b;  // (r, Height) end points
  uint8_t truth;         // 0 ground, 1 obstacle
};

struct VerticalScene {
  double sensor_height = 1.5;
  double max_range = 80.0;
  std::vector<Segment> segments;

  void addGroundLine(double ground, double slope, double r0 = -200.0, double r1 = 200.0) {
    segments.push_back({{r0, ground + slope * r0}, {r1, ground + slope * r1}, 0});
  }
  // A box standing on flat ground at Height `base`: near face, top, far face.
  void addBox(double r_near, double r_far, double base, double height) {
    segments.push_back({{r_near, base}, {r_near, base + height}, 1});
    segments.push_back({{r_near, base + height}, {r_far, base + height}, 1});
    segments.push_back({{r_far, base}, {r_far, base + height}, 1});
  }
  void addWall(double r, double base, double height) {
    segments.push_back({{r, base}, {r, base + height}, 1});
  }

  // Range along the ray at elevation `angle` (radians, 0 = horizontal, -pi/2 = straight down,
  // pi = backwards), or +Inf when nothing is hit within max_range. *truth of the hit segment.
  double cast(double angle, uint8_t* truth) const {
    const Eigen::Vector2d o(0.0, sensor_height);
    const Eigen::Vector2d d(std::cos(angle), std::sin(angle));
    double best = std::numeric_limits<double>::infinity();
    for (const Segment& s : segments) {
      const Eigen::Vector2d e = s.b - s.a;
      const double den = d.x() * (-e.y()) - d.y() * (-e.x());
      if (std::fabs(den) < 1e-12) continue;
      const Eigen::Vector2d w = s.a - o;
      const double t = (w.x() * (-e.y()) - w.y() * (-e.x())) / den;
      const double u = (d.x() * w.y() - d.y() * w.x()) / den;
      if (t > 1e-9 && u >= 0.0 && u <= 1.0 && t < best) {
        best = t;
        if (truth) *truth = s.truth;
      }
    }
    return best <= max_range ? best : std::numeric_limits<double>::infinity();
  }

  // A scan from angle_min in steps of increment (radians): ranges and per-return truth
  // (2 = no return).
  void scan(double angle_min, double increment, int count, std::vector<float>* ranges,
            std::vector<uint8_t>* truth) const {
    ranges->resize(count);
    truth->resize(count);
    for (int k = 0; k < count; ++k) {
      uint8_t t = 2;
      const double range = cast(angle_min + k * increment, &t);
      (*ranges)[k] = static_cast<float>(range);
      (*truth)[k] = std::isfinite(range) ? t : 2;
    }
  }

  // The SICK LMS-291 in the vertical plane: 181 degrees... 361 returns at 0.5 degrees from
  // straight down (-90) to straight up (+90); r and Height of each return (NaN: no return).
  void pairs(std::vector<float>* r, std::vector<float>* h, std::vector<uint8_t>* truth,
             int count = 361, double angle_min = -M_PI / 2, double increment = M_PI / 360) const {
    std::vector<float> ranges;
    scan(angle_min, increment, count, &ranges, truth);
    r->resize(count);
    h->resize(count);
    for (int k = 0; k < count; ++k) {
      const double a = angle_min + k * increment;
      if (std::isfinite(ranges[k])) {
        (*r)[k] = static_cast<float>(ranges[k] * std::cos(a));
        (*h)[k] = static_cast<float>(sensor_height + ranges[k] * std::sin(a));
      } else {
        (*r)[k] = (*h)[k] = std::numeric_limits<float>::quiet_NaN();
      }
    }
  }
};

}  // namespace hough_test
