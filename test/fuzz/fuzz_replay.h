// Replays a fuzz target's committed inputs (test/fuzz/corpus/<target>/ and
// test/fuzz/regressions/<target>/) through its entry point inside a gtest, so that the plain and
// the sanitizer builds of the unit tests run every input that once crashed a target.
#pragma once

#include <dirent.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ladar_perception {
namespace fuzz {

using Entry = int (*)(const uint8_t*, size_t);

inline std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name != "." && name != "..") out.push_back(dir + "/" + name);
    }
    closedir(d);
  }
  return out;
}

// Runs every file of the target's corpus and regressions; returns how many were replayed.
inline int replay(const std::string& target, Entry entry, bool need_regressions) {
  const std::string root = std::string(LADAR_SOURCE_DIR) + "/test/fuzz/";
  std::vector<std::string> files = filesIn(root + "corpus/" + target);
  const std::vector<std::string> regressions = filesIn(root + "regressions/" + target);
  if (need_regressions) {
    EXPECT_FALSE(regressions.empty()) << target;
  }
  files.insert(files.end(), regressions.begin(), regressions.end());
  for (const std::string& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
    SCOPED_TRACE(f);
    EXPECT_EQ(0, entry(bytes.data(), bytes.size()));
  }
  return static_cast<int>(files.size());
}

}  // namespace fuzz
}  // namespace ladar_perception
