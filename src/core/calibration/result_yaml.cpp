#include "ladar_perception/calibration/result_yaml.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>

namespace ladar_perception {
namespace calibration {

// Always with a decimal point: XmlRpc must read a double, never an int.
std::string yamlNumber(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9f", v);
  return buf;
}

std::string yamlFigure(double v, int significant_digits) {
  if (!std::isfinite(v)) return "unobservable";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", significant_digits, v);
  return buf;
}

std::string yamlText(const std::string& s) {
  std::string out;
  for (char c : s) out += (c == '\n' || c == '\r' || c == '"') ? ' ' : c;
  return out;
}

std::string transformStampedYaml(const std::string& parent_frame, const std::string& child_frame,
                                 const Pose6& extrinsic, const std::string& indent) {
  const Eigen::Isometry3d t = toIsometry(extrinsic);
  const Eigen::Quaterniond q(t.linear());
  std::ostringstream y;
  y << indent << "header:\n" << indent << "  frame_id: \"" << yamlText(parent_frame) << "\"\n";
  y << indent << "child_frame_id: \"" << yamlText(child_frame) << "\"\n";
  y << indent << "transform:\n";
  y << indent << "  translation: {x: " << yamlNumber(t.translation().x())
    << ", y: " << yamlNumber(t.translation().y()) << ", z: " << yamlNumber(t.translation().z())
    << "}\n";
  y << indent << "  rotation: {x: " << yamlNumber(q.x()) << ", y: " << yamlNumber(q.y())
    << ", z: " << yamlNumber(q.z()) << ", w: " << yamlNumber(q.w()) << "}\n";
  return y.str();
}

std::string staticTransformYaml(const std::string& parent_frame, const std::string& child_frame,
                                const CalibrationResult& r) {
  std::ostringstream y;
  y << "# ladar_perception calibration of " << yamlText(child_frame) << " against the reference, "
    << "method " << yamlText(r.method) << "\n";
  y << "# success: " << (r.success ? "true" : "false") << "; " << yamlText(r.message) << "\n";
  y << "# x y z roll pitch yaw:";
  for (int i = 0; i < 6; ++i) y << " " << yamlNumber(r.extrinsic[i]);
  y << "\n";
  y << "# stddev x y z roll pitch yaw:";
  for (int i = 0; i < 6; ++i) y << " " << yamlFigure(r.stddev[i]);
  y << "\n# final cost: " << yamlFigure(r.final_cost) << "\n";
  y << "# unobservable:";
  for (const std::string& u : r.unobservable) y << " " << u;
  y << (r.unobservable.empty() ? " none" : "") << "\n";
  y << transformStampedYaml(parent_frame, child_frame, r.extrinsic);
  return y.str();
}

bool writeFileAtomically(const std::string& path, const std::string& text, std::string* error) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    if (error) *error = "cannot create " + tmp + ": " + std::strerror(errno);
    return false;
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (error) *error = "cannot write " + tmp + ": " + std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    if (error) *error = "cannot flush " + tmp + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    if (error) *error = "cannot rename to " + path + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  return true;
}

bool backupExistingFile(const std::string& path, std::string* backup, std::string* error) {
  if (backup) backup->clear();
  if (::access(path.c_str(), F_OK) != 0) return true;  // nothing to keep
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  std::strftime(stamp, sizeof(stamp), "%Y%m%dT%H%M%SZ", &utc);
  for (int k = 0; k < 1000; ++k) {
    const std::string name = path + "." + stamp + (k ? "-" + std::to_string(k) : "") + ".bak";
    // A hard link keeps the previous file's bytes under the new name at once, without a copy
    // that a kill could leave half-written; the original stays in place until the rename.
    if (::link(path.c_str(), name.c_str()) == 0) {
      if (backup) *backup = name;
      return true;
    }
    if (errno == EEXIST) continue;
    // No hard links on this file system: copy, atomically too.
    std::FILE* in = std::fopen(path.c_str(), "rb");
    if (!in) break;
    std::string text;
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof(buf), in)) > 0) text.append(buf, n);
    std::fclose(in);
    if (!writeFileAtomically(name, text, error)) return false;
    if (backup) *backup = name;
    return true;
  }
  if (error) *error = "cannot keep a backup of " + path + ": " + std::strerror(errno);
  return false;
}

bool writeStaticTransformYaml(const std::string& path, const std::string& parent_frame,
                              const std::string& child_frame, const CalibrationResult& result,
                              std::string* error) {
  if (!backupExistingFile(path, nullptr, error)) return false;
  return writeFileAtomically(path, staticTransformYaml(parent_frame, child_frame, result), error);
}

std::string staticTransformLaunchLine(const std::string& yaml_path,
                                      const std::string& parent_frame,
                                      const std::string& child_frame) {
  std::string ns = child_frame + "_calibration";
  for (char& c : ns) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  }
  std::ostringstream l;
  l << "<rosparam command=\"load\" file=\"" << yaml_path << "\" ns=\"" << ns << "\"/>"
    << "<node pkg=\"tf2_ros\" type=\"static_transform_publisher\" name=\"" << ns
    << "_publisher\" args=\"/" << ns << "\"/>";
  return l.str();
}

}  // namespace calibration
}  // namespace ladar_perception
