#include "ladar_perception/calibration/network.h"

#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

#include "ladar_perception/calibration/result_yaml.h"

namespace ladar_perception {
namespace calibration {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double rotationAngle(const Pose6& d) {
  return Eigen::AngleAxisd(toIsometry((Pose6() << 0, 0, 0, d[3], d[4], d[5]).finished()).linear())
      .angle();
}

// The edge's estimate of `to` given where `from` is: the calibration placed `from` at
// from_estimate and found `to` at result.extrinsic; the relative mount is what the edge measures.
Pose6 predictedTo(const NetworkEdge& e, const std::vector<Pose6>& x) {
  if (e.from < 0) return e.result.extrinsic;
  const Eigen::Isometry3d relative =
      toIsometry(e.from_estimate).inverse() * toIsometry(e.result.extrinsic);
  return fromIsometry(toIsometry(x[e.from]) * relative);
}

// Per-DOF weight 1/sigma of an edge: its reported stddev with the floor added in quadrature;
// 0 for a DOF it cannot fix.
Pose6 edgeWeights(const NetworkEdge& e, const NetworkParams& params) {
  Pose6 w;
  for (int k = 0; k < 6; ++k) {
    const double s = e.result.stddev[k];
    const double floor = k < 3 ? params.floor_translation : params.floor_rotation;
    w[k] = std::isfinite(s) ? 1.0 / std::sqrt(s * s + floor * floor) : 0.0;
  }
  for (const std::string& name : e.result.unobservable) {
    const int k = dofIndex(name);
    if (k >= 0) w[k] = 0.0;
  }
  return w;
}

}  // namespace

std::string networkKey(const std::string& frame) {
  std::string key = frame;
  for (char& c : key) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  }
  if (key.empty() || std::isdigit(static_cast<unsigned char>(key[0]))) key = "sensor_" + key;
  return key;
}

