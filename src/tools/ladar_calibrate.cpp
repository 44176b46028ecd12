// ladar_calibrate: the Calibration nodelet's work offline, from a rosbag. Reads the reference and
// target topics (PointCloud2 or LaserScan, detected per message) and /tf + /tf_static, pairs each
// scan with the vehicle pose (odom -> base_link) at its stamp, calls calibration::calibrate (one
// target) or calibration::calibrateNetwork (several --target-topic), prints progress and the
// result, and writes the YAML static_transform_publisher loads (a network: one YAML for every
// target and the launch file that publishes them).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include "ladar_perception/calibration/calibrator.h"
#include "ladar_perception/calibration/network.h"
#include "ladar_perception/calibration/result_yaml.h"
#include "ladar_perception/ros/calibration_ros.h"

namespace cal = ladar_perception::calibration;

namespace {

void usage() {
  std::cerr
      << "usage: ladar_calibrate BAG --reference-topic TOPIC --target-topic TOPIC [--target-topic T2 ...]\n"
         "         [--odom-frame odom] [--base-frame base_link] [--method NAME]\n"
         "         [--initial x,y,z,roll,pitch,yaw] [--spread x,y,z,roll,pitch,yaw]\n"
         "         [--output FILE.yaml] [--max-scans N] [--min-range M] [--max-range M]\n"
         "         [--voxel M] [--surface-voxel M] [--repeatability W] [--reference-only] [--quiet]\n"
         "--max-scans N: at most N scans per sensor, evenly spread over the bag (default 200)\n"
         "--voxel M: each scan thinned to this voxel before buffering (default 0.1 m)\n"
         "Several --target-topic: the targets are calibrated as one network (each against the\n"
         "  reference, then every pair of targets against each other unless --reference-only,\n"
         "  solved jointly); --output names the one YAML for all (default\n"
         "  ladar_calibration_network.yaml) and a .launch beside it publishes them; each\n"
         "  target's initial guess is its --target-initial, else its mount in the bag's tf, else\n"
         "  --initial. After a --target-topic: --target-initial x,y,z,roll,pitch,yaw (that\n"
         "  target's initial guess), --target-surface-voxel M (its surface voxel; 0.4 for a\n"
         "  stereo camera), --target-max-scans N (its --max-scans: a 2D ladar's lines are many),\n"
         "  --target-voxel M (its --voxel; 0.02 for a stereo camera, whose accurate near returns\n"
         "  a coarse voxel merges)\n"
         "--surface-voxel: the refinement's surface model voxel (default 0.2 m; 0.4 when a\n"
         "  stereo camera is one of the pair)\n"
         "The target's extrinsic (base_link -> target frame) is searched around --initial; the\n"
         "reference's extrinsic comes from the bag's tf (base_link -> reference frame).\nmethods:";
  for (const std::string& m : cal::methodNames()) std::cerr << " " << m;
  std::cerr << " (default " << cal::defaultMethod() << ")\n";
}

bool parsePose(const std::string& text, cal::Pose6* out) {
  std::stringstream ss(text);
  std::string item;
  int i = 0;
  while (std::getline(ss, item, ',')) {
    if (i >= 6) return false;
    try {
      (*out)[i++] = std::stod(item);
    } catch (const std::exception&) {
      return false;
    }
  }
  return i == 6;
}

// Several targets: calibrateNetwork, one YAML for all and the launch file beside it.
int calibrateNetwork(std::vector<cal::ScanSet>& sets, const std::vector<std::string>& frames,
                     const std::vector<double>& target_voxels,
                     const std::vector<std::pair<bool, cal::Pose6>>& target_initials,
                     const Eigen::Isometry3d& reference_extrinsic, const tf2::BufferCore& tf,
                     const std::string& base_frame, const cal::CalibrationParams& params,
                     bool initial_given, bool cross_pairs, std::string output, bool quiet) {
  cal::NetworkInput input;
  input.reference_name = frames[0];
  input.reference = std::move(sets[0]);
  input.reference_extrinsic = reference_extrinsic;
  for (std::size_t k = 1; k < sets.size(); ++k) {
    cal::NetworkTarget t;
    t.name = frames[k];
    t.scans = std::move(sets[k]);
    t.spread = params.spread;
    t.initial = params.initial;
    t.surface_voxel = target_voxels[k - 1];
    if (target_initials[k - 1].first) {
      t.initial = target_initials[k - 1].second;
    } else if (!initial_given) {
      try {  // an existing (uncertain) calibration in the bag is a natural initial guess
        t.initial = cal::fromIsometry(
            tf2::transformToEigen(tf.lookupTransform(base_frame, frames[k], ros::Time(0))));
        std::printf("%s: initial guess from the bag's tf\n", frames[k].c_str());
      } catch (const tf2::TransformException&) {
        std::printf("%s: initial guess zero (give --initial)\n", frames[k].c_str());
      }
    }
    input.targets.push_back(std::move(t));
  }
  cal::NetworkParams network;
  network.calibration = params;
  network.cross_pairs = cross_pairs;
  int line = 0;
  const cal::NetworkResult r = cal::calibrateNetwork(
      input, network, [&](const std::string& edge, const cal::SearchProgress& p) {
        if (!quiet) {
          std::printf("%4d %s: %-16s iteration %3d cost %.6g  x %.4f y %.4f z %.4f roll %.5f "
                      "pitch %.5f yaw %.5f\n",
                      ++line, edge.c_str(), p.stage.c_str(), p.iteration, p.best_cost,
                      p.estimate[0], p.estimate[1], p.estimate[2], p.estimate[3], p.estimate[4],
                      p.estimate[5]);
          std::fflush(stdout);
        }
        return true;
      });
  std::printf("\nnetwork %s in %.2f s: %s\n", r.success ? "calibrated" : "NOT calibrated",
              r.elapsed, r.message.c_str());
  for (const cal::NetworkSensorResult& s : r.sensors) {
    std::printf("%s -> %s: x %.4f y %.4f z %.4f m, roll %.5f pitch %.5f yaw %.5f rad (%s); "
                "pairwise %s\n  stddev %.4f %.4f %.4f m, %.5f %.5f %.5f rad\n",
                base_frame.c_str(), s.name.c_str(), s.joint[0], s.joint[1], s.joint[2], s.joint[3],
                s.joint[4], s.joint[5], s.success ? "calibrated" : "NOT calibrated",
                s.pairwise_success ? "success" : "no success", s.stddev[0], s.stddev[1],
                s.stddev[2], s.stddev[3], s.stddev[4], s.stddev[5]);
  }
  for (const cal::NetworkEdge& e : r.edges) {
    std::printf("edge %s <- %s: %s, loop closure %.4f m %.5f rad, joint residual %.4f m %.5f rad\n",
                r.sensors[e.to].name.c_str(),
                e.from < 0 ? frames[0].c_str() : r.sensors[e.from].name.c_str(),
                e.result.success ? "success" : (e.used ? "partial" : "not used"),
                e.loop_translation, e.loop_rotation, e.residual_translation, e.residual_rotation);
  }
  if (output.empty()) output = "ladar_calibration_network.yaml";
  std::string launch = output;
  const std::size_t dot = launch.rfind(".yaml");
  if (dot != std::string::npos && dot + 5 == launch.size()) launch.erase(dot);
  launch += ".launch";
  std::string error;
  if (!cal::backupExistingFile(output, nullptr, &error) ||
      !cal::writeFileAtomically(output, cal::networkYaml(base_frame, r), &error) ||
      !cal::backupExistingFile(launch, nullptr, &error) ||
      !cal::writeFileAtomically(launch, cal::networkLaunch(output, r), &error)) {
    std::cerr << error << "\n";
    return 1;
  }
  std::printf("written to %s%s\nlaunch: roslaunch %s\n", output.c_str(),
              r.success ? "" : " (NOT a success: see its comments)", launch.c_str());
  return r.success ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  std::string bag_path, ref_topic, odom_frame = "odom", base_frame = "base_link";
  std::string method = cal::defaultMethod(), output;
  cal::CalibrationParams params;
  std::vector<std::string> target_topics;
  std::vector<double> target_voxels;  // per target, 0 = --surface-voxel's
  std::vector<std::pair<bool, cal::Pose6>> target_initials;  // per target: given, value
  std::vector<std::size_t> target_max_scans;                 // per target, 0 = --max-scans
  std::vector<double> target_thin;                           // per target, < 0 = --voxel
  bool initial_given = false, quiet = false, reference_only = false;
  std::size_t max_scans = 200;
  double min_range = 0.5, max_range = 120.0, voxel = 0.1;
  int windows = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "missing value for " << a << "\n";
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--reference-topic") ref_topic = value();
      else if (a == "--target-topic") {
        target_topics.push_back(value());
        target_voxels.push_back(0.0);
        target_initials.emplace_back(false, cal::Pose6::Zero());
        target_max_scans.push_back(0);
        target_thin.push_back(-1.0);
      } else if (a == "--target-surface-voxel") {
        if (target_voxels.empty()) { std::cerr << "--target-surface-voxel follows its --target-topic\n"; return 2; }
        target_voxels.back() = std::stod(value());
      } else if (a == "--target-voxel") {
        if (target_thin.empty()) { std::cerr << "--target-voxel follows its --target-topic\n"; return 2; }
        target_thin.back() = std::stod(value());
      } else if (a == "--target-max-scans") {
        if (target_max_scans.empty()) { std::cerr << "--target-max-scans follows its --target-topic\n"; return 2; }
        target_max_scans.back() = std::stoul(value());
      } else if (a == "--target-initial") {
        if (target_initials.empty()) { std::cerr << "--target-initial follows its --target-topic\n"; return 2; }
        if (!parsePose(value(), &target_initials.back().second)) { std::cerr << "--target-initial needs 6 numbers\n"; return 2; }
        target_initials.back().first = true;
      }
      else if (a == "--reference-only") reference_only = true;
      else if (a == "--odom-frame") odom_frame = value();
      else if (a == "--base-frame") base_frame = value();
      else if (a == "--method") method = value();
      else if (a == "--output") output = value();
      else if (a == "--max-scans") max_scans = std::stoul(value());
      else if (a == "--min-range") min_range = std::stod(value());
      else if (a == "--max-range") max_range = std::stod(value());
      else if (a == "--voxel") voxel = std::stod(value());
      else if (a == "--surface-voxel") params.refinement.reference_voxel = std::max(0.05, std::stod(value()));
      else if (a == "--repeatability") windows = std::stoi(value());
      else if (a == "--quiet") quiet = true;
      else if (a == "--initial") {
        if (!parsePose(value(), &params.initial)) { std::cerr << "--initial needs 6 numbers\n"; return 2; }
        initial_given = true;
      } else if (a == "--spread") {
        if (!parsePose(value(), &params.spread)) { std::cerr << "--spread needs 6 numbers\n"; return 2; }
      } else if (a == "-h" || a == "--help") { usage(); return 0; }
      else if (!a.empty() && a[0] != '-' && bag_path.empty()) bag_path = a;
      else { std::cerr << "unknown argument " << a << "\n"; usage(); return 2; }
    } catch (const std::exception&) {
      std::cerr << "bad number for " << a << "\n";
      return 2;
    }
  }
  if (bag_path.empty() || ref_topic.empty() || target_topics.empty()) {
    usage();
    return 2;
  }
  if (!cal::isMethod(method)) {
    std::cerr << "unknown method '" << method << "'\n";
    usage();
    return 2;
  }
  params.method = method;
  if (method == "particle_filter") params.search = cal::thesisParticleFilterParams().search;

  try {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    // Pass 1: every transform, so a scan's vehicle pose is found whatever the message order.
    rosbag::View tf_view(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}));
    const ros::Duration span = tf_view.size() > 0 ? tf_view.getEndTime() - tf_view.getBeginTime()
                                                  : ros::Duration(0);
    tf2::BufferCore tf(span + ros::Duration(60.0));
    std::size_t transforms = 0;
    for (const rosbag::MessageInstance& m : tf_view) {
      tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
      if (!msg) continue;
      const bool is_static = m.getTopic() == "/tf_static";
      for (const geometry_msgs::TransformStamped& t : msg->transforms) {
        tf.setTransform(t, "bag", is_static);
        ++transforms;
      }
    }
    // Pass 2: the scans.
    // sets[0]: the reference, sets[k]: the k-th --target-topic.
    std::vector<std::string> topics{ref_topic};
    topics.insert(topics.end(), target_topics.begin(), target_topics.end());
    std::vector<cal::ScanSet> sets(topics.size());
    std::vector<std::string> frames(topics.size());
    std::size_t skipped = 0, unreadable = 0;
    rosbag::View view(bag, rosbag::TopicQuery(topics));
    // At most max_scans per sensor, evenly spread over the bag: every stride-th message.
    std::vector<std::size_t> stride(topics.size(), 1), seen(topics.size(), 0), limit(topics.size(), max_scans);
    for (std::size_t k = 0; k < topics.size(); ++k) {
      if (k > 0 && target_max_scans[k - 1] > 0) limit[k] = target_max_scans[k - 1];
      const std::size_t count = rosbag::View(bag, rosbag::TopicQuery(topics[k])).size();
      if (limit[k] > 0 && count > limit[k]) stride[k] = (count + limit[k] - 1) / limit[k];
    }
    cal::PointVector points;
    for (const rosbag::MessageInstance& m : view) {
      const std::size_t side =
          std::find(topics.begin(), topics.end(), m.getTopic()) - topics.begin();
      if (side >= topics.size()) continue;
      cal::ScanSet& set = sets[side];
      if (seen[side]++ % stride[side] != 0 || set.numScans() >= limit[side]) continue;
      std::string error, frame;
      ros::Time stamp;
      bool ok = false;
      if (auto cloud = m.instantiate<sensor_msgs::PointCloud2>()) {
        ok = ladar_perception::calibrationPoints(*cloud, min_range, max_range, &points, &error);
        frame = cloud->header.frame_id;
        stamp = cloud->header.stamp;
      } else if (auto scan = m.instantiate<sensor_msgs::LaserScan>()) {
        ok = ladar_perception::calibrationPoints(*scan, &points, &error);
        frame = scan->header.frame_id;
        stamp = scan->header.stamp;
      } else {
        error = "neither PointCloud2 nor LaserScan (" + m.getDataType() + ")";
      }
      if (!ok) {
        if (unreadable++ == 0) std::cerr << m.getTopic() << ": " << error << "\n";
        continue;
      }
      if (frames[side].empty()) frames[side] = frame;
      std::string why;
      if (!tf.canTransform(odom_frame, base_frame, stamp, &why)) {
        ++skipped;
        continue;
      }
      const Eigen::Isometry3d vehicle =
          tf2::transformToEigen(tf.lookupTransform(odom_frame, base_frame, stamp));
      const double thin = side > 0 && target_thin[side - 1] >= 0 ? target_thin[side - 1] : voxel;
      if (thin > 0) points = cal::voxelDownsample(points, thin);
      set.addScan(stamp.toSec(), vehicle, points);
    }
    std::printf("%s: %zu transforms; %zu reference scans (%s)", bag_path.c_str(), transforms,
                sets[0].numScans(), frames[0].c_str());
    for (std::size_t k = 1; k < sets.size(); ++k) {
      std::printf(", %zu target scans (%s)", sets[k].numScans(), frames[k].c_str());
    }
    std::printf("; %zu without a vehicle pose, %zu unreadable\n", skipped, unreadable);
    for (const cal::ScanSet& set : sets) {
      if (set.empty()) {
        std::cerr << "no data to calibrate with: check the topics and that " << odom_frame
                  << " -> " << base_frame << " is in the bag's tf\n";
        return 1;
      }
    }
    Eigen::Isometry3d reference_extrinsic;
    try {
      reference_extrinsic =
          tf2::transformToEigen(tf.lookupTransform(base_frame, frames[0], ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      std::cerr << "the reference's extrinsic " << base_frame << " -> " << frames[0]
                << " is not in the bag's tf: " << e.what() << "\n";
      return 1;
    }
    if (sets.size() > 2) {
      return calibrateNetwork(sets, frames, target_voxels, target_initials, reference_extrinsic, tf, base_frame, params,
                              initial_given, !reference_only, output, quiet);
    }
    cal::CalibrationInput input;
    input.reference = std::move(sets[0]);
    input.target = std::move(sets[1]);
    input.reference_extrinsic = reference_extrinsic;
    if (!initial_given) {
      try {  // an existing (uncertain) calibration in the bag is a natural initial guess
        params.initial = cal::fromIsometry(
            tf2::transformToEigen(tf.lookupTransform(base_frame, frames[1], ros::Time(0))));
        std::printf("initial guess from the bag's tf %s -> %s\n", base_frame.c_str(), frames[1].c_str());
      } catch (const tf2::TransformException&) {
        std::printf("initial guess: zero (give --initial)\n");
      }
    }
    int line = 0;
    const cal::CalibrationResult r = cal::calibrate(input, params, [&](const cal::SearchProgress& p) {
      if (!quiet) {
        std::printf("%4d %-16s iteration %3d evaluations %6ld cost %.6g  x %.4f y %.4f z %.4f "
                    "roll %.5f pitch %.5f yaw %.5f\n",
                    ++line, p.stage.c_str(), p.iteration, p.evaluations, p.best_cost, p.estimate[0],
                    p.estimate[1], p.estimate[2], p.estimate[3], p.estimate[4], p.estimate[5]);
        std::fflush(stdout);
      }
      return true;
    });
    std::printf("\n%s in %.2f s: %s\n", r.success ? "calibrated" : "NOT calibrated", r.elapsed,
                r.message.c_str());
    std::printf("%s -> %s: x %.4f y %.4f z %.4f m, roll %.5f pitch %.5f yaw %.5f rad\n",
                base_frame.c_str(), frames[1].c_str(), r.extrinsic[0], r.extrinsic[1],
                r.extrinsic[2], r.extrinsic[3], r.extrinsic[4], r.extrinsic[5]);
    std::printf("stddev: %.4f %.4f %.4f m, %.5f %.5f %.5f rad; final cost %.6g; unobservable:",
                r.stddev[0], r.stddev[1], r.stddev[2], r.stddev[3], r.stddev[4], r.stddev[5],
                r.final_cost);
    for (const std::string& u : r.unobservable) std::printf(" %s", u.c_str());
    std::printf("%s\n", r.unobservable.empty() ? " none" : "");
    if (windows > 1) {
      const cal::Pose6 rep = cal::repeatability(input, params, r.extrinsic, windows);
      std::printf("repeatability over %d time windows (std): %.4f %.4f %.4f m, %.5f %.5f %.5f rad\n",
                  windows, rep[0], rep[1], rep[2], rep[3], rep[4], rep[5]);
    }
    if (output.empty()) output = "ladar_calibration_" + frames[1] + ".yaml";
    std::string error;
    if (!cal::writeStaticTransformYaml(output, base_frame, frames[1], r, &error)) {
      std::cerr << error << "\n";
      return 1;
    }
    std::printf("written to %s%s\nlaunch: %s\n", output.c_str(),
                r.success ? "" : " (NOT a success: see its comments)",
                cal::staticTransformLaunchLine(output, base_frame, frames[1]).c_str());
    return r.success ? 0 : 3;
  } catch (const std::exception& e) {
    std::cerr << "ladar_calibrate: " << e.what() << "\n";
    return 1;
  }
}
