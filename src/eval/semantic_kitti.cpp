#include "ladar_perception/eval/semantic_kitti.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <dirent.h>
#include <fstream>
#include <sys/stat.h>

namespace ladar_perception {
namespace eval {

namespace semantic_kitti {

std::string className(uint16_t c) {
  switch (c) {
    case 0: return "unlabeled";
    case 1: return "outlier";
    case 10: return "car";
    case 11: return "bicycle";
    case 13: return "bus";
    case 15: return "motorcycle";
    case 16: return "on-rails";
    case 18: return "truck";
    case 20: return "other-vehicle";
    case 30: return "person";
    case 31: return "bicyclist";
    case 32: return "motorcyclist";
    case 40: return "road";
    case 44: return "parking";
    case 48: return "sidewalk";
    case 49: return "other-ground";
    case 50: return "building";
    case 51: return "fence";
    case 52: return "other-structure";
    case 60: return "lane-marking";
    case 70: return "vegetation";
    case 71: return "trunk";
    case 72: return "terrain";
    case 80: return "pole";
    case 81: return "traffic-sign";
    case 99: return "other-object";
    case 252: return "moving-car";
    case 253: return "moving-bicyclist";
    case 254: return "moving-person";
    case 255: return "moving-motorcyclist";
    case 256: return "moving-on-rails";
    case 257: return "moving-bus";
    case 258: return "moving-truck";
    case 259: return "moving-other-vehicle";
    default: return "class-" + std::to_string(c);
  }
}

bool isGroundClass(uint16_t c) {
  return c == kRoad || c == kParking || c == kSidewalk || c == kOtherGround ||
         c == kLaneMarking || c == kTerrain;
}

}  // namespace semantic_kitti

const char* protocolName(GroundProtocol p) { return p == GroundProtocol::kA ? "A" : "B"; }

TruthRole truthRole(uint16_t c, float z_sensor, float sensor_height, GroundProtocol p) {
  using namespace semantic_kitti;
  if (isGroundClass(c)) return TruthRole::kGround;
  if (c == kUnlabeled || c == kOutlier) {
    return p == GroundProtocol::kA ? TruthRole::kNotScored : TruthRole::kNotScoredUnlessGround;
  }
  if (c == kVegetation) {
    if (p == GroundProtocol::kA) return TruthRole::kNotScored;
    return z_sensor < -0.75f * sensor_height ? TruthRole::kGround : TruthRole::kNonGround;
  }
  return TruthRole::kNonGround;
}

constexpr std::array<float, RangeBands::kCount - 1> RangeBands::kEdges;

std::string RangeBands::name(int b) {
  auto metres = [](float v) { return std::to_string(static_cast<int>(v)); };
  if (b <= 0) return "0-" + metres(kEdges[0]) + " m";
  if (b >= kCount - 1) return metres(kEdges[kCount - 2]) + " m and beyond";
  return metres(kEdges[b - 1]) + "-" + metres(kEdges[b]) + " m";
}

void RealGroundScore::add(const RealGroundScore& o) {
  scans += o.scans;
  true_ground += o.true_ground;
  false_ground += o.false_ground;
  missed_ground += o.missed_ground;
  true_obstacle += o.true_obstacle;
  dropped_ground += o.dropped_ground;
  for (const auto& [c, n] : o.classes) {
    ClassCount& mine = classes[c];
    mine.points += n.points;
    mine.called_ground += n.called_ground;
  }
  for (int b = 0; b < RangeBands::kCount; ++b) {
    bands[b].ground += o.bands[b].ground;
    bands[b].ground_called_ground += o.bands[b].ground_called_ground;
    bands[b].non_ground += o.bands[b].non_ground;
    bands[b].non_ground_called_ground += o.bands[b].non_ground_called_ground;
  }
}

void scoreGroundScan(const PointCloudView& view, const uint16_t* classes,
                     const uint8_t* called_ground, float sensor_height, GroundProtocol protocol,
                     RealGroundScore* score) {
  // Per-class counts in a flat table first (classes are < 2^16), then into the map.
  std::vector<RealGroundScore::ClassCount> by_class(260);
  auto classCount = [&](uint16_t c) -> RealGroundScore::ClassCount& {
    if (c >= by_class.size()) by_class.resize(c + 1u);
    return by_class[c];
  };
  const std::size_t n = view.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p = view.xyz(i);
    const TruthRole role = truthRole(classes[i], p.z(), sensor_height, protocol);
    const bool ground = called_ground[i] != 0;
    if (role == TruthRole::kNotScored) continue;
    if (role == TruthRole::kNotScoredUnlessGround) {
      score->dropped_ground += ground;
      continue;
    }
    RealGroundScore::ClassCount& cc = classCount(classes[i]);
    ++cc.points;
    cc.called_ground += ground;
    const float range = std::hypot(p.x(), p.y());
    RealGroundScore::BandCount& band = score->bands[RangeBands::band(std::isfinite(range) ? range : 0.f)];
    if (role == TruthRole::kGround) {
      ++band.ground;
      band.ground_called_ground += ground;
      (ground ? score->true_ground : score->missed_ground) += 1;
    } else {
      ++band.non_ground;
      band.non_ground_called_ground += ground;
      (ground ? score->false_ground : score->true_obstacle) += 1;
    }
  }
  for (std::size_t c = 0; c < by_class.size(); ++c) {
    if (!by_class[c].points) continue;
    RealGroundScore::ClassCount& mine = score->classes[static_cast<uint16_t>(c)];
    mine.points += by_class[c].points;
    mine.called_ground += by_class[c].called_ground;
  }
  ++score->scans;
}

namespace {

bool isDirectory(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool isFile(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// "000123" -> 123; -1 for a name that is not all digits.
long frameNumber(const std::string& stem) {
  if (stem.empty() || !std::all_of(stem.begin(), stem.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
    return -1;
  return std::strtol(stem.c_str(), nullptr, 10);
}

}  // namespace

namespace {

// A symbolic link checked out or unpacked without link support becomes a small text file that
// holds the link's target (git with core.symlinks=false, some archive tools). SemanticKITTI
// folders are often built by linking velodyne/ scans to a KITTI odometry copy, so such a stub
// is followed: a file shorter than a single return whose whole content names an existing file,
// relative to the stub's folder or absolute.
std::string resolveLinkStub(const std::string& folder, const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return path;
  const std::streamsize bytes = in.tellg();
  if (bytes <= 0 || bytes >= 1024 || bytes % 16 == 0) return path;
  std::string target(static_cast<std::size_t>(bytes), '\0');
  in.seekg(0);
  if (!in.read(&target[0], bytes)) return path;
  while (!target.empty() && (target.back() == '\n' || target.back() == '\r')) target.pop_back();
  for (const char c : target)
    if (c < 0x20 || c > 0x7e) return path;
  if (target.empty()) return path;
  const std::string resolved = target[0] == '/' ? target : folder + "/" + target;
  return isFile(resolved) ? resolved : path;
}

}  // namespace

bool listLabelledFrames(const std::string& dir, long first, long last,
                        std::vector<LabelledFrameFiles>* frames, std::string* error) {
  frames->clear();
  const std::string scans = dir + "/velodyne", labels = dir + "/labels";
  if (!isDirectory(scans)) {
    *error = dir + " has no velodyne/ folder (SemanticKITTI layout: velodyne/NNNNNN.bin, labels/NNNNNN.label)";
    return false;
  }
  DIR* d = ::opendir(scans.c_str());
  if (!d) {
    *error = "cannot list " + scans;
    return false;
  }
  std::vector<std::pair<long, LabelledFrameFiles>> found;
  std::size_t without_label = 0;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() <= 4 || name.compare(name.size() - 4, 4, ".bin") != 0) continue;
    const std::string stem = name.substr(0, name.size() - 4);
    const long number = frameNumber(stem);
    if (number < 0) continue;
    if (first <= last && (number < first || number > last)) continue;
    LabelledFrameFiles f;
    f.name = stem;
    f.scan_path = resolveLinkStub(scans, scans + "/" + name);
    f.label_path = labels + "/" + stem + ".label";
    if (!isFile(f.label_path)) {
      ++without_label;
      continue;
    }
    found.emplace_back(number, f);
  }
  ::closedir(d);
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& f : found) frames->push_back(std::move(f.second));
  if (frames->empty()) {
    *error = dir + ": no scan with a label file" +
             (first <= last ? " in frames " + std::to_string(first) + ":" + std::to_string(last) : std::string()) +
             (without_label ? " (" + std::to_string(without_label) + " scans have no labels/NNNNNN.label)" : "");
    return false;
  }
  return true;
}

bool readSemanticClasses(const std::string& path, std::size_t expected_points,
                         std::vector<uint16_t>* classes, std::string* error) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) {
    *error = "cannot open " + path;
    return false;
  }
  const std::streamsize bytes = in.tellg();
  if (bytes < 0 || static_cast<std::size_t>(bytes) != expected_points * 4) {
    *error = path + ": " + std::to_string(bytes < 0 ? 0 : bytes / 4) + " labels for a scan of " +
             std::to_string(expected_points) + " returns (uint32 per return)";
    return false;
  }
  in.seekg(0);
  std::vector<uint32_t> raw(expected_points);
  if (!in.read(reinterpret_cast<char*>(raw.data()), bytes)) {
    *error = path + ": read failed";
    return false;
  }
  classes->resize(expected_points);
  for (std::size_t i = 0; i < expected_points; ++i) (*classes)[i] = static_cast<uint16_t>(raw[i] & 0xFFFFu);
  return true;
}

bool parseFrameRange(const std::string& text, long* first, long* last) {
  const std::size_t colon = text.find(':');
  auto number = [](const std::string& s, long* out) {
    if (s.empty() || !std::all_of(s.begin(), s.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
      return false;
    *out = std::strtol(s.c_str(), nullptr, 10);
    return true;
  };
  if (colon == std::string::npos) {
    if (!number(text, first)) return false;
    *last = *first;
    return true;
  }
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  *first = 0;
  *last = 999999999L;
  if (!a.empty() && !number(a, first)) return false;
  if (!b.empty() && !number(b, last)) return false;
  return (!a.empty() || !b.empty()) && *first <= *last;
}

}  // namespace eval
}  // namespace ladar_perception