void solveNetwork(int targets, const NetworkParams& params, std::vector<NetworkEdge>* edges,
                  std::vector<NetworkSensorResult>* sensors, double* cost) {
  sensors->resize(targets);
  // The starting point: each target's first usable edge's estimate, pairwise edges first.
  std::vector<Pose6> x(targets, Pose6::Zero());
  std::vector<bool> reached(targets, false);
  for (int pass = 0; pass < targets + 1; ++pass) {
    for (const NetworkEdge& e : *edges) {
      if (!e.used || reached[e.to] || (e.from >= 0 && !reached[e.from])) continue;
      x[e.to] = predictedTo(e, x);
      reached[e.to] = true;
    }
  }
  std::vector<Pose6> weights;
  for (const NetworkEdge& e : *edges) weights.push_back(edgeWeights(e, params));
  // A weak prior on the start keeps the normal equations invertible: a DOF no edge fixes keeps
  // its start, with a standard deviation of prior_sigma (far above max_stddev: unobservable).
  constexpr double prior_sigma = 1e3;
  std::vector<double> robust(edges->size(), 1.0);  // per edge (reweight below)
  const int n = 6 * targets;
  const auto residuals = [&](const std::vector<Pose6>& at, Eigen::VectorXd* r) {
    std::vector<double> out;
    for (std::size_t k = 0; k < edges->size(); ++k) {
      const NetworkEdge& e = (*edges)[k];
      if (!e.used || !reached[e.to]) continue;
      const Pose6 d = poseDifference(at[e.to], predictedTo(e, at));
      const double w = std::sqrt(robust[k]);
      for (int i = 0; i < 6; ++i) out.push_back(w * weights[k][i] * d[i]);
    }
    r->resize(static_cast<int>(out.size()));
    for (std::size_t i = 0; i < out.size(); ++i) (*r)[static_cast<int>(i)] = out[i];
  };
  const std::vector<Pose6> start = x;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Identity(n, n) / (prior_sigma * prior_sigma);
  // Iteratively reweighted (Huber per edge): an edge whose normalised residual exceeds
  // params.robust_threshold is down-weighted by threshold / residual, so one inconsistent edge
  // (a loop that does not close) cannot pull the others' sensors by its point count.
  const auto reweight = [&](const std::vector<Pose6>& at) {
    for (std::size_t k = 0; k < edges->size(); ++k) {
      const NetworkEdge& e = (*edges)[k];
      robust[k] = 1.0;
      if (!e.used || !reached[e.to] || params.robust_threshold <= 0) continue;
      const double norm =
          poseDifference(at[e.to], predictedTo(e, at)).cwiseProduct(weights[k]).norm();
      if (norm > params.robust_threshold) robust[k] = params.robust_threshold / norm;
    }
  };
  // Variance components (Helmert): the pairwise edges and the cross edges are two classes whose
  // reported standard deviations may be off by different factors (a 2D ladar's cloud as the
  // surface is far noisier than the Velodyne's). Each class's variances are scaled up so that
  // its normalised squared residuals match its share of the redundancy.
  const std::vector<Pose6> base_weights = weights;
  const auto scaleClasses = [&](const std::vector<Pose6>& at) {
    double chi2[2] = {0, 0}, count[2] = {0, 0};
    for (std::size_t k = 0; k < edges->size(); ++k) {
      const NetworkEdge& e = (*edges)[k];
      if (!e.used || !reached[e.to]) continue;
      const int c = e.from < 0 ? 0 : 1;
      chi2[c] += poseDifference(at[e.to], predictedTo(e, at)).cwiseProduct(base_weights[k]).squaredNorm();
      for (int i = 0; i < 6; ++i) count[c] += base_weights[k][i] > 0;
    }
    int solved = 0;
    for (bool r : reached) solved += r;
    const double redundancy = count[0] + count[1] - 6.0 * solved;
    if (redundancy < 1 || count[0] == 0 || count[1] == 0) return;
    for (int c = 0; c < 2; ++c) {
      const double share = count[c] * redundancy / (count[0] + count[1]);
      const double factor = std::max(1.0, chi2[c] / share);
      for (std::size_t k = 0; k < edges->size(); ++k) {
        if (((*edges)[k].from < 0 ? 0 : 1) == c) weights[k] = base_weights[k] / std::sqrt(factor);
      }
    }
  };
  for (int iteration = 0; iteration < std::max(1, params.joint_iterations); ++iteration) {
    if (params.variance_components) scaleClasses(x);
    reweight(x);
    Eigen::VectorXd r0;
    residuals(x, &r0);
    Eigen::MatrixXd jacobian(r0.size(), n);
    constexpr double h = 1e-7;
    for (int j = 0; j < n; ++j) {
      std::vector<Pose6> plus = x, minus = x;
      plus[j / 6][j % 6] += h;
      minus[j / 6][j % 6] -= h;
      Eigen::VectorXd rp, rm;
      residuals(plus, &rp);
      residuals(minus, &rm);
      jacobian.col(j) = (rp - rm) / (2 * h);
    }
    Eigen::VectorXd prior(n);
    for (int j = 0; j < n; ++j) prior[j] = (j % 6 < 3 ? x[j / 6][j % 6] - start[j / 6][j % 6]
                                                      : wrapAngle(x[j / 6][j % 6] - start[j / 6][j % 6])) /
                                           prior_sigma;
    normal = jacobian.transpose() * jacobian +
             Eigen::MatrixXd::Identity(n, n) / (prior_sigma * prior_sigma);
    const Eigen::VectorXd gradient = jacobian.transpose() * r0 + prior / prior_sigma;
    const Eigen::VectorXd step = normal.ldlt().solve(-gradient);
    for (int j = 0; j < n; ++j) x[j / 6][j % 6] += step[j];
    for (Pose6& p : x) p = fromIsometry(toIsometry(p));  // angles back into their ranges
    if (step.cwiseAbs().maxCoeff() < 1e-10 && iteration > 0) break;
  }
  for (std::size_t k = 0; k < edges->size(); ++k) (*edges)[k].weight = robust[k];
  const Eigen::MatrixXd covariance = normal.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  Eigen::VectorXd r;
  residuals(x, &r);
  if (cost) *cost = r.squaredNorm();
  for (int t = 0; t < targets; ++t) {
    NetworkSensorResult& s = (*sensors)[t];
    s.joint = x[t];
    s.unobservable.clear();
    for (int k = 0; k < 6; ++k) {
      const double sd = std::sqrt(std::max(0.0, covariance(6 * t + k, 6 * t + k)));
      const bool fixed = reached[t] && sd <= (k < 3 ? params.max_stddev : params.max_stddev_rotation);
      s.stddev[k] = fixed ? sd : kInf;
      if (!fixed) s.unobservable.push_back(dofName(k));
    }
    s.success = reached[t] && s.unobservable.empty();
  }
  for (NetworkEdge& e : *edges) {
    if (!reached[e.to] || (e.from >= 0 && !reached[e.from])) continue;
    e.residual = poseDifference(x[e.to], predictedTo(e, x));
    e.residual_translation = e.residual.head<3>().norm();
    e.residual_rotation = rotationAngle(e.residual);
  }
}

