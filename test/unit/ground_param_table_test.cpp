// Each node's parameter table (vertical_scan_params.def, hough_params.def) is the one definition
// of its parameters: --set and the ROS mapping are produced from it, the node's .cfg reads it,
// and this test fails when the default settings, the documented YAML or the README drift from
// it.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "ladar_perception/ground/hough_ground.h"
#include "ladar_perception/ground/vertical_scan.h"

namespace ladar_perception {
namespace {

std::string readFile(const std::string& relative) {
  std::ifstream in(std::string(LADAR_SOURCE_DIR) + "/" + relative);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The parameters the README documents: backticked names, `prefix_*` globs and `_suffix`
// shorthands ("`ground_slope_min`, `_max`" documents ground_slope_max).
struct Documented {
  std::set<std::string> names;
  std::vector<std::string> prefixes;
  bool covers(const std::string& name) const {
    if (names.count(name)) return true;
    for (const std::string& p : prefixes) {
      if (name.compare(0, p.size(), p) == 0) return true;
    }
    return false;
  }
};

Documented readmeNames(const std::string& text) {
  Documented d;
  std::istringstream lines(text);
  std::string line;
  const std::regex token("`([A-Za-z_][A-Za-z0-9_]*\\*?)`");
  while (std::getline(lines, line)) {
    std::string last;
    for (std::sregex_iterator it(line.begin(), line.end(), token), end; it != end; ++it) {
      const std::string t = (*it)[1];
      if (t.back() == '*') {
        d.prefixes.push_back(t.substr(0, t.size() - 1));
      } else if (t[0] == '_' && !last.empty() && last.rfind('_') != std::string::npos) {
        d.names.insert(last.substr(0, last.rfind('_')) + t);
      } else {
        d.names.insert(t);
        last = t;
      }
    }
  }
  return d;
}

// One node's table with its accessors, its default and thesis settings, and its files.
struct NodeTable {
  const char* node;
  const std::vector<ParamInfo>& (*table)();
  std::function<bool(const std::string&, double*)> get_default;
  std::function<bool(const std::string&, double*)> get_thesis;
  // Sets `key` on a copy of the default settings and reads `read_key` back.
  std::function<bool(const std::string&, double, const std::string&, double*, std::string*)> set_and_get;
  const char* yaml;
  const char* cfg;
  const char* def;
};

std::vector<NodeTable> nodeTables() {
  static const VerticalScanParams vs_default = verticalScanDefaultParams();
  static const VerticalScanParams vs_thesis = verticalScanThesisParams();
  static const HoughGroundParams h_default = houghGroundDefaultParams();
  static const HoughGroundParams h_thesis = houghGroundThesisParams();
  return {
      {"VerticalScanGround", &verticalScanParamTable,
       [](const std::string& k, double* v) { return getVerticalScanParam(vs_default, k, v); },
       [](const std::string& k, double* v) { return getVerticalScanParam(vs_thesis, k, v); },
       [](const std::string& k, double v, const std::string& r, double* out, std::string* error) {
         VerticalScanParams p = vs_default;
         return setVerticalScanParam(&p, k, v, error) && getVerticalScanParam(p, r, out);
       },
       "config/vertical_scan_ground.yaml", "cfg/VerticalScanGround.cfg", "vertical_scan_params.def"},
      {"HoughGround", &houghGroundParamTable,
       [](const std::string& k, double* v) { return getHoughGroundParam(h_default, k, v); },
       [](const std::string& k, double* v) { return getHoughGroundParam(h_thesis, k, v); },
       [](const std::string& k, double v, const std::string& r, double* out, std::string* error) {
         HoughGroundParams p = h_default;
         return setHoughGroundParam(&p, k, v, error) && getHoughGroundParam(p, r, out);
       },
       "config/hough_ground.yaml", "cfg/HoughGround.cfg", "hough_params.def"},
  };
}

TEST(ParamTable, TheDefaultMethodHasTheTableDefaultsWithinTheirRanges) {
  for (const NodeTable& node : nodeTables()) {
    ASSERT_GE(node.table().size(), 20u) << node.node;
    std::set<std::string> names;
    for (const ParamInfo& row : node.table()) {
      const std::string what = std::string(node.node) + " " + row.name;
      EXPECT_TRUE(names.insert(row.name).second) << what << " twice";
      double value = 0.0;
      ASSERT_TRUE(node.get_default(row.name, &value)) << what;
      EXPECT_EQ(static_cast<float>(value), static_cast<float>(row.default_value)) << what;
      EXPECT_LE(row.min, row.default_value) << what;
      EXPECT_GE(row.max, row.default_value) << what;
      ASSERT_TRUE(node.get_thesis(row.name, &value)) << what;
      EXPECT_LE(row.min, value) << what << " of the thesis method is outside the range";
      EXPECT_GE(row.max, value) << what << " of the thesis method is outside the range";
    }
  }
}

TEST(ParamTable, SetTakesTheNameOrTheFieldPathWithinTheRangeOnly) {
  for (const NodeTable& node : nodeTables()) {
    for (const ParamInfo& row : node.table()) {
      const std::string what = std::string(node.node) + " " + row.name;
      std::string error;
      for (const double v : {row.min, row.max}) {
        double got = 0.0;
        ASSERT_TRUE(node.set_and_get(row.name, v, row.member, &got, &error)) << what << ": " << error;
        EXPECT_EQ(static_cast<float>(got), static_cast<float>(v)) << what;
      }
      double got = 0.0;
      EXPECT_TRUE(node.set_and_get(row.member, row.default_value, row.name, &got, &error)) << what;
      EXPECT_FALSE(node.set_and_get(row.name, row.max + 1.0, row.name, &got, &error)) << what;
      EXPECT_NE(error.find(row.name), std::string::npos) << error;
      EXPECT_FALSE(node.set_and_get(row.name, std::nan(""), row.name, &got, &error)) << what;
    }
    std::string error;
    double got = 0.0;
    EXPECT_FALSE(node.set_and_get("no_such_parameter", 1.0, "no_such_parameter", &got, &error));
    EXPECT_NE(error.find("no_such_parameter"), std::string::npos);
  }
}

// Every row is in the node's documented YAML, commented out at its default.
TEST(ParamTable, TheDocumentedYamlListsEveryParameterAtItsDefault) {
  for (const NodeTable& node : nodeTables()) {
    const std::string yaml = readFile(node.yaml);
    ASSERT_FALSE(yaml.empty()) << node.yaml;
    for (const ParamInfo& row : node.table()) {
      const std::regex entry("(^|\\n)#? ?" + std::string(row.name) + ": *([^ #\\n]+)");
      std::smatch m;
      ASSERT_TRUE(std::regex_search(yaml, m, entry)) << row.name << " is not in " << node.yaml;
      const std::string v = m[2];
      double value = 0.0;
      if (v == "true" || v == "false") {
        value = v == "true" ? 1.0 : 0.0;
      } else if (std::string(row.name) == "curb_policy") {
        value = v == "ground" ? kCurbGround : kCurbObstacle;
      } else {
        value = std::stod(v);
      }
      EXPECT_EQ(static_cast<float>(value), static_cast<float>(row.default_value))
          << row.name << " is " << v << " in " << node.yaml;
    }
  }
}

// A .cfg produces its entries from the table: no threshold is written there a second time.
TEST(ParamTable, TheCfgReadsTheTable) {
  for (const NodeTable& node : nodeTables()) {
    const std::string cfg = readFile(node.cfg);
    ASSERT_NE(cfg.find(node.def), std::string::npos) << node.cfg;
    for (const ParamInfo& row : node.table()) {
      EXPECT_EQ(cfg.find("gen.add(\"" + std::string(row.name) + "\""), std::string::npos)
          << row.name << " is written in " << node.cfg << " as well as in the table";
    }
  }
}

TEST(ParamTable, TheReadmeDocumentsEveryParameter) {
  const Documented documented = readmeNames(readFile("README.md"));
  for (const NodeTable& node : nodeTables()) {
    for (const ParamInfo& row : node.table()) {
      EXPECT_TRUE(documented.covers(row.name)) << node.node << " " << row.name << " is not in the README";
    }
  }
}

}  // namespace
}  // namespace ladar_perception

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
