// patchworkpp_masks: run upstream Patchwork++ (url-kaist/patchwork-plusplus, cpp/) on KITTI .bin scans
// and write one byte per input point (1 = ground, 0 = not ground) to MASK_DIR/NNNNNN.mask.
//
//   patchworkpp_masks --velodyne DIR --out MASK_DIR [--frames a:b] [--repeat N] [--callgrind-once]
//
// --frames a:b   inclusive range of frame numbers (file stem as integer), e.g. 0:2 -> 0,1,2.
// --repeat N     time each scan N times; print the median ms per scan. Every repetition starts
//                from the same saved Patchwork++ state (a copy of the object taken before the
//                scan), so repeats do not perturb the adaptive thresholds and the mask written is
//                the one of the plain sequential pass (repetition 1).
// --callgrind-once  CALLGRIND_START/STOP_INSTRUMENTATION around exactly one estimateGround call:
//                the first repetition on the first scan. Run under
//                valgrind --tool=callgrind --instr-atstart=no.
//
// Patchwork++ is stateful (A-GLE thresholds, sensor height, TGR flatness history), so scans are
// processed in order by one instance created with default patchwork::Params.
#include "patchwork/patchworkpp.h"

#include <valgrind/callgrind.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>
#include <dirent.h>
#include <sys/stat.h>

namespace {

std::string dirname_of(const std::string &p) {
  size_t s = p.find_last_of('/');
  return s == std::string::npos ? std::string(".") : p.substr(0, s);
}

bool read_file_bytes(const std::string &path, std::vector<char> &buf) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  f.seekg(0, std::ios::end);
  std::streamoff n = f.tellg();
  f.seekg(0, std::ios::beg);
  buf.resize(static_cast<size_t>(n));
  if (n > 0) f.read(buf.data(), n);
  return static_cast<bool>(f);
}

// Reads a KITTI velodyne scan. Small files whose size is not a multiple of 16 bytes are treated
// as text stubs that hold a link target relative to the stub's folder (followed up to 8 times).
bool load_kitti_bin(std::string path, Eigen::MatrixXf &cloud, std::string &resolved) {
  std::vector<char> buf;
  for (int hop = 0; hop < 8; ++hop) {
    if (!read_file_bytes(path, buf)) {
      std::fprintf(stderr, "error: cannot read %s\n", path.c_str());
      return false;
    }
    if (buf.size() % 16 != 0 && buf.size() < 4096) {
      std::string target(buf.begin(), buf.end());
      while (!target.empty() && (target.back() == '\n' || target.back() == '\r' ||
                                 target.back() == ' ' || target.back() == '\0'))
        target.pop_back();
      path = (!target.empty() && target[0] == '/') ? target : dirname_of(path) + "/" + target;
      continue;
    }
    resolved = path;
    const size_t n = buf.size() / 16;
    const float *f = reinterpret_cast<const float *>(buf.data());
    cloud.resize(static_cast<Eigen::Index>(n), 4);
    for (size_t i = 0; i < n; ++i)
      cloud.row(static_cast<Eigen::Index>(i)) << f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3];
    return true;
  }
  std::fprintf(stderr, "error: too many link hops for %s\n", path.c_str());
  return false;
}

bool is_frame_name(const std::string &name, long &frame) {
  if (name.size() < 5 || name.compare(name.size() - 4, 4, ".bin") != 0) return false;
  std::string stem = name.substr(0, name.size() - 4);
  if (stem.empty() || stem.find_first_not_of("0123456789") != std::string::npos) return false;
  frame = std::strtol(stem.c_str(), nullptr, 10);
  return true;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void usage() {
  std::fprintf(stderr,
               "usage: patchworkpp_masks --velodyne DIR --out MASK_DIR [--frames a:b] [--repeat N] "
               "[--callgrind-once]\n");
}

}  // namespace

