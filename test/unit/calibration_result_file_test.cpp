// The calibration result file survives a kill: writeFileAtomically writes a temporary file and
// renames it, so a process killed (SIGKILL) in the middle of writing leaves the previous file
// intact; writeStaticTransformYaml keeps the previous result as a timestamped backup.
#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "ladar_perception/calibration/result_yaml.h"

namespace cal = ladar_perception::calibration;

namespace {

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string tempDir() {
  char tmpl[] = "/tmp/ladar_result_file_XXXXXX";
  const char* d = mkdtemp(tmpl);
  return d ? d : "/tmp";
}

std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n != "." && n != "..") out.push_back(n);
    }
    closedir(d);
  }
  return out;
}

cal::CalibrationResult someResult(double x) {
  cal::CalibrationResult r;
  r.success = true;
  r.extrinsic(0) = x;
  return r;
}

}  // namespace

TEST(CalibrationResultFile, KilledInTheMiddleOfTheWriteLeavesThePreviousFile) {
  const std::string dir = tempDir();
  const std::string path = dir + "/result.yaml";
  std::string error;
  ASSERT_TRUE(cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(1.0),
                                            &error)) << error;
  const std::string previous = readAll(path);
  ASSERT_FALSE(previous.empty());

  // Deterministic: the child may write at most 4 KiB to any file; writing 1 MiB makes the
  // kernel kill it with SIGXFSZ inside the write() call, with the temporary file half full.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    struct rlimit no_core = {0, 0}, small = {4096, 4096};
    setrlimit(RLIMIT_CORE, &no_core);
    setrlimit(RLIMIT_FSIZE, &small);
    cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(2.0), nullptr);
    cal::writeFileAtomically(path, std::string(1u << 20, '#'), nullptr);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGXFSZ);
  // The small write before it went through whole (atomically); the killed one left nothing.
  const std::string after = readAll(path);
  EXPECT_NE(after, previous);
  EXPECT_EQ(after, cal::staticTransformYaml("base_link", "sick_front", someResult(2.0)));
  const std::string tmp = path + ".tmp." + std::to_string(child);
  struct stat st;
  EXPECT_EQ(::stat(tmp.c_str(), &st), 0);  // the half-written temporary file is all that remains
  EXPECT_GT(st.st_size, 0);
  EXPECT_LE(st.st_size, 4096);
  ::unlink(tmp.c_str());
}

TEST(CalibrationResultFile, SigkillWhileWritingNeverLeavesAPartialFile) {
  const std::string dir = tempDir();
  const std::string path = dir + "/result.yaml";
  std::string error;
  ASSERT_TRUE(cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(1.0),
                                            &error)) << error;
  const std::string previous = readAll(path);
  const std::string big(256u << 20, '#');
  // A child writes a large file and is killed with SIGKILL once its temporary file exists.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    cal::writeFileAtomically(path, big, nullptr);
    _exit(0);
  }
  const std::string tmp = path + ".tmp." + std::to_string(child);
  struct stat st;
  bool reaped = false;
  for (int i = 0; i < 60000; ++i) {  // up to 60 s, polling the condition
    if (::stat(tmp.c_str(), &st) == 0) break;
    if (::waitpid(child, nullptr, WNOHANG) == child) { reaped = true; break; }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!reaped) {
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
  }
  // Either the previous file or the complete new one, never a mixture or a truncation.
  const std::string after = readAll(path);
  EXPECT_TRUE(after == previous || after.size() == big.size()) << after.size() << " bytes";
  ::unlink(tmp.c_str());
}

TEST(CalibrationResultFile, PreviousResultKeptAsTimestampedBackup) {
  const std::string dir = tempDir();
  const std::string path = dir + "/result.yaml";
  std::string error;
  ASSERT_TRUE(cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(1.0),
                                            &error)) << error;
  EXPECT_EQ(filesIn(dir).size(), 1u);  // the first result has no predecessor
  const std::string first = readAll(path);
  ASSERT_TRUE(cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(2.0),
                                            &error)) << error;
  ASSERT_TRUE(cal::writeStaticTransformYaml(path, "base_link", "sick_front", someResult(3.0),
                                            &error)) << error;
  const std::string third = readAll(path);
  EXPECT_NE(first, third);
  std::vector<std::string> backups;
  for (const std::string& f : filesIn(dir)) {
    if (f != "result.yaml") backups.push_back(f);
  }
  ASSERT_EQ(backups.size(), 2u);  // both predecessors, even within one second
  bool found_first = false;
  for (const std::string& b : backups) {
    // result.yaml.YYYYMMDDTHHMMSSZ[-N].bak
    EXPECT_EQ(b.rfind("result.yaml.", 0), 0u) << b;
    EXPECT_EQ(b.substr(b.size() - 4), ".bak") << b;
    EXPECT_NE(b.find('T'), std::string::npos) << b;
    found_first |= readAll(dir + "/" + b) == first;
  }
  EXPECT_TRUE(found_first);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
