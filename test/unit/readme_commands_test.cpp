// The commands README.md shows work as written: every `roslaunch ladar_perception FILE.launch
// arg:=value` names a launch file of the package and arguments it declares, every tool of the
// tools table is built, and every option the table gives a tool is in that tool's --help.
// (scripts/test and scripts/demo themselves are what CI runs.)
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string readme() { return readFile(std::string(LADAR_SOURCE_DIR) + "/README.md"); }

// The folder of this test's executable: the tools are built beside it.
std::string toolDir() {
  std::array<char, 4096> buf{};
  const ssize_t n = readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  std::string exe(buf.data(), n > 0 ? static_cast<std::size_t>(n) : 0);
  return exe.substr(0, exe.rfind('/'));
}

bool isExecutable(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(path.c_str(), X_OK) == 0;
}

std::string run(const std::string& command) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((command + " 2>&1").c_str(), "r"), pclose);
  if (!pipe) return out;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe.get())) out += buf.data();
  return out;
}

TEST(ReadmeCommands, EveryRoslaunchNamesALaunchFileAndArgumentsItDeclares) {
  // Shell line continuations joined, so a command's arguments are on one line.
  const std::string text = std::regex_replace(readme(), std::regex("\\\\\\n\\s*"), " ");
  const std::regex command("roslaunch ladar_perception ([A-Za-z_]+\\.launch)([^`\\n]*)");
  const std::regex argument("([A-Za-z_]+):=");
  int commands = 0;
  for (std::sregex_iterator it(text.begin(), text.end(), command), end; it != end; ++it) {
    const std::string file = (*it)[1];
    if (file == "FILE.launch") continue;  // the placeholder of the prose
    ++commands;
    const std::string launch = readFile(std::string(LADAR_SOURCE_DIR) + "/launch/" + file);
    ASSERT_FALSE(launch.empty()) << "README runs launch/" << file << ", which does not exist";
    const std::string args = (*it)[2];
    for (std::sregex_iterator a(args.begin(), args.end(), argument); a != end; ++a) {
      EXPECT_NE(launch.find("<arg name=\"" + (*a)[1].str() + "\""), std::string::npos)
          << file << " declares no argument " << (*a)[1];
    }
  }
  EXPECT_GE(commands, 3);
}

TEST(ReadmeCommands, EveryToolOfTheTableIsBuiltAndKnowsItsOptions) {
  const std::string text = readme();
  const std::string dir = toolDir();
  // Rows of the tools table: | `tool ...` | what it does |
  const std::regex row("\\n\\| `([a-z_]+)[^|]*\\|([^\\n]*)");
  const std::regex option("`(--[a-z][a-z-]*)");
  std::set<std::string> tools;
  for (std::sregex_iterator it(text.begin(), text.end(), row), end; it != end; ++it) {
    const std::string tool = (*it)[1];
    const std::string path = dir + "/" + tool;
    if (!isExecutable(path)) continue;  // a parameter table's row, not a tool
    tools.insert(tool);
    if (tool == "vertical_scan_ground") continue;  // a ROS node: no --help without a master
    const std::string help = run(path + " --help");
    const std::string line = (*it)[0];
    for (std::sregex_iterator o(line.begin(), line.end(), option); o != end; ++o) {
      EXPECT_NE(help.find((*o)[1].str()), std::string::npos)
          << tool << " --help does not mention " << (*o)[1] << ", which the README gives it";
    }
  }
  for (const char* tool : {"ground_segment", "ground_eval", "ladar_simulate", "calibration_benchmark",
                           "ladar_calibrate", "sensor_transforms", "vertical_scan_ground"}) {
    EXPECT_TRUE(tools.count(tool)) << tool << " is not built in " << dir << " or not in the README";
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
