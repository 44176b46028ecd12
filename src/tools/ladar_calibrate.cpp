// ladar_calibrate: the Calibration nodelet's work offline, from a rosbag. Reads the reference and
// target topics (PointCloud2 or LaserScan, detected per message) and /tf + /tf_static, pairs each
// scan with the vehicle pose (odom -> base_link) at its stamp, calls calibration::calibrate,
// prints progress and the result, and writes the YAML static_transform_publisher loads.
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
#include "ladar_perception/calibration/result_yaml.h"
#include "ladar_perception/ros/calibration_ros.h"

namespace cal = ladar_perception::calibration;

namespace {

void usage() {
  std::cerr
      << "usage: ladar_calibrate BAG --reference-topic TOPIC --target-topic TOPIC\n"
         "         [--odom-frame odom] [--base-frame base_link] [--method NAME]\n"
         "         [--initial x,y,z,roll,pitch,yaw] [--spread x,y,z,roll,pitch,yaw]\n"
         "         [--output FILE.yaml] [--max-scans N] [--min-range M] [--max-range M]\n"
         "         [--voxel M] [--surface-voxel M] [--repeatability W] [--quiet]\n"
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

}  // namespace

int main(int argc, char** argv) {
  std::string bag_path, ref_topic, target_topic, odom_frame = "odom", base_frame = "base_link";
  std::string method = cal::defaultMethod(), output;
  cal::CalibrationParams params;
  bool initial_given = false, quiet = false;
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
      else if (a == "--target-topic") target_topic = value();
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
  if (bag_path.empty() || ref_topic.empty() || target_topic.empty()) {
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
    cal::CalibrationInput input;
    std::string frames[2];
    std::size_t skipped = 0, unreadable = 0;
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{ref_topic, target_topic}));
    cal::PointVector points;
    for (const rosbag::MessageInstance& m : view) {
      const int side = m.getTopic() == target_topic ? 1 : 0;
      cal::ScanSet& set = side == 0 ? input.reference : input.target;
      if (set.numScans() >= max_scans) continue;
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
      if (voxel > 0) points = cal::voxelDownsample(points, voxel);
      set.addScan(stamp.toSec(), vehicle, points);
    }
    std::printf("%s: %zu transforms; %zu reference scans (%s), %zu target scans (%s); %zu without "
                "a vehicle pose, %zu unreadable\n",
                bag_path.c_str(), transforms, input.reference.numScans(), frames[0].c_str(),
                input.target.numScans(), frames[1].c_str(), skipped, unreadable);
    if (input.reference.empty() || input.target.empty()) {
      std::cerr << "no data to calibrate with: check the topics and that " << odom_frame << " -> "
                << base_frame << " is in the bag's tf\n";
      return 1;
    }
    try {
      input.reference_extrinsic =
          tf2::transformToEigen(tf.lookupTransform(base_frame, frames[0], ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      std::cerr << "the reference's extrinsic " << base_frame << " -> " << frames[0]
                << " is not in the bag's tf: " << e.what() << "\n";
      return 1;
    }
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