int main(int argc, char **argv) {
  std::string vel_dir, out_dir;
  long f_lo = -1, f_hi = -1;
  int repeat = 1;
  bool cg_once = false;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto need = [&](const char *opt) -> std::string {
      if (i + 1 >= argc) { std::fprintf(stderr, "missing value for %s\n", opt); usage(); std::exit(2); }
      return argv[++i];
    };
    if (a == "--velodyne") vel_dir = need("--velodyne");
    else if (a == "--out") out_dir = need("--out");
    else if (a == "--frames") {
      std::string v = need("--frames");
      size_t c = v.find(':');
      if (c == std::string::npos) { f_lo = f_hi = std::strtol(v.c_str(), nullptr, 10); }
      else {
        f_lo = c == 0 ? -1 : std::strtol(v.substr(0, c).c_str(), nullptr, 10);
        f_hi = c + 1 >= v.size() ? -1 : std::strtol(v.substr(c + 1).c_str(), nullptr, 10);
      }
    } else if (a == "--repeat") repeat = std::max(1, std::atoi(need("--repeat").c_str()));
    else if (a == "--callgrind-once") cg_once = true;
    else if (a == "-h" || a == "--help") { usage(); return 0; }
    else { std::fprintf(stderr, "unknown argument %s\n", a.c_str()); usage(); return 2; }
  }
  if (vel_dir.empty() || out_dir.empty()) { usage(); return 2; }

  std::vector<std::pair<long, std::string>> frames;
  DIR *d = opendir(vel_dir.c_str());
  if (!d) { std::fprintf(stderr, "error: cannot open %s\n", vel_dir.c_str()); return 1; }
  while (dirent *e = readdir(d)) {
    long fr;
    std::string name = e->d_name;
    if (!is_frame_name(name, fr)) continue;
    if (f_lo >= 0 && fr < f_lo) continue;
    if (f_hi >= 0 && fr > f_hi) continue;
    frames.emplace_back(fr, name);
  }
  closedir(d);
  std::sort(frames.begin(), frames.end());
  if (frames.empty()) { std::fprintf(stderr, "error: no frames selected\n"); return 1; }
  mkdir(out_dir.c_str(), 0755);

  patchwork::Params params;  // upstream defaults, untouched
  patchwork::PatchWorkpp pw(params);

  std::vector<double> all_medians;
  long total_pts = 0, total_gnd = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    const std::string in_path = vel_dir + "/" + frames[k].second;
    Eigen::MatrixXf cloud;
    std::string resolved;
    if (!load_kitti_bin(in_path, cloud, resolved)) return 1;
    const long n = cloud.rows();

    std::vector<double> ms;
    patchwork::PatchWorkpp snapshot = pw;  // state before this scan
    for (int r = 0; r < repeat; ++r) {
      if (r > 0) pw = snapshot;  // every repetition starts from the same state
      const bool cg = cg_once && k == 0 && r == 0;
      auto t0 = std::chrono::steady_clock::now();
      if (cg) CALLGRIND_START_INSTRUMENTATION;
      pw.estimateGround(cloud);
      if (cg) CALLGRIND_STOP_INSTRUMENTATION;
      auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    const double med = median(ms);
    all_medians.push_back(med);

    Eigen::VectorXi gidx = pw.getGroundIndices();
    Eigen::VectorXi nidx = pw.getNongroundIndices();
    std::vector<unsigned char> mask(static_cast<size_t>(n), 0);
    long dup = 0, bad = 0;
    for (Eigen::Index i = 0; i < gidx.size(); ++i) {
      const int id = gidx(i);
      if (id < 0 || id >= n) { ++bad; continue; }
      if (mask[id]) ++dup;
      mask[id] = 1;
    }
    long gnd = 0;
    for (unsigned char m : mask) gnd += m;

    const std::string stem = frames[k].second.substr(0, frames[k].second.size() - 4);
    const std::string out_path = out_dir + "/" + stem + ".mask";
    FILE *fo = std::fopen(out_path.c_str(), "wb");
    if (!fo) { std::fprintf(stderr, "error: cannot write %s\n", out_path.c_str()); return 1; }
    if (n > 0) std::fwrite(mask.data(), 1, mask.size(), fo);
    std::fclose(fo);

    total_pts += n;
    total_gnd += gnd;
    std::printf("frame %s points %ld ground %ld nonground_out %ld (ground+nonground=%ld, dup %ld, "
                "bad %ld) ground_frac %.4f median_ms %.3f (n=%d) src %s\n",
                stem.c_str(), n, gnd, static_cast<long>(nidx.size()),
                static_cast<long>(gidx.size() + nidx.size()), dup, bad,
                n ? double(gnd) / n : 0.0, med, repeat, resolved.c_str());
  }
  std::printf("total points %ld ground %ld ground_frac %.4f median_of_per_scan_median_ms %.3f "
              "frames %zu repeat %d\n",
              total_pts, total_gnd, total_pts ? double(total_gnd) / total_pts : 0.0,
              median(all_medians), frames.size(), repeat);
  return 0;
}