NetworkResult calibrateNetwork(const NetworkInput& input, const NetworkParams& params,
                               const NetworkProgressFn& progress) {
  const auto wall_start = std::chrono::steady_clock::now();
  const double cpu_start = threadCpuSeconds();
  NetworkResult out;
  const int targets = static_cast<int>(input.targets.size());
  out.sensors.resize(targets);
  for (int t = 0; t < targets; ++t) out.sensors[t].name = input.targets[t].name;
  const auto finish = [&](NetworkResult& r) -> NetworkResult& {
    r.elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    r.cpu_time = threadCpuSeconds() - cpu_start;
    return r;
  };
  if (targets == 0) {
    out.message = "no target sensors";
    return finish(out);
  }
  bool cancelled = false;
  const auto run = [&](const std::string& edge_name, const CalibrationInput& pair,
                       const CalibrationParams& pair_params) {
    return calibrate(pair, pair_params, [&](const SearchProgress& p) {
      if (progress && !progress(edge_name, p)) cancelled = true;
      return !cancelled;
    });
  };
  const auto paramsFor = [&](const NetworkTarget& a, const NetworkTarget* b) {
    CalibrationParams p = params.calibration;
    const double voxel = std::max(a.surface_voxel, b ? b->surface_voxel : 0.0);
    if (voxel > 0) p.refinement.reference_voxel = std::max(p.refinement.reference_voxel, voxel);
    return p;
  };

  // The pairwise edges: every target against the reference.
  for (int t = 0; t < targets && !cancelled; ++t) {
    const NetworkTarget& target = input.targets[t];
    CalibrationInput pair;
    pair.reference = input.reference;
    pair.reference_extrinsic = input.reference_extrinsic;
    pair.target = target.scans;
    CalibrationParams p = paramsFor(target, nullptr);
    p.initial = target.initial;
    p.spread = target.spread;
    NetworkEdge e;
    e.from = -1;
    e.to = t;
    e.from_estimate = fromIsometry(input.reference_extrinsic);
    e.result = run(target.name + " <- " + input.reference_name, pair, p);
    e.used = e.result.success || e.result.partial;
    out.sensors[t].pairwise = e.result.extrinsic;
    out.sensors[t].pairwise_success = e.result.success;
    out.edges.push_back(std::move(e));
  }

  // The cross edges: each pair of targets, the denser cloud as the surface.
  if (params.cross_pairs) {
    for (int i = 0; i < targets && !cancelled; ++i) {
      for (int j = i + 1; j < targets && !cancelled; ++j) {
        if (!out.edges[i].used || !out.edges[j].used) continue;
        const bool i_denser = input.targets[i].scans.numPoints() >= input.targets[j].scans.numPoints();
        const int from = i_denser ? i : j, to = i_denser ? j : i;
        const NetworkTarget& surface = input.targets[from];
        const NetworkTarget& fitted = input.targets[to];
        CalibrationInput pair;
        pair.reference = surface.scans;
        pair.reference_extrinsic = toIsometry(out.sensors[from].pairwise);
        pair.target = fitted.scans;
        CalibrationParams p = paramsFor(surface, &fitted);
        p.method = "refine";
        p.initial = out.sensors[to].pairwise;
        p.spread = params.cross_spread;
        NetworkEdge e;
        e.from = from;
        e.to = to;
        e.from_estimate = out.sensors[from].pairwise;
        e.result = run(fitted.name + " <- " + surface.name, pair, p);
        e.used = e.result.success || e.result.partial;
        out.edges.push_back(std::move(e));
      }
    }
  }
  if (cancelled) {
    out.message = "cancelled";
    return finish(out);
  }

  // Loop closures before the joint solve: a cross edge's estimate of `to` against the pairwise one.
  std::vector<Pose6> pairwise;
  for (const NetworkSensorResult& s : out.sensors) pairwise.push_back(s.pairwise);
  for (NetworkEdge& e : out.edges) {
    if (e.from < 0) continue;
    e.loop = poseDifference(predictedTo(e, pairwise), pairwise[e.to]);
    e.loop_translation = e.loop.head<3>().norm();
    e.loop_rotation = rotationAngle(e.loop);
  }

  std::vector<NetworkSensorResult> solved = out.sensors;
  solveNetwork(targets, params, &out.edges, &solved, &out.joint_cost);
  int calibrated = 0;
  std::ostringstream msg;
  for (int t = 0; t < targets; ++t) {
    NetworkSensorResult& s = out.sensors[t];
    s.joint = solved[t].joint;
    s.stddev = solved[t].stddev;
    s.unobservable = solved[t].unobservable;
    s.success = solved[t].success;
    calibrated += s.success;
    if (!s.success) {
      msg << (msg.tellp() > 0 ? "; " : "") << s.name << ": ";
      if (s.unobservable.size() == 6) {
        msg << "no usable edge (" << out.edges[t].result.message << ")";
      } else {
        msg << "the network cannot fix";
        for (const std::string& u : s.unobservable) msg << " " << u;
      }
    }
  }
  out.success = calibrated == targets;
  std::ostringstream head;
  head << calibrated << " of " << targets << " sensors calibrated, " << out.edges.size()
       << " edges, joint cost " << out.joint_cost;
  out.message = head.str() + (msg.tellp() > 0 ? ": " + msg.str() : "");
  return finish(out);
}

