// calibration_benchmark: the thesis's calibration experiment (5.2.1) on the simulator.
// (Over 600 lines: the experiment's statistics, its --diagnose report and the trace plot share
// the trials' state; the calibration itself is calibrate() of the core.)
// For each trial: 10 vehicle poses within 5 m and 0.5 rad, the reference sensor 2 m above the
// ground at the origin, the target 1 m forward, an initial guess off by up to +-1 m and +-0.2 rad
// per axis; then calibrate() with the chosen method. Prints per-DOF mean and standard deviation
// of the signed error, its mean and worst absolute value and the seconds per trial; --json
// writes the same (interfaces.md schema);
// --plot draws the convergence of each DOF per iteration (thesis Figures 5.3-5.8).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "ladar_perception/calibration/experiment.h"
#include "ladar_perception/io/image.h"

namespace cal = ladar_perception::calibration;
namespace sim = ladar_perception::sim;
using ladar_perception::RgbImage;

namespace {

// --drift: the drift monitor on a simulated drive (experiment.h runDriftDrive): every check,
// then the false alarms before the bump, the time to ERROR after it and the CPU per check.
int runDrift(const sim::World& world, const std::string& world_name, const cal::PairSetup& pair,
             const cal::DriftDriveOptions& options, uint64_t seed, bool quiet) {
  const cal::DriftMonitorParams params;
  std::printf("drift monitor: pair %s, world %s, %.0f s drive at %.1f m/s, scans every %.1f s, "
              "checks every %.1f s, window %.0f s, seed %llu",
              pair.name.c_str(), world_name.c_str(), options.duration, options.speed,
              options.scan_interval, options.check_interval, params.window,
              static_cast<unsigned long long>(seed));
  if (options.bump_time >= 0) {
    std::printf(", bump at %.0f s: %g %g %g m, %g %g %g rad", options.bump_time, options.bump[0],
                options.bump[1], options.bump[2], options.bump[3], options.bump[4], options.bump[5]);
  }
  std::printf("\n");
  cal::DriftDriveResult result;
  std::string error;
  const bool ok = cal::runDriftDrive(
      world, pair, params, options, seed, &result, &error, [quiet](const cal::DriftCheck& c) {
        if (quiet) return;
        const cal::DriftEstimate& e = c.estimate;
        std::printf("t %6.1f s %-7s offset x %+.4f y %+.4f z %+.4f m, roll %+.5f pitch %+.5f yaw "
                    "%+.5f rad, cpu %.2f s; %s\n",
                    c.time, cal::driftLevelName(e.level), e.offset[0], e.offset[1], e.offset[2],
                    e.offset[3], e.offset[4], e.offset[5], e.cpu_time, e.message.c_str());
        std::fflush(stdout);
      });
  if (!ok) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  double worst_t = 0, worst_r = 0;  // the largest offsets before the bump
  for (const cal::DriftCheck& c : result.checks) {
    if (options.bump_time >= 0 && c.time >= options.bump_time) continue;
    if (!c.estimate.estimated) continue;
    worst_t = std::max(worst_t, c.estimate.offset.head<3>().cwiseAbs().maxCoeff());
    worst_r = std::max(worst_r, c.estimate.offset.tail<3>().cwiseAbs().maxCoeff());
  }
  std::printf("checks %zu; before the bump: %d WARN, %d ERROR, largest offset %.4f m and %.5f rad",
              result.checks.size(), result.warn_before, result.error_before, worst_t, worst_r);
  if (options.bump_time >= 0) {
    if (result.detected_after >= 0) {
      std::printf("; ERROR %.0f s after the bump", result.detected_after);
    } else {
      std::printf("; the bump never reached ERROR");
    }
  }
  std::printf("\nCPU per check: mean %.2f s, max %.2f s (%.1f%% of one core at a check every %.0f s)\n",
              result.mean_check_cpu, result.max_check_cpu,
              100.0 * result.mean_check_cpu / options.check_interval, options.check_interval);
  return 0;
}

// --network: the thesis vehicle's sensors calibrated as one network against its Velodyne
// (network.h): per trial and sensor the pairwise and the joint errors and the loops' closure;
// then per sensor the worst errors and the trials within 5 cm and 0.01 rad per axis, both ways.
int runNetwork(const sim::World& world, const std::string& world_name,
               const cal::ExperimentOptions& options, const cal::NetworkParams& params,
               int trials, uint64_t seed, const std::string& json_path, bool quiet) {
  const cal::NetworkSetup network = cal::thesisVehicleNetwork();
  const std::size_t n = network.targets.size();
  std::printf("network %s: reference %s, targets", network.name.c_str(),
              network.reference_name.c_str());
  for (const std::string& t : network.target_names) std::printf(" %s", t.c_str());
  std::printf("; world %s, trajectory %s, %d trials, seed %llu, cross pairs %s\n",
              world_name.c_str(), options.trajectory.c_str(), trials,
              static_cast<unsigned long long>(seed), params.cross_pairs ? "all" : "none");
  // Per sensor: worst |error| per DOF and the trials within 5 cm / 0.01 rad, pairwise and joint.
  std::vector<cal::Pose6> worst_pair(n, cal::Pose6::Zero()), worst_joint(n, cal::Pose6::Zero());
  std::vector<int> within_pair(n, 0), within_joint(n, 0), claimed_joint(n, 0), false_joint(n, 0);
  std::vector<double> cpu;
  double worst_loop_t = 0, worst_loop_r = 0;
  const auto within = [](const cal::Pose6& e) {
    return e.head<3>().cwiseAbs().maxCoeff() <= 0.05 && e.tail<3>().cwiseAbs().maxCoeff() <= 0.01;
  };
  for (int t = 0; t < trials; ++t) {
    cal::NetworkTrial trial;
    std::string error;
    if (!cal::makeNetworkTrial(world, network, options, seed * 1000003ULL + t, &trial, &error)) {
      std::cerr << "trial " << t << ": simulation failed: " << error << "\n";
      return 1;
    }
    cal::NetworkParams p = params;
    p.calibration.search.seed = seed * 7919ULL + t;
    const cal::NetworkResult r = cal::calibrateNetwork(trial.input, p);
    cpu.push_back(r.cpu_time);
    std::printf("trial %d: %s (cpu %.1f s)\n", t, r.message.c_str(), r.cpu_time);
    for (std::size_t k = 0; k < n; ++k) {
      const cal::NetworkSensorResult& s = r.sensors[k];
      const cal::Pose6 ep = cal::poseDifference(s.pairwise, trial.truth[k]);
      const cal::Pose6 ej = cal::poseDifference(s.joint, trial.truth[k]);
      for (int d = 0; d < 6; ++d) {
        if (s.pairwise_success) worst_pair[k][d] = std::max(worst_pair[k][d], std::abs(ep[d]));
        if (s.success) worst_joint[k][d] = std::max(worst_joint[k][d], std::abs(ej[d]));
      }
      within_pair[k] += s.pairwise_success && within(ep);
      within_joint[k] += s.success && within(ej);
      claimed_joint[k] += s.success;
      false_joint[k] += s.success && !within(ej);
      if (!quiet) {
        std::printf("  %-12s pairwise %s err %+.4f %+.4f %+.4f m %+.5f %+.5f %+.5f rad | joint %s "
                    "err %+.4f %+.4f %+.4f m %+.5f %+.5f %+.5f rad\n",
                    s.name.c_str(), s.pairwise_success ? "ok  " : "FAIL", ep[0], ep[1], ep[2],
                    ep[3], ep[4], ep[5], s.success ? "ok  " : "FAIL", ej[0], ej[1], ej[2], ej[3],
                    ej[4], ej[5]);
      }
    }
    for (const cal::NetworkEdge& e : r.edges) {
      if (e.from < 0) continue;
      if (e.used) {
        worst_loop_t = std::max(worst_loop_t, e.loop_translation);
        worst_loop_r = std::max(worst_loop_r, e.loop_rotation);
      }
      if (!quiet) {
        std::printf("  loop %s <- %s: %s, closure %.4f m %.5f rad, joint residual %.4f m %.5f rad\n",
                    r.sensors[e.to].name.c_str(), r.sensors[e.from].name.c_str(),
                    e.result.success ? "success" : (e.used ? "partial" : "not used"),
                    e.loop_translation, e.loop_rotation, e.residual_translation,
                    e.residual_rotation);
      }
    }
    std::fflush(stdout);
  }
  std::printf("\n%-12s %-8s %9s %9s %9s %9s %9s %9s  %s\n", "sensor", "solution", "x [m]", "y [m]",
              "z [m]", "roll", "pitch", "yaw", "within 5 cm, 0.01 rad (claimed, claimed but off)");
  for (std::size_t k = 0; k < n; ++k) {
    for (int joint = 0; joint < 2; ++joint) {
      const cal::Pose6& w = joint ? worst_joint[k] : worst_pair[k];
      std::printf("%-12s %-8s %9.4f %9.4f %9.4f %9.5f %9.5f %9.5f  %d/%d", network.target_names[k].c_str(),
                  joint ? "joint" : "pairwise", w[0], w[1], w[2], w[3], w[4], w[5],
                  joint ? within_joint[k] : within_pair[k], trials);
      if (joint) std::printf(" (%d, %d)", claimed_joint[k], false_joint[k]);
      std::printf("\n");
    }
  }
  std::sort(cpu.begin(), cpu.end());
  std::printf("worst loop closure %.4f m %.5f rad; CPU per network median %.1f s, max %.1f s\n",
              worst_loop_t, worst_loop_r, cpu[cpu.size() / 2], cpu.back());
  if (!json_path.empty()) {
    std::ofstream j(json_path);
    j << "{\"network\": \"" << network.name << "\", \"world\": \"" << world_name
      << "\", \"trials\": " << trials << ", \"sensors\": {";
    for (std::size_t k = 0; k < n; ++k) {
      j << (k ? ", " : "") << "\"" << network.target_names[k] << "\": {";
      for (int joint = 0; joint < 2; ++joint) {
        const cal::Pose6& w = joint ? worst_joint[k] : worst_pair[k];
        j << (joint ? ", \"joint\"" : "\"pairwise\"") << ": {\"worst\": [";
        for (int d = 0; d < 6; ++d) j << (d ? ", " : "") << w[d];
        j << "], \"within\": " << (joint ? within_joint[k] : within_pair[k]) << "}";
      }
      j << "}";
    }
    j << "}, \"cpu_seconds\": {\"median\": " << cpu[cpu.size() / 2] << ", \"max\": " << cpu.back()
      << "}}\n";
  }
  return 0;
}

std::string fmt1(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.1f", v);
  return b;
}

void usage() {
  std::cerr
      << "usage: calibration_benchmark [--pair velodyne-velodyne|sick-velodyne|sick-sick|"
         "stereo-velodyne|velodyne-stereo]\n"
         "         [--method NAME] [--trials N] [--seed S] [--world NAME] [--json OUT]\n"
         "         [--plot OUT.png] [--noise table4.1|datasheet|none] [--reference-noise NAME]\n"
         "         [--poses N]\n"
         "         [--bin M] [--repeatability W] [--centre X,Y] [--disk] [--probe M] [--quiet]\n"
         "         [--drive-speed M_PER_S] [--sparse-noise-floor M] [--diagnose] [--only T]\n"
         "--set NAME=VALUE: a refinement or sweep parameter (experiments): max_target_points,\n"
         "  target_voxel, reference_voxel, huber, normal_neighbours, max_correspondence_end,\n"
         "  max_iterations, plane_sweep_iterations, plane_sweep_passes, plane_sweep_coarse_points,\n"
         "  plane_sweep_fine_points, plane_sweep_fine_iterations, sparse_extrapolation_steps,\n"
         "  sparse_final_iterations, plane_sweep_polish_step, plane_sweep_polish_min_rise,\n"
         "  plane_sweep_flat_rise, coarse_restarts, plane_sweep_consistency,\n"
         "  sparse_level_keep_every, sparse_level_normal_z, sparse_level_extrapolation_steps,\n"
         "  score_cluster, symmetric_refinement, noise_floor, range_noise, range_noise_per_m2,\n"
         "  reference_noise\n"
         "--reference-noise NAME: the reference sensor's noise profile instead of --noise's (the\n"
         "  same random streams: only that sensor's noise differs)\n"
         "--only T: run trial T alone (0-based; the same data and seeds as in the full run)\n"
         "--drive-speed: the vehicle's speed between poses; a 2D ladar and a stereo camera scan\n"
         "  at their own rate along the way (default 2 m/s; 0 = 20 scans per segment)\n"
         "--stereo-at-poses: the stereo camera frames once per pose only (the thesis's set-up)\n"
         "--network thesis-vehicle [--no-cross-pairs]: the thesis vehicle's LMS-291s (ahead,\n"
         "  behind) and stereo camera calibrated as one network against its HDL-64E, pairwise\n"
         "  and joint errors per sensor and the loops' closure (with --trials, --seed, --world,\n"
         "  --trajectory, --noise, --json)\n"
         "--drift [--duration S] [--bump x,y,z,roll,pitch,yaw --bump-at T]: the drift monitor\n"
         "  on a drive back and forth along the world's drive (a 3D pair), checks every 4 s; prints\n"
         "  the false alarms before the bump, the time to ERROR after it, the CPU per check\n"
         "--trajectory thesis|turns|hill: random poses around the centre (the thesis's), or a slalom\n"
         "  of +-2 m, 20 m wavelength, along the world's standard drive; hill: that slalom on the\n"
         "  hillside world (unless --world), turns and grade changes\n"
         "--sparse-noise-floor: 2D targets' residual weighting by the reference's local noise\n"
         "  (default 0.02 m, 0 = off)\n"
         "--sparse-range-noise M, --sparse-reference-noise M: that weighting's target range noise\n"
         "  (default 0.1 m, 0 = the reference spread alone) and reference plane floor (0.0025 m)\n"
         "--diagnose: per trial, the target's scans and points, the share of its points on\n"
         "  objects (> 0.3 m above the ground at the truth), the 2D ground-line sweep's costs and\n"
         "  the point-to-plane Hessian's eigenvalues and weakest eigenvectors at the truth and at\n"
         "  the solution\n"
         "methods:";
  for (const std::string& m : cal::methodNames()) std::cerr << " " << m;
  std::cerr << " (default " << cal::defaultMethod() << ")\n";
}

// Per-DOF statistics of the signed errors over the trials: mean and standard deviation (the
// thesis's figures, 5.2.1: "mean within 2 cm, standard deviation under 10 cm"), and the mean and
// worst absolute error.
struct DofStats {
  double mean = 0, std = 0, mean_abs = 0, worst = 0;
};

DofStats stats(const std::vector<double>& v) {  // v: the signed errors
  DofStats s;
  if (v.empty()) return s;
  for (double x : v) {
    s.mean += x;
    s.mean_abs += std::abs(x);
    s.worst = std::max(s.worst, std::abs(x));
  }
  s.mean /= v.size();
  s.mean_abs /= v.size();
  for (double x : v) s.std += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(s.std / (v.size() - 1)) : 0.0;
  return s;
}

void printStats(const std::vector<std::vector<double>>& errors, std::vector<DofStats>* out = nullptr) {
  std::printf("%-6s %12s %12s %12s %12s\n", "dof", "mean", "std", "mean |err|", "worst |err|");
  for (int d = 0; d < 6; ++d) {
    const DofStats s = stats(errors[d]);
    std::printf("%-6s %+12.5f %12.5f %12.5f %12.5f %s\n", cal::dofName(d), s.mean, s.std, s.mean_abs, s.worst,
                d < 3 ? "m" : "rad");
    if (out) out->push_back(s);
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A small line plotter: 2 x 3 panels (x, y, z on top; roll, pitch, yaw below), one line per
// trial, the signed error of the DOF's estimate after each iteration; the grey line is zero
// error, the panel's vertical range is +-1 m (translation) or +-0.2 rad (rotation), the initial
// guess's range, with light lines at +-10 % of it.
void drawLine(RgbImage* img, int x0, int y0, int x1, int y1, const uint8_t c[3]) {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  while (true) {
    img->set(x0, y0, c[0], c[1], c[2]);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) { err += dy; x0 += sx; }
    if (e2 <= dx) { err += dx; y0 += sy; }
  }
}

bool writePlot(const std::string& path, const std::vector<std::vector<cal::Pose6>>& traces,
               const cal::Pose6& range, std::string* error) {
  const int pw = 360, ph = 220, margin = 12;
  RgbImage img(3 * pw + 4 * margin, 2 * ph + 3 * margin, 255, 255, 255);
  std::size_t longest = 1;
  for (const auto& t : traces) longest = std::max(longest, t.size());
  const uint8_t grey[3] = {150, 150, 150}, light[3] = {220, 220, 220}, black[3] = {0, 0, 0};
  for (int d = 0; d < 6; ++d) {
    const int ox = margin + (d % 3) * (pw + margin), oy = margin + (d / 3) * (ph + margin);
    const auto ypix = [&](double e) {
      const double f = std::max(-1.0, std::min(1.0, e / range[d]));
      return oy + static_cast<int>(std::lround((1.0 - f) * 0.5 * (ph - 1)));
    };
    drawLine(&img, ox, ypix(0.1 * range[d]), ox + pw - 1, ypix(0.1 * range[d]), light);
    drawLine(&img, ox, ypix(-0.1 * range[d]), ox + pw - 1, ypix(-0.1 * range[d]), light);
    drawLine(&img, ox, ypix(0), ox + pw - 1, ypix(0), grey);
    drawLine(&img, ox, oy, ox + pw - 1, oy, black);
    drawLine(&img, ox, oy + ph - 1, ox + pw - 1, oy + ph - 1, black);
    drawLine(&img, ox, oy, ox, oy + ph - 1, black);
    drawLine(&img, ox + pw - 1, oy, ox + pw - 1, oy + ph - 1, black);
    for (std::size_t t = 0; t < traces.size(); ++t) {
      uint8_t c[3];
      const double hue = 6.0 * t / std::max<std::size_t>(1, traces.size());
      const int sector = static_cast<int>(hue) % 6;
      const double f = hue - std::floor(hue);
      const uint8_t up = static_cast<uint8_t>(200 * f), down = static_cast<uint8_t>(200 * (1 - f));
      const uint8_t table[6][3] = {{200, up, 0}, {down, 200, 0}, {0, 200, up},
                                   {0, down, 200}, {up, 0, 200}, {200, 0, down}};
      std::copy(table[sector], table[sector] + 3, c);
      const auto& tr = traces[t];
      for (std::size_t i = 1; i < tr.size(); ++i) {
        const int xa = ox + static_cast<int>((i - 1) * (pw - 1) / std::max<std::size_t>(1, longest - 1));
        const int xb = ox + static_cast<int>(i * (pw - 1) / std::max<std::size_t>(1, longest - 1));
        drawLine(&img, xa, ypix(tr[i - 1][d]), xb, ypix(tr[i][d]), c);
      }
    }
  }
  return ladar_perception::writePng(path, img, error);
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

// Hessian of the robust point-to-plane cost (refinement.h) at a hypothesis: eigenvalues per
// correspondence (x, y, z in m^-2... unscaled: rotations in rad) and the three weakest directions.
void printHessian(const char* where, const cal::SurfaceModel& model, const cal::ScanSet& target,
                  const cal::Pose6& pose, const cal::CalibrationParams& params) {
  const cal::Linearisation lin = cal::linearise(model, target, pose,
                                                params.refinement.max_correspondence_end,
                                                params.refinement.huber);
  if (lin.correspondences <= 0) {
    std::printf("          %s: no correspondences\n", where);
    return;
  }
  Eigen::SelfAdjointEigenSolver<cal::Matrix6> es(lin.hessian / lin.correspondences);
  std::printf("          %s: %ld correspondences of %zu points, robust cost over all %.5f, "
              "Hessian eigenvalues per correspondence (m, rad):",
              where, lin.correspondences, target.numPoints(),
              cal::sparseTargetCost(lin, target.numPoints(), params.refinement));
  for (int i = 0; i < 6; ++i) std::printf(" %.3g", es.eigenvalues()[i]);
  std::printf("\n");
  for (int k = 0; k < 3; ++k) {
    std::printf("            eigenvector %d (x y z roll pitch yaw):", k);
    for (int i = 0; i < 6; ++i) std::printf(" %+.3f", es.eigenvectors()(i, k));
    std::printf("\n");
  }
}

void printDiagnosis(const cal::ExperimentTrial& trial, const cal::CalibrationParams& params,
                    const cal::CalibrationResult& r) {
  const cal::ScanSet& t = trial.input.target;
  cal::PointVector at_truth;
  cal::accumulate(t, cal::toIsometry(trial.truth), &at_truth);
  long objects = 0;
  for (std::size_t i = 0; i < at_truth.size(); ++i) {
    // Height above the ground under the vehicle of the point's scan (flat-ish worlds).
    std::size_t k = std::upper_bound(t.scan_begin.begin(), t.scan_begin.end(),
                                     static_cast<uint32_t>(i)) - t.scan_begin.begin() - 1;
    if (at_truth[i].z() - t.vehicle_poses[k].translation().z() > 0.3) ++objects;
  }
  std::printf("          target: %zu scans, %zu points (%.1f per scan), %.1f %% on objects at the "
              "truth; reference: %zu scans, %zu points\n",
              t.numScans(), t.numPoints(), t.numPoints() / std::max<double>(1, t.numScans()),
              100.0 * objects / std::max<std::size_t>(1, at_truth.size()),
              trial.input.reference.numScans(), trial.input.reference.numPoints());
  const cal::Pose6 coarse = cal::poseDifference(r.search.best, trial.truth);
  std::printf("          coarse search (%d iterations) error: x %+.3f y %+.3f z %+.3f m, roll %+.4f "
              "pitch %+.4f yaw %+.4f rad, cost %.5f\n",
              r.search.iterations, coarse[0], coarse[1], coarse[2], coarse[3], coarse[4], coarse[5],
              r.search.best_cost);
  if (!r.plane_sweep.empty()) {
    std::printf("          ground-line sweep (rotation rad: cost):");
    for (const auto& c : r.plane_sweep) std::printf(" %+.2f:%.5f", c.first, c.second);
    std::printf("\n");
    if (r.search.trace.size() < r.trace.size()) {
      const cal::Pose6 swept = cal::poseDifference(r.trace[r.search.trace.size()], trial.truth);
      std::printf("          final refinement: %d iterations, %s\n", r.refinement.iterations,
                  r.refinement.converged ? "converged" : "not converged");
      std::printf("          final refinement's x, y error per iteration:");
      for (const cal::Pose6& p : r.refinement.trace) {
        const cal::Pose6 e = cal::poseDifference(p, trial.truth);
        std::printf(" %+.3f,%+.3f", e[0], e[1]);
      }
      std::printf("\n");
      std::printf("          after the sweep error: x %+.3f y %+.3f z %+.3f m, roll %+.4f "
                  "pitch %+.4f yaw %+.4f rad\n",
                  swept[0], swept[1], swept[2], swept[3], swept[4], swept[5]);
    }
  }
  cal::PointVector reference;
  cal::accumulate(trial.input.reference, trial.input.reference_extrinsic, &reference);
  reference = cal::voxelDownsample(reference, params.refinement.reference_voxel);
  cal::SurfaceModel model;
  model.build(reference, params.refinement);
  const cal::ScanSet target = cal::refinementTarget(t, params.refinement);
  printHessian("at the truth", model, target, trial.truth, params);
  printHessian("at the solution", model, target, r.extrinsic, params);
  // The calibrator's own costs (its 2D-target weighting): the final refinement's and the sweep's.
  cal::RefinementParams final_rp = params.refinement;
  if (cal::isSparseTarget(t, params)) {
    final_rp.keep_edges = params.sparse_keep_edges || final_rp.keep_edges;
    if (params.sparse_noise_floor > 0) final_rp.noise_floor = params.sparse_noise_floor;
    cal::SurfaceModel sparse_model;
    sparse_model.build(reference, final_rp);
    cal::RefinementParams scored = final_rp;
    scored.range_noise = params.sparse_range_noise;
    scored.reference_noise = params.sparse_reference_noise;
    const double end = final_rp.max_correspondence_end;
    const auto costs = [&](const cal::Pose6& p, double* c_final, double* c_scored) {
      *c_final = cal::sparseTargetCost(cal::linearise(sparse_model, target, p, end, final_rp),
                                       target.numPoints(), final_rp);
      *c_scored = cal::sparseTargetCost(cal::linearise(sparse_model, target, p, end, scored),
                                        target.numPoints(), scored);
    };
    double ft, st, fs, ss;
    costs(trial.truth, &ft, &st);
    costs(r.extrinsic, &fs, &ss);
    std::printf("          calibrator's costs (final refinement's weighting / sweep's): at the truth "
                "%.6f / %.6f, at the solution %.6f / %.6f\n", ft, st, fs, ss);
    // The truth refined with given settings: where that cost's minimum lies.
    const auto from_truth = [&](const char* label, const cal::RefinementParams& with) {
      const cal::Pose6 e = cal::poseDifference(
          cal::refine(sparse_model, target, trial.truth, with).extrinsic, trial.truth);
      std::printf("          %s: x %+.3f y %+.3f z %+.3f m, roll %+.4f pitch %+.4f yaw %+.4f rad\n",
                  label, e[0], e[1], e[2], e[3], e[4], e[5]);
    };
    cal::RefinementParams rp = final_rp;
    rp.max_correspondence_start = rp.max_correspondence_end;
    from_truth("final refinement started at the truth ends at error", rp);
    if (cal::groundLineStepDirection(trial.truth, params.ground_z, &rp.frozen_direction)) {
      from_truth("same with the ground-line rotation held (as after the sweep)", rp);
    }
    {
      // The sweep's score along the family through the truth, each member fully refined
      // (30 iterations) with its rotation held: where the score itself puts the minimum.
      std::printf("          sweep score along the family at the truth, members refined fully:");
      std::vector<double> as, cs;
      for (double a = -0.008; a <= 0.00801; a += 0.004) {
        cal::Pose6 start;
        if (!cal::rotateAboutGroundLine(trial.truth, a, params.ground_z, &start)) continue;
        cal::RefinementParams hp = final_rp;
        hp.max_correspondence_start = hp.max_correspondence_end;
        if (!cal::groundLineStepDirection(start, params.ground_z, &hp.frozen_direction)) continue;
        const cal::Pose6 refined = cal::refine(sparse_model, target, start, hp).extrinsic;
        const double c = cal::sparseTargetCost(cal::linearise(sparse_model, target, refined, end, scored),
                                               target.numPoints(), scored);
        const cal::Pose6 e = cal::poseDifference(refined, trial.truth);
        std::printf(" %+.3f:%.6f(x%+.3f,y%+.3f)", a, c, e[0], e[1]);
        as.push_back(a);
        cs.push_back(c);
      }
      if (as.size() == 5) {  // least-squares parabola
        Eigen::Matrix<double, 5, 3> m;
        Eigen::Matrix<double, 5, 1> b;
        for (int i = 0; i < 5; ++i) { m(i, 0) = as[i] * as[i]; m(i, 1) = as[i]; m(i, 2) = 1; b[i] = cs[i]; }
        const Eigen::Vector3d q = m.colPivHouseholderQr().solve(b);
        std::printf("; parabola minimum %+.4f", q[0] > 0 ? -q[1] / (2 * q[0]) : NAN);
      }
      std::printf("\n");
    }
    rp = scored;
    rp.max_correspondence_start = rp.max_correspondence_end;
    from_truth("same with the sweep's weighting ends at error", rp);
  }
  std::printf("          observability at the solution: scaled eigenvalues");
  for (int i = 0; i < 6; ++i) std::printf(" %.3g", r.observability.eigenvalues[i]);
  std::printf("; stddev");
  for (int i = 0; i < 6; ++i) std::printf(" %.3g", r.stddev[i]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string pair_name = "velodyne-velodyne", method = cal::defaultMethod(), world_name = "thesis";
  bool world_given = false;
  std::string json_path, plot_path, noise_name = "table4.1", reference_noise_name;
  int trials = 10, poses = 10, windows = 0, only = -1;
  uint64_t seed = 1;
  double bin = -1, probe = -1, centre_x = 0, centre_y = 0;
  bool centre_given = false, corridor_given = false;
  bool quiet = false, diagnose = false;
  std::vector<std::pair<std::string, double>> settings;
  double drive_speed = cal::ExperimentOptions().drive_speed;
  bool stereo_at_poses = false;
  bool drift = false;
  std::string network_name;
  bool cross_pairs = true;
  cal::DriftDriveOptions drift_options;
  std::string trajectory = "thesis";
  double sparse_noise_floor = cal::CalibrationParams().sparse_noise_floor;
  double sparse_range_noise = cal::CalibrationParams().sparse_range_noise;
  double sparse_reference_noise = cal::CalibrationParams().sparse_reference_noise;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "missing value for " << name << "\n";
        usage();
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--pair") pair_name = value("--pair");
      else if (a == "--method") method = value("--method");
      else if (a == "--trials") trials = std::stoi(value("--trials"));
      else if (a == "--seed") seed = std::stoull(value("--seed"));
      else if (a == "--world") { world_name = value("--world"); world_given = true; }
      else if (a == "--json") json_path = value("--json");
      else if (a == "--plot") plot_path = value("--plot");
      else if (a == "--noise") noise_name = value("--noise");
      else if (a == "--reference-noise") reference_noise_name = value("--reference-noise");
      else if (a == "--poses") poses = std::stoi(value("--poses"));
      else if (a == "--bin") bin = std::stod(value("--bin"));
      else if (a == "--repeatability") windows = std::stoi(value("--repeatability"));
      else if (a == "--quiet") quiet = true;
      else if (a == "--diagnose") diagnose = true;
      else if (a == "--only") only = std::stoi(value("--only"));
      else if (a == "--set") {
        const std::string v = value("--set");
        const std::size_t eq = v.find('=');
        if (eq == std::string::npos) throw std::invalid_argument("set");
        settings.emplace_back(v.substr(0, eq), std::stod(v.substr(eq + 1)));
      }
      else if (a == "--drive-speed") drive_speed = std::stod(value("--drive-speed"));
      else if (a == "--stereo-at-poses") stereo_at_poses = true;
      else if (a == "--trajectory") trajectory = value("--trajectory");
      else if (a == "--sparse-noise-floor") sparse_noise_floor = std::stod(value("--sparse-noise-floor"));
      else if (a == "--sparse-range-noise") sparse_range_noise = std::stod(value("--sparse-range-noise"));
      else if (a == "--sparse-reference-noise") sparse_reference_noise = std::stod(value("--sparse-reference-noise"));
      else if (a == "--disk") corridor_given = true;  // the thesis's disk of poses on any world
      else if (a == "--drift") drift = true;
      else if (a == "--network") network_name = value("--network");
      else if (a == "--no-cross-pairs") cross_pairs = false;
      else if (a == "--duration") drift_options.duration = std::stod(value("--duration"));
      else if (a == "--bump-at") drift_options.bump_time = std::stod(value("--bump-at"));
      else if (a == "--bump") {
        std::stringstream ss(value("--bump"));
        std::string item;
        int k = 0;
        while (std::getline(ss, item, ',')) {
          if (k >= 6) throw std::invalid_argument("bump");
          drift_options.bump[k++] = std::stod(item);
        }
        if (k != 6) throw std::invalid_argument("bump");
      }
      else if (a == "--centre") {
        const std::string v = value("--centre");
        const std::size_t comma = v.find(',');
        if (comma == std::string::npos) throw std::invalid_argument("centre");
        centre_x = std::stod(v.substr(0, comma));
        centre_y = std::stod(v.substr(comma + 1));
        centre_given = true;
      }
      else if (a == "--probe") probe = std::stod(value("--probe"));
      else if (a == "-h" || a == "--help") { usage(); return 0; }
      else { std::cerr << "unknown argument " << a << "\n"; usage(); return 2; }
    } catch (const std::exception&) {
      std::cerr << "bad number for " << a << "\n";
      return 2;
    }
  }
  if (method == "default" || method.empty()) method = cal::defaultMethod();
  if (!cal::isMethod(method)) {
    std::cerr << "unknown method '" << method << "'\n";
    usage();
    return 2;
  }
  if (only >= trials) {
    std::cerr << "--only must be below --trials\n";
    return 2;
  }
  if (trials < 1 || poses < 1) {
    std::cerr << "--trials and --poses must be at least 1\n";
    return 2;
  }
  std::string error;
  cal::PairSetup pair;
  if (!cal::pairFromName(pair_name, &pair, &error)) {
    std::cerr << error << "\n";
    return 2;
  }
  cal::ExperimentOptions options;
  options.poses = poses;
  options.drive_speed = drive_speed;
  options.stereo_while_driving = !stereo_at_poses;
  // "hill": the slalom on the hillside world, whose drive climbs and falls over its slopes:
  // turns and grade changes, so that the vehicle's motion excites every axis of a 2D pair.
  if (trajectory == "hill") {
    trajectory = "turns";
    if (!world_given) world_name = "hillside";
  }
  options.trajectory = trajectory;
  // The alley (walls at y = +-3.2 from x = -60 to 160) is driven along, not turned in: poses
  // within +-5 m along x around its middle, +-0.5 m across, yaw +-0.02 rad. (With the thesis's
  // +-0.5 rad of yaw the walls would fix the extrinsic's x through the turning: see the report.)
  if (world_name == "alley" && !corridor_given) {
    if (!centre_given) centre_x = 50.0;
    options.max_lateral = 0.5;
    options.max_yaw = 0.02;
  }
  options.centre_x = centre_x;
  options.centre_y = centre_y;
  if (!sim::noiseProfileFromName(noise_name, &options.noise)) {
    std::cerr << "unknown noise profile '" << noise_name << "'\n";
    return 2;
  }
  if (!reference_noise_name.empty()) {
    options.reference_noise_set = true;
    if (!sim::noiseProfileFromName(reference_noise_name, &options.reference_noise)) {
      std::cerr << "unknown noise profile '" << reference_noise_name << "'\n";
      return 2;
    }
  }
  sim::World world;
  if (!sim::makeStandardWorld(world_name, static_cast<uint32_t>(seed), &world, &error)) {
    std::cerr << error << "\n";
    return 2;
  }
  if (drift) {
    drift_options.noise = options.noise;
    return runDrift(world, world_name, pair, drift_options, seed, quiet);
  }
  if (!network_name.empty()) {
    if (network_name != "thesis-vehicle") {
      std::cerr << "unknown network '" << network_name << "' (networks: thesis-vehicle)\n";
      return 2;
    }
    cal::NetworkParams network_params;
    network_params.cross_pairs = cross_pairs;
    network_params.calibration.method = method;
    return runNetwork(world, world_name, options, network_params, trials, seed, json_path, quiet);
  }
  cal::CalibrationParams params =
      method == "particle_filter" ? cal::thesisParticleFilterParams() : cal::CalibrationParams();
  params.method = method;
  params.spread = options.guess_offset;
  if (bin > 0) params.bin_size = bin;
  if (probe > 0) params.observability.probe = probe;
  params.sparse_noise_floor = sparse_noise_floor;
  params.sparse_range_noise = sparse_range_noise;
  params.sparse_reference_noise = sparse_reference_noise;
  cal::adaptParamsToPair(pair, &params);
  for (const auto& kv : settings) {
    const std::string& k = kv.first;
    const double v = kv.second;
    if (k == "max_target_points") params.refinement.max_target_points = static_cast<int>(v);
    else if (k == "target_voxel") params.refinement.target_voxel = v;
    else if (k == "reference_voxel") params.refinement.reference_voxel = v;
    else if (k == "huber") params.refinement.huber = v;
    else if (k == "normal_neighbours") params.refinement.normal_neighbours = static_cast<int>(v);
    else if (k == "max_correspondence_end") params.refinement.max_correspondence_end = v;
    else if (k == "max_iterations") params.refinement.max_iterations = static_cast<int>(v);
    else if (k == "plane_sweep_iterations") params.plane_sweep_iterations = static_cast<int>(v);
    else if (k == "plane_sweep_passes") params.plane_sweep_passes = static_cast<int>(v);
    else if (k == "plane_sweep_coarse_points") params.plane_sweep_coarse_points = static_cast<int>(v);
    else if (k == "plane_sweep_fine_points") params.plane_sweep_fine_points = static_cast<int>(v);
    else if (k == "plane_sweep_fine_iterations") params.plane_sweep_fine_iterations = static_cast<int>(v);
    else if (k == "sparse_extrapolation_steps") params.sparse_extrapolation_steps = static_cast<int>(v);
    else if (k == "sparse_final_iterations") params.sparse_final_iterations = static_cast<int>(v);
    else if (k == "plane_sweep_polish_step") params.plane_sweep_polish_step = v;
    else if (k == "plane_sweep_polish_min_rise") params.plane_sweep_polish_min_rise = v;
    else if (k == "plane_sweep_flat_rise") params.plane_sweep_flat_rise = v;
    else if (k == "sparse_level_keep_every") params.sparse_level_keep_every = static_cast<int>(v);
    else if (k == "sparse_level_normal_z") params.sparse_level_normal_z = v;
    else if (k == "sparse_level_extrapolation_steps") params.sparse_level_extrapolation_steps = static_cast<int>(v);
    else if (k == "coarse_restarts") params.coarse_restarts = static_cast<int>(v);
    else if (k == "plane_sweep_consistency") params.plane_sweep_consistency = v;
    else if (k == "score_cluster") params.observability.score_cluster = v;
    else if (k == "symmetric_refinement") params.symmetric_refinement = v != 0;
    else if (k == "noise_floor") params.refinement.noise_floor = v;
    else if (k == "range_noise") params.refinement.range_noise = v;
    else if (k == "range_noise_per_m2") params.refinement.range_noise_per_m2 = v;
    else if (k == "reference_noise") params.refinement.reference_noise = v;
    else {
      std::cerr << "unknown --set parameter " << k << "\n";
      return 2;
    }
  }

  std::printf("pair %s (target %s against reference %s), world %s, method %s, %d trials, seed %llu, "
              "%s\n",
              pair.name.c_str(), cal::sensorKindName(pair.target.kind),
              cal::sensorKindName(pair.reference.kind), world_name.c_str(), method.c_str(), trials,
              static_cast<unsigned long long>(seed),
              trajectory == "thesis"
                  ? ("poses around (" + fmt1(centre_x) + ", " + fmt1(centre_y) + ")").c_str()
                  : "trajectory turns (a slalom along the world's drive)");
  std::vector<std::vector<double>> errors(6);
  // The particle filter also reports the inverse-error weighted mean over all its hypotheses
  // (thesis 4.4.4); its errors are summarised separately.
  const bool pf = method == "particle_filter";
  std::vector<std::vector<double>> mean_errors(6);
  std::vector<double> seconds, cpu_seconds;
  std::set<std::string> unobservable;
  std::vector<std::vector<cal::Pose6>> traces;
  int successes = 0;
  // |error| / reported standard deviation of every observable DOF of every trial: how honest
  // the stddev of the result (and of the service's response) is.
  std::vector<double> error_in_sd;
  for (int t = 0; t < trials; ++t) {
    if (only >= 0 && t != only) continue;
    cal::ExperimentTrial trial;
    if (!cal::makeTrial(world, pair, options, seed * 1000003ULL + t, &trial, &error)) {
      std::cerr << "trial " << t << ": simulation failed: " << error << "\n";
      return 1;
    }
    params.initial = trial.initial_guess;
    params.search.seed = seed * 7919ULL + t;
    const cal::CalibrationResult r = cal::calibrate(trial.input, params);
    const cal::Pose6 err = cal::poseDifference(r.extrinsic, trial.truth);
    for (int d = 0; d < 6; ++d) errors[d].push_back(err[d]);
    const cal::Pose6 mean_err = cal::poseDifference(r.search.weighted_mean, trial.truth);
    if (pf) {
      for (int d = 0; d < 6; ++d) mean_errors[d].push_back(mean_err[d]);
    }
    seconds.push_back(r.elapsed);
    cpu_seconds.push_back(r.cpu_time);
    unobservable.insert(r.unobservable.begin(), r.unobservable.end());
    successes += r.success ? 1 : 0;
    for (int d = 0; d < 6; ++d) {
      if (std::isfinite(r.stddev[d]) && r.stddev[d] > 0) error_in_sd.push_back(std::abs(err[d]) / r.stddev[d]);
    }
    std::vector<cal::Pose6> trace{cal::poseDifference(trial.initial_guess, trial.truth)};
    for (const cal::Pose6& p : r.trace) trace.push_back(cal::poseDifference(p, trial.truth));
    traces.push_back(trace);
    if (!quiet) {
      std::printf("trial %2d: %s %.2f s (cpu %.2f s), %ld evaluations%s, error x %+.4f y %+.4f z %+.4f m, "
                  "roll %+.5f pitch %+.5f yaw %+.5f rad; %s\n",
                  t, r.success ? "ok  " : "FAIL", r.elapsed, r.cpu_time, r.evaluations,
                  r.restarts > 0 ? (", " + std::to_string(r.restarts) + " coarse restarts").c_str() : "",
                  err[0], err[1], err[2], err[3], err[4], err[5], r.message.c_str());
      const cal::Pose6 curv = r.observability.curvature / std::max(1e-300, r.observability.curvature.maxCoeff());
      std::printf("          cost curvature along the Hessian's eigenvectors (relative): %.2g %.2g %.2g %.2g %.2g %.2g\n",
                  curv[0], curv[1], curv[2], curv[3], curv[4], curv[5]);
      const cal::Pose6& ms = r.observability.measured_stddev;
      std::printf("          stddev from the measured curvature: x %.3g y %.3g z %.3g m, roll %.3g pitch %.3g yaw %.3g rad"
                  " (sigma^2 %.3g, N %ld, eigen-curvatures %.3g %.3g %.3g %.3g %.3g %.3g)\n",
                  ms[0], ms[1], ms[2], ms[3], ms[4], ms[5], r.refinement.at_solution.residual_variance,
                  r.refinement.at_solution.correspondences,
                  r.observability.curvature[0], r.observability.curvature[1], r.observability.curvature[2],
                  r.observability.curvature[3], r.observability.curvature[4], r.observability.curvature[5]);
      std::printf("          reported stddev: x %.3g y %.3g z %.3g m, roll %.3g pitch %.3g yaw %.3g rad\n",
                  r.stddev[0], r.stddev[1], r.stddev[2], r.stddev[3], r.stddev[4], r.stddev[5]);
      const cal::Pose6& sg = r.observability.significance;
      std::printf("          curvature significance (mean / standard error): %.3g %.3g %.3g %.3g %.3g %.3g\n",
                  sg[0], sg[1], sg[2], sg[3], sg[4], sg[5]);
      if (pf) {
        std::printf("          weighted mean: error x %+.4f y %+.4f z %+.4f m, roll %+.5f pitch %+.5f "
                    "yaw %+.5f rad; %d iterations, final spread %.4f %.4f %.4f m %.5f %.5f %.5f rad\n",
                    mean_err[0], mean_err[1], mean_err[2], mean_err[3], mean_err[4], mean_err[5],
                    r.search.iterations, r.search.spread[0], r.search.spread[1], r.search.spread[2],
                    r.search.spread[3], r.search.spread[4], r.search.spread[5]);
      }
      if (diagnose) printDiagnosis(trial, params, r);
      if (windows > 1) {
        const cal::Pose6 rep = cal::repeatability(trial.input, params, r.extrinsic, windows);
        std::printf("          repeatability over %d windows (std): x %.4f y %.4f z %.4f m, "
                    "roll %.5f pitch %.5f yaw %.5f rad\n",
                    windows, rep[0], rep[1], rep[2], rep[3], rep[4], rep[5]);
      }
      std::fflush(stdout);
    }
  }
  std::printf("\nerror (solution - truth) over the trials:\n");
  std::vector<DofStats> summary;
  printStats(errors, &summary);
  if (pf) {
    std::printf("inverse-error weighted mean (thesis 4.4.4):\n");
    printStats(mean_errors);
  }
  const double sec_median = median(seconds), sec_max = *std::max_element(seconds.begin(), seconds.end());
  const double cpu_median = median(cpu_seconds),
               cpu_max = *std::max_element(cpu_seconds.begin(), cpu_seconds.end());
  std::printf("seconds per trial: median %.2f max %.2f (wall clock); cpu median %.2f max %.2f; "
              "successes %d/%d; unobservable:",
              sec_median, sec_max, cpu_median, cpu_max, successes, static_cast<int>(seconds.size()));
  for (const std::string& u : unobservable) std::printf(" %s", u.c_str());
  std::printf("%s\n", unobservable.empty() ? " none" : "");
  // The share of observable DOF estimates within k reported standard deviations of the truth
  // (68 / 95 / 99.7 % for an honest Gaussian figure).
  const auto within = [&](double k) {
    const auto n = std::count_if(error_in_sd.begin(), error_in_sd.end(), [k](double z) { return z <= k; });
    return error_in_sd.empty() ? 0.0 : 100.0 * static_cast<double>(n) / static_cast<double>(error_in_sd.size());
  };
  const double sd_median = error_in_sd.empty() ? NAN : median(error_in_sd);
  std::printf("reported stddev: |error| within 1 / 2 / 3 sd for %.0f / %.0f / %.0f %% of %zu DOF estimates "
              "(median |error| / sd %.2f)\n",
              within(1), within(2), within(3), error_in_sd.size(), sd_median);

  if (!json_path.empty()) {
    std::ostringstream j;
    j << "{\"pair\": \"" << pair.name << "\", \"method\": \"" << method << "\", \"world\": \""
      << world_name << "\", \"trials\": " << trials << ", \"seed\": " << seed
      << ", \"noise\": \"" << noise_name << "\", \"poses\": " << poses << ",\n \"errors\": {";
    for (int d = 0; d < 6; ++d) {
      j << (d ? ", " : "") << "\"" << cal::dofName(d) << "\": {\"mean\": " << jsonNumber(summary[d].mean)
        << ", \"std\": " << jsonNumber(summary[d].std) << ", \"mean_abs\": " << jsonNumber(summary[d].mean_abs)
        << ", \"worst\": " << jsonNumber(summary[d].worst)
        << "}";
    }
    j << "},\n \"seconds_per_trial\": {\"median\": " << jsonNumber(sec_median)
      << ", \"max\": " << jsonNumber(sec_max) << "},\n \"cpu_seconds_per_trial\": {\"median\": "
      << jsonNumber(cpu_median) << ", \"max\": " << jsonNumber(cpu_max)
      << "},\n \"stddev_coverage\": {\"within_1\": " << jsonNumber(within(1))
      << ", \"within_2\": " << jsonNumber(within(2)) << ", \"within_3\": " << jsonNumber(within(3))
      << ", \"median_error_over_sd\": " << jsonNumber(sd_median) << "}"
      << ",\n \"successes\": " << successes
      << ",\n \"unobservable\": [";
    bool first = true;
    for (const std::string& u : unobservable) {
      j << (first ? "" : ", ") << "\"" << u << "\"";
      first = false;
    }
    j << "]}\n";
    const std::string tmp = json_path + ".tmp";
    {
      std::ofstream f(tmp);
      f << j.str();
      if (!f) {
        std::cerr << "cannot write " << json_path << "\n";
        return 1;
      }
    }
    if (std::rename(tmp.c_str(), json_path.c_str()) != 0) {
      std::cerr << "cannot write " << json_path << "\n";
      return 1;
    }
  }
  if (!plot_path.empty() && !writePlot(plot_path, traces, options.guess_offset, &error)) {
    std::cerr << "plot: " << error << "\n";
    return 1;
  }
  return 0;
}