std::string networkYaml(const std::string& parent_frame, const NetworkResult& r) {
  std::ostringstream y;
  y << "# ladar_perception calibration of a sensor network against its reference\n";
  y << "# success: " << (r.success ? "true" : "false") << "; " << yamlText(r.message) << "\n";
  y << "# edges (to <- from: pairwise or cross estimate; loop closure and joint residual as\n"
       "# translation [m] / rotation [rad]):\n";
  for (const NetworkEdge& e : r.edges) {
    const std::string from = e.from < 0 ? "reference" : r.sensors[e.from].name;
    y << "#   " << yamlText(r.sensors[e.to].name) << " <- " << yamlText(from) << ": "
      << (e.result.success ? "success" : (e.used ? "partial" : "not used"));
    if (e.from >= 0) {
      y << ", loop " << yamlFigure(e.loop_translation, 4) << " / "
        << yamlFigure(e.loop_rotation, 4);
    }
    y << ", residual " << yamlFigure(e.residual_translation, 4) << " / "
      << yamlFigure(e.residual_rotation, 4) << "\n";
  }
  for (const NetworkSensorResult& s : r.sensors) {
    y << "\n# " << yamlText(s.name) << ": " << (s.success ? "calibrated" : "NOT calibrated")
      << "; x y z roll pitch yaw:";
    for (int k = 0; k < 6; ++k) y << " " << yamlNumber(s.joint[k]);
    y << "\n# stddev:";
    for (int k = 0; k < 6; ++k) y << " " << yamlFigure(s.stddev[k], 4);
    y << "; pairwise estimate:";
    for (int k = 0; k < 6; ++k) y << " " << yamlNumber(s.pairwise[k]);
    y << "\n" << networkKey(s.name) << ":\n";
    y << transformStampedYaml(parent_frame, s.name, s.joint, "  ");
  }
  return y.str();
}

std::string networkLaunch(const std::string& yaml_path, const NetworkResult& r) {
  std::ostringstream l;
  l << "<launch>\n  <!-- ladar_perception network calibration: one static_transform_publisher per "
       "sensor, each reading its transform from the YAML. -->\n";
  l << "  <rosparam command=\"load\" file=\"" << yamlText(yaml_path)
    << "\" ns=\"ladar_calibration_network\"/>\n";
  for (const NetworkSensorResult& s : r.sensors) {
    const std::string key = networkKey(s.name);
    if (!s.success) l << "  <!-- " << key << " was NOT calibrated -->\n";
    l << "  <node pkg=\"tf2_ros\" type=\"static_transform_publisher\" name=\"" << key
      << "_calibration_publisher\" args=\"/ladar_calibration_network/" << key << "\"/>\n";
  }
  l << "</launch>\n";
  return l.str();
}

}  // namespace calibration
}  // namespace ladar_perception
